//! `write_restart FILE` and `read_restart FILE`: mcdem's own restart file, JSON (layout in
//! docs/dem.md). LIGGGHTS' binary restart format depends on its build (sizes, byte order, the
//! styles compiled in) and cannot be read portably, so mcdem writes and reads its own: the box and
//! boundary styles, the number of atom types, and the engine's state (particles in memory order,
//! pair and wall contact histories, step, time step; see [`crate::engine::EngineState`]). As with
//! LIGGGHTS, the continuing deck defines materials, pair style, walls and fixes again, the walls in
//! the same order (wall contact histories name walls by their order). The groups (names, and the
//! particles' mask bits) are kept, and so is the state of each `fix insert/stream`, which a fix of
//! the same ID in the continuing deck takes up, as LIGGGHTS does; other insertion and averaging
//! fixes start afresh. A file that is not an mcdem restart stops with an error saying so.

use serde::{Deserialize, Serialize};

use super::*;
use crate::engine::EngineState;

/// The `format` field of an mcdem restart file.
const FORMAT: &str = "mcdem restart";
const VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
struct RestartFile {
    format: String,
    version: u32,
    ntypes: usize,
    /// Boundary style per axis: `p`, `f`, `m` or `s`.
    boundary: [String; 3],
    /// The box as created (the minimum of a `boundary m` axis), once known.
    box0: Option<([f64; 3], [f64; 3])>,
    engine: EngineState,
    /// The deck's groups in mask-bit order (bit 1 first; LAMMPS restarts keep groups too).
    #[serde(default)]
    groups: Vec<String>,
    /// The state of each `fix insert/stream` (LIGGGHTS restarts keep their insertion fixes').
    #[serde(default)]
    streams: Vec<fixes::stream::StreamState>,
}

impl Deck {
    pub(super) fn write_restart(&mut self, a: &[&str]) -> R<()> {
        commands::need(a, 2)?;
        if a.len() > 2 {
            return Err(unsupported(&format!("write_restart keyword {}", a[2])));
        }
        // As LAMMPS: a '*' in the name becomes the step.
        let name = a[1].replace('*', &self.world.step.to_string());
        let boundary = std::array::from_fn(|k| {
            match (self.periodic[k], self.shrink[k], self.shrink_min[k]) {
                (true, _, _) => "p",
                (false, false, _) => "f",
                (false, true, true) => "m",
                (false, true, false) => "s",
            }
            .to_string()
        });
        let file = RestartFile {
            format: FORMAT.into(),
            version: VERSION,
            ntypes: self.ntypes,
            boundary,
            box0: self.box0.map(|(lo, hi)| ([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z])),
            engine: self.world.restart_state()?,
            groups: self.groups.names(),
            streams: self.insertion.stream_states(),
        };
        let text = serde_json::to_string(&file).map_err(|e| format!("write_restart: {e}"))?;
        let path = PathBuf::from(&name);
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .map_err(|e| format!("write_restart: cannot create {}: {e}", dir.display()))?;
        }
        std::fs::write(&path, text + "\n").map_err(|e| format!("write_restart: cannot write {name}: {e}"))?;
        self.say(&format!(
            "INFO: write_restart: {} particles, {} contact histories at step {} to {name}",
            self.world.p.len(),
            file.engine.pairs.len() + file.engine.wall_contacts.len(),
            self.world.step
        ));
        Ok(())
    }

    pub(super) fn read_restart(&mut self, a: &[&str]) -> R<()> {
        commands::need(a, 2)?;
        if a.len() > 2 {
            return Err(unsupported(&format!("read_restart keyword {}", a[2])));
        }
        if a[1].contains('*') {
            return Err(unsupported("read_restart with '*' in the file name (give the file)"));
        }
        let path = self.input_path(a[1]);
        let bytes =
            std::fs::read(&path).map_err(|e| format!("read_restart: cannot read {}: {e}", path.display()))?;
        let text = std::str::from_utf8(&bytes).ok().filter(|t| t.trim_start().starts_with('{'));
        let Some(text) = text else {
            return Err(format!(
                "read_restart: {} is not an mcdem restart file: it looks like a LIGGGHTS binary restart, which mcdem cannot read (the format depends on LIGGGHTS' build); write the restart with mcdem's write_restart instead",
                a[1]
            ));
        };
        let file: RestartFile = serde_json::from_str(text)
            .map_err(|e| format!("read_restart: {} is not a readable mcdem restart file ({e})", a[1]))?;
        if file.format != FORMAT || file.version != VERSION {
            return Err(format!(
                "read_restart: {} is '{}' version {}, not '{FORMAT}' version {VERSION}",
                a[1], file.format, file.version
            ));
        }
        if file.engine.particles.typ.iter().any(|&t| t >= file.ntypes) {
            return Err(format!(
                "read_restart: {}: a particle type beyond the {} atom types",
                a[1], file.ntypes
            ));
        }
        for k in 0..3 {
            let s = file.boundary[k].as_str();
            if !matches!(s, "p" | "f" | "m" | "s") {
                return Err(format!("read_restart: {}: bad boundary style '{s}'", a[1]));
            }
            self.periodic[k] = s == "p";
            self.shrink[k] = matches!(s, "m" | "s");
            self.shrink_min[k] = s == "m";
        }
        if file.engine.periodic != self.periodic {
            return Err(format!(
                "read_restart: {}: the box's periodic axes disagree with its boundary styles",
                a[1]
            ));
        }
        self.world.restore_state(&file.engine)?;
        self.ntypes = file.ntypes;
        let v = |a: [f64; 3]| Vec3::new(a[0], a[1], a[2]);
        self.box0 = file.box0.map(|(lo, hi)| (v(lo), v(hi)));
        self.groups.particles_added(None)?;
        let (contacts, streams) = (file.engine.pairs.len() + file.engine.wall_contacts.len(), file.streams);
        self.insertion.restore_streams(streams);
        self.groups
            .restore(&file.groups, &self.world.p.mask)
            .map_err(|e| format!("read_restart: {}: {e}", a[1]))?;
        self.say(&format!(
            "INFO: read_restart: {} particles, {} contact histories at step {} from {}",
            self.world.p.len(),
            contacts,
            self.world.step,
            a[1]
        ));
        Ok(())
    }
}

//! The nonlocal solver on the 514-particle compression: the committed DEM state at the start of
//! the second compression (`validation/cases/nonlocal/hydrogel_start_2nd_compression.dump`),
//! compressed to φ = 0.85 in 40 load steps (the target: < 60 s), kernels `boussinesq` and, in the
//! full bench, `sphere`. "particle_steps_per_s" is particles × load steps per second.

use std::path::Path;
use std::time::Instant;

use super::{Options, Report, Row};
use crate::nonlocal::uniaxial::{compress, Uniaxial};
use crate::nonlocal::{Kernel, KernelKind};

pub const SCENE: &str = "nonlocal_514_to_phi_0.85";
const STEPS: usize = 40;

pub fn rows(opts: &Options, report: &mut Report, say: &mut dyn FnMut(&str)) -> Result<(), String> {
    let state = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("validation/cases/nonlocal/hydrogel_start_2nd_compression.dump");
    if !state.is_file() {
        report.notes.push(format!("nonlocal row skipped: {} not found", state.display()));
        return Ok(());
    }
    let u = Uniaxial::hydrogel(0.5, STEPS)?;
    let spheres = crate::nonlocal::scene::read_liggghts_dump(&state, u.particle)?;
    let kinds: &[KernelKind] =
        if opts.quick { &[KernelKind::Boussinesq] } else { &[KernelKind::Boussinesq, KernelKind::Sphere] };
    for &kind in kinds {
        let t = Instant::now();
        let points = compress(&spheres, &u, Kernel::new(kind, 1.0)?).map_err(|e| e.to_string())?;
        let secs = t.elapsed().as_secs_f64();
        say(&format!("nonlocal 514 to phi 0.85, {STEPS} steps, kernel {}: {secs:.1} s", kind.name()));
        report.rows.push(Row {
            engine: "rust",
            model: format!("nonlocal_{}", kind.name()).into(),
            scene: SCENE.into(),
            n: spheres.len(),
            // FIRE's force evaluation runs on the rayon pool (Newton's sparse LU on one thread).
            threads: rayon::current_num_threads(),
            particle_steps_per_s: (spheres.len() * points.len()) as f64 / secs,
            wall_time_s: secs,
            memory_bytes_per_particle: None,
            rounds_particle_steps_per_s: Vec::new(),
        });
    }
    report.notes.push(format!(
        "nonlocal: {STEPS} load steps from the committed start state, nu = 0.5; target < 60 s to phi = 0.85"
    ));
    Ok(())
}

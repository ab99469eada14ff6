//! `dump custom|local|custom/vtk|mesh/vtk|mesh/stl`, `dump_modify`, and writing the frames due at a step.

use super::*;

impl Deck {
    pub(super) fn dump(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 4 {
            return Err("dump: expected 'dump ID group style N file …'".into());
        }
        match a[3] {
            "custom/vtk" | "mesh/vtk" => return self.dump_vtk(a),
            "mesh/stl" => {
                if a.len() < 6 {
                    return Err("dump mesh/stl: expected N FILE [mesh fix IDs]".into());
                }
                let every = int(a[4])?;
                if every <= 0 {
                    return Err("dump: N must be > 0".into());
                }
                let all = self.world.meshes.len();
                let d = vtk::VtkDump::stl(a[1], every as u64, a[5], &a[6..], |f| self.mesh_index(f), all)?;
                self.vtk_dumps.push(d);
                return Ok(());
            }
            "custom" => {}
            "local" => {
                self.groups.act_on(a[2], &format!("dump {} {}", a[1], a[3]))?;
                self.local_dumps.push(local::LocalDump::parse(a[1], &a[4..])?);
                return Ok(());
            }
            other => return Err(unsupported(&format!("dump style {other}"))),
        }
        if a.len() < 7 {
            return Err("dump custom: expected N file columns…".into());
        }
        self.groups.act_on(a[2], &format!("dump {} {}", a[1], a[3]))?;
        let every = int(a[4])?;
        if every <= 0 {
            return Err("dump: N must be > 0".into());
        }
        let mut cols = Vec::new();
        for c in &a[6..] {
            cols.push(Col::parse(c).ok_or_else(|| unsupported(&format!("dump custom column {c}")))?);
        }
        self.dumps.push(Dump::new(
            a[1],
            every as u64,
            PathBuf::from(a[5]),
            a[6..].iter().map(|s| s.to_string()).collect(),
            cols,
        ));
        Ok(())
    }

    /// `dump ID group custom/vtk|mesh/vtk N FILE …` (see `vtk.rs`).
    pub(super) fn dump_vtk(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 7 {
            return Err(format!("dump {}: expected N file and at least one column or keyword", a[3]));
        }
        self.groups.act_on(a[2], &format!("dump {} {}", a[1], a[3]))?;
        let every = int(a[4])?;
        if every <= 0 {
            return Err("dump: N must be > 0".into());
        }
        let d = if a[3] == "custom/vtk" {
            vtk::VtkDump::particles(a[1], every as u64, a[5], &a[6..])?
        } else {
            let all = self.world.meshes.len();
            vtk::VtkDump::mesh(a[1], every as u64, a[5], &a[6..], |f| self.mesh_index(f), all)?
        };
        self.vtk_dumps.push(d);
        Ok(())
    }

    pub(super) fn dump_modify(&mut self, a: &[&str]) -> R<()> {
        let id = *a.get(1).ok_or("dump_modify: missing ID")?;
        let Some(d) = self.dumps.iter_mut().find(|d| d.name == id) else {
            if self.vtk_dumps.iter().any(|d| d.name == id) {
                return Err(unsupported(&format!("dump_modify of the VTK dump {id}")));
            }
            return Err(format!("dump_modify: no dump {id}"));
        };
        let mut k = 2;
        while k < a.len() {
            match a[k] {
                "format" => {
                    let f = a.get(k + 1).ok_or("dump_modify format: missing string")?;
                    d.format = Some(format::parse(f)?);
                    k += 2;
                }
                "sort" if a.get(k + 1) == Some(&"id") => k += 2,
                other => return Err(unsupported(&format!("dump_modify keyword {other}"))),
            }
        }
        Ok(())
    }

    /// Writes every dump whose interval divides the current step.
    pub(super) fn write_dumps(&mut self) -> R<()> {
        let step = self.world.step;
        for d in &mut self.dumps {
            if step % d.every == 0 && d.last != Some(step) {
                d.write(&self.world)?;
            }
        }
        for d in &mut self.local_dumps {
            if step % d.every == 0 && d.last != Some(step) {
                d.write(&mut self.world, &self.pair_locals)?;
            }
        }
        let vtk_due = |d: &vtk::VtkDump| step % d.every == 0 && d.last != Some(step);
        if self.vtk_dumps.iter().any(vtk_due) {
            // Meshes under a `fix move/mesh` or with a surface_vel carry a velocity LIGGGHTS
            // writes; others have none.
            let moving: Vec<bool> = self.world.meshes.iter().map(|m| m.has_velocity()).collect();
            for d in self.vtk_dumps.iter_mut().filter(|d| vtk_due(d)) {
                d.write(&self.world, &moving)?;
            }
        }
        Ok(())
    }
}

//! Atoms: the box, `read_data`, `create_atoms single`, `set`, `velocity`.

use super::*;

impl Deck {
    pub(super) fn set_box(&mut self, b: [f64; 6]) -> R<()> {
        if self.world.domain.is_some() {
            return Err("the simulation box already exists".into());
        }
        let lo = Vec3::new(b[0], b[2], b[4]);
        let hi = Vec3::new(b[1], b[3], b[5]);
        if (0..3).any(|k| hi[k].partial_cmp(&lo[k]) != Some(std::cmp::Ordering::Greater)) {
            return Err("box bounds must have hi > lo".into());
        }
        self.world.domain = Some(Domain::new(lo, hi, self.periodic));
        Ok(())
    }

    /// `read_data FILE`: the box, the atoms and their velocities ([`super::data_file`]).
    pub(super) fn read_data(&mut self, file: &str) -> R<()> {
        let path = self.input_path(file);
        let d = super::data_file::read(&path)?;
        if let Some(n) = d.atom_types {
            self.ntypes = n;
        }
        if let Some(b) = d.bounds {
            self.set_box(b)?;
        }
        for a in &d.atoms {
            if a.typ < 1 || a.typ > self.ntypes {
                return Err(format!(
                    "{}: atom {} has type {} outside 1..{}",
                    path.display(),
                    a.id,
                    a.typ,
                    self.ntypes
                ));
            }
            self.world.p.push(a.id, a.typ - 1, Vec3::new(a.x[0], a.x[1], a.x[2]), a.diameter, a.density);
            if let Some(image) = a.image {
                let i = self.world.p.len() - 1;
                self.world.p.image[i] = image;
            }
        }
        // The particles were empty before (the box did not exist): the file's index is theirs.
        for &(i, v) in &d.velocities {
            self.world.p.v[i] = Vec3::new(v[0], v[1], v[2]);
            self.world.p.omega[i] = Vec3::new(v[3], v[4], v[5]);
        }
        let read = if d.has_velocities { ", velocities read" } else { "" };
        self.say(&format!("  {} atoms{read}", d.natoms));
        Ok(())
    }

    pub(super) fn index_of(&self, id: i64) -> R<usize> {
        self.world.p.id.iter().position(|&x| x == id).ok_or_else(|| format!("no atom with id {id}"))
    }

    pub(super) fn create_atoms(&mut self, a: &[&str]) -> R<()> {
        if a.len() >= 3 && matches!(a[2], "region" | "box") {
            return self.create_atoms_lattice(a);
        }
        if a.len() < 6 || a[2] != "single" {
            return Err(unsupported(
                "create_atoms style (only 'create_atoms TYPE single x y z [units box]', 'TYPE region ID' or 'TYPE box')",
            ));
        }
        if a.len() > 6 && !(a.len() == 8 && a[6] == "units" && a[7] == "box") {
            return Err(unsupported("create_atoms keyword"));
        }
        let typ = int(a[1])? as usize;
        if typ < 1 || typ > self.ntypes {
            return Err(format!("atom type {typ} outside 1..{}", self.ntypes));
        }
        let x = Vec3::new(num(a[3])?, num(a[4])?, num(a[5])?);
        self.groups.particles_added(None)?;
        let id = self.world.p.id.iter().copied().max().unwrap_or(0) + 1;
        // LIGGGHTS default for a new sphere: diameter 1, density 1 (set changes it).
        self.world.p.push(id, typ - 1, x, 1.0, 1.0);
        Ok(())
    }

    pub(super) fn set(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 5 {
            return Err("set: expected 'set atom|type|group ID keyword value …'".into());
        }
        let sel: Vec<usize> = match a[1] {
            "atom" if a[2] == "*" => (0..self.world.p.len()).collect(),
            "atom" => vec![self.index_of(int(a[2])?)?],
            "type" => {
                let t = int(a[2])? as usize;
                (0..self.world.p.len()).filter(|&i| self.world.p.typ[i] + 1 == t).collect()
            }
            "group" => {
                let bit = self.groups.bit(a[2], "set group")?;
                (0..self.world.p.len()).filter(|&i| self.world.p.mask[i] & bit != 0).collect()
            }
            other => return Err(unsupported(&format!("set style {other}"))),
        };
        let mut k = 3;
        while k + 1 < a.len() + 1 && k < a.len() {
            let v = num(a.get(k + 1).ok_or("set: missing value")?)?;
            for &i in &sel {
                match a[k] {
                    "diameter" => self.world.p.set_size(i, Some(v), None),
                    "density" => self.world.p.set_size(i, None, Some(v)),
                    "vx" => self.world.p.v[i].x = v,
                    "vy" => self.world.p.v[i].y = v,
                    "vz" => self.world.p.v[i].z = v,
                    "omegax" => self.world.p.omega[i].x = v,
                    "omegay" => self.world.p.omega[i].y = v,
                    "omegaz" => self.world.p.omega[i].z = v,
                    other => return Err(unsupported(&format!("set keyword {other}"))),
                }
            }
            k += 2;
        }
        Ok(())
    }

    pub(super) fn velocity(&mut self, a: &[&str]) -> R<()> {
        if a.get(2) == Some(&"ramp") {
            // `velocity all ramp vx VLO VHI y YLO YHI [sum yes|no] [units box]` (LAMMPS): the
            // streaming profile of a Lees–Edwards shear.
            if a.len() < 9 || a[1] != "all" || a[3] != "vx" || a[6] != "y" {
                return Err(unsupported(
                    "velocity ramp form (only 'velocity all ramp vx VLO VHI y YLO YHI')",
                ));
            }
            let (vlo, vhi, ylo, yhi) = (num(a[4])?, num(a[5])?, num(a[7])?, num(a[8])?);
            if yhi <= ylo || !(yhi - ylo).is_finite() {
                return Err(format!("velocity ramp: YHI ({yhi}) must exceed YLO ({ylo})"));
            }
            let mut sum = false;
            let mut k = 9;
            while k < a.len() {
                match (a[k], a.get(k + 1).copied()) {
                    ("sum", Some(v @ ("yes" | "no"))) => sum = v == "yes",
                    ("units", Some("box")) => {}
                    _ => return Err(unsupported(&format!("velocity ramp keyword {}", a[k]))),
                }
                k += 2;
            }
            let p = &mut self.world.p;
            for i in 0..p.len() {
                let s = ((p.x[i].y - ylo) / (yhi - ylo)).clamp(0.0, 1.0);
                let v = vlo + s * (vhi - vlo);
                p.v[i].x = if sum { p.v[i].x + v } else { v };
            }
            return Ok(());
        }
        if a.len() < 6 || a[1] != "all" || a[2] != "set" {
            return Err(unsupported("velocity form (only 'velocity all set vx vy vz [units box]')"));
        }
        if a.len() > 6 && !(a.len() == 8 && a[6] == "units" && a[7] == "box") {
            return Err(unsupported("velocity keyword"));
        }
        let v = Vec3::new(num(a[3])?, num(a[4])?, num(a[5])?);
        self.world.p.v.iter_mut().for_each(|x| *x = v);
        Ok(())
    }
}

//! `fix` and `unfix`: one handler per fix style (the `match` in `fix`).

mod adapt;
mod ave_time;
pub(super) mod check_timestep;
pub(super) mod insert;
mod insert_common;
pub(super) mod momentum;
mod move_mesh;
mod reset_timestep;
pub(super) mod stream;
mod walls;

use super::*;

impl Deck {
    pub(super) fn fix(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 4 {
            return Err("fix: expected 'fix ID group style …'".into());
        }
        let (id, group, style) = (a[1], a[2], a[3]);
        // An insertion fix's group is where its particles go; any other fix acts on its group.
        // `nve/sphere` and `momentum` act on their group's members (mask bits), whatever it holds.
        if style.starts_with("insert/") {
            self.groups.check_exists(group, &format!("fix {id} {style}"))?;
            self.groups.particles_added(Some(group))?;
        } else if !matches!(style, "nve/sphere" | "momentum") {
            self.groups.act_on(group, &format!("fix {id} {style}"))?;
        }
        if self.fixes.iter().any(|(n, _)| n == id) {
            // LIGGGHTS replaces a fix redefined with the same ID; only the stateless ones here.
            if style != "property/global" {
                return Err(unsupported(&format!("redefining fix {id} without unfix")));
            }
            self.fixes.retain(|(n, _)| n != id);
        }
        let kind = match style {
            "property/global" => {
                if a.len() < 6 {
                    return Err("fix property/global: expected NAME STYLE values".into());
                }
                let vals = a[6..].iter().map(|s| num(s)).collect::<R<Vec<f64>>>()?;
                self.props.insert(a[4].into(), (a[5].into(), vals));
                FixKind::Property
            }
            "gravity" => {
                if a.len() != 9 || a[5] != "vector" {
                    return Err(unsupported("fix gravity form (only 'gravity MAG vector x y z')"));
                }
                let g = num(a[4])?;
                let dir = Vec3::new(num(a[6])?, num(a[7])?, num(a[8])?);
                let l = dir.norm();
                if l == 0.0 {
                    return Err("fix gravity: zero direction vector".into());
                }
                self.world.gravity = Some(dir / l * g);
                FixKind::Gravity
            }
            "nve/sphere" => {
                if a.len() > 4 {
                    return Err(unsupported("fix nve/sphere keywords"));
                }
                if self.world.integrate {
                    return Err(unsupported(&format!("fix {id} nve/sphere: a second integration fix")));
                }
                let bit = self.groups.bit(group, &format!("fix {id} nve/sphere"))?;
                self.world.integrate = true;
                self.world.integrate_group = (bit != GROUP_ALL).then_some(bit);
                FixKind::Nve
            }
            "deform" => {
                // Lees–Edwards simple shear: `fix ID all deform N xy erate RATE remap v`.
                if a.len() != 10 || a[5] != "xy" || a[6] != "erate" || a[8] != "remap" || a[9] != "v" {
                    return Err(unsupported("fix deform form (only 'deform N xy erate RATE remap v')"));
                }
                int(a[4])?;
                let rate = num(a[7])?;
                if !rate.is_finite() {
                    return Err(format!("fix deform: shear rate must be finite, got {}", a[7]));
                }
                if !(self.periodic[0] && self.periodic[1]) {
                    return Err("fix deform xy (Lees–Edwards shear) needs periodic x and y boundaries".into());
                }
                let d = self.world.domain.as_mut().ok_or("fix deform before the simulation box")?;
                d.le_vjump = rate * (d.hi.y - d.lo.y);
                FixKind::Deform
            }
            "multicontact/halfspace" => {
                if a.len() != 6 || a[4] != "geometric_prefactor" {
                    return Err(unsupported("fix multicontact/halfspace form (geometric_prefactor G)"));
                }
                let g = num(a[5])?;
                if g <= 0.0 {
                    return Err("fix multicontact/halfspace: geometric_prefactor > 0 required".into());
                }
                self.mc_gamma = Some(g);
                FixKind::MultiContact
            }
            "wall/gran" => self.wall_gran(a)?,
            "mesh/surface" | "mesh/surface/stress" => self.mesh_surface(a)?,
            "move/mesh" => self.move_mesh(a)?,
            "ave/time" => self.ave_time(a)?,
            "particletemplate/sphere" => self.particle_template(a)?,
            "particledistribution/discrete"
            | "particledistribution/discrete/massbased"
            | "particledistribution/discrete/numberbased" => self.particle_distribution(a)?,
            "insert/pack" => self.insert_pack(a)?,
            "insert/stream" => self.insert_stream(a)?,
            "check/timestep/gran" => self.check_timestep(a)?,
            "momentum" => self.momentum(a)?,
            "adapt" => self.fix_adapt(a)?,
            other => return Err(unsupported(&format!("fix style {other}"))),
        };
        self.fixes.push((id.into(), kind));
        Ok(())
    }

    pub(super) fn unfix(&mut self, a: &[&str]) -> R<()> {
        let id = *a.get(1).ok_or("unfix: missing ID")?;
        let pos =
            self.fixes.iter().position(|(n, _)| n == id).ok_or_else(|| format!("unfix: no fix {id}"))?;
        let (_, kind) = self.fixes.remove(pos);
        match kind {
            FixKind::Property => {}
            FixKind::Gravity => self.world.gravity = None,
            FixKind::Nve => {
                self.world.integrate = false;
                self.world.integrate_group = None;
            }
            FixKind::Momentum => self.momenta.retain(|m| m.fix != id),
            FixKind::MoveMesh(m) => self.world.meshes[m].stop_motion(),
            // An inactive wall keeps its slot so wall-contact keys stay valid.
            FixKind::Wall(w) => self.world.walls[w].geom = WallGeom::Meshes(Vec::new()),
            FixKind::AveTime(k) => {
                if let Some(mut at) = self.aves[k].take() {
                    if let Some(o) = at.out.as_mut() {
                        let _ = o.flush();
                    }
                }
            }
            FixKind::MultiContact => self.mc_gamma = None,
            FixKind::Deform => {
                if let Some(d) = self.world.domain.as_mut() {
                    d.le_vjump = 0.0;
                }
            }
            FixKind::MeshSurface(_) => return Err(unsupported("unfix of a mesh/surface fix")),
            FixKind::Insert => self.stop_inserting(id),
            FixKind::CheckTimestep(k) => self.checks[k] = None,
            // The radii keep their last values (LIGGGHTS restores nothing for `atom diameter`).
            FixKind::Adapt { .. } => {}
        }
        Ok(())
    }
}

//! `fix ID group check/timestep/gran N fraction_r fraction_h [warn yes|no]` as LIGGGHTS 3.8
//! (`fix_check_timestep_gran.cpp`): every N steps, at the end of the step, the time step is
//! compared with the smallest Rayleigh time of the particles and the smallest Hertz time of a
//! particle hitting its own copy at the highest relative speed (twice the fastest particle, or the
//! fastest particle plus the fastest node of a moving mesh wall, whichever is larger); the formulas
//! are in [`crate::physics::timestep`]. It warns as LIGGGHTS does when Δt passes either fraction, when
//! the fastest particle may travel half the neighbour skin in a step, or further than the smallest
//! radius. Its vector, `f_ID[1]`, `f_ID[2]`, `f_ID[3]`, is Δt/t_Rayleigh, Δt/t_Hertz and
//! v_max Δt / skin of the last check (0 before the first).

use std::f64::consts::PI;

use crate::deck::*;
use crate::physics::timestep::{effective_modulus, hertz_time, rayleigh_time};

/// LIGGGHTS' starting value of the minima (its `BIG`): what an empty group reports.
const BIG: f64 = 1e6;

#[derive(Debug, Clone)]
pub(in crate::deck) struct CheckTimestep {
    every: u64,
    fraction_rayleigh: f64,
    fraction_hertz: f64,
    warn: bool,
    /// Δt/t_R, Δt/t_H, v_max Δt / skin of the last check.
    pub(in crate::deck) values: [f64; 3],
}

impl Deck {
    pub(in crate::deck) fn check_timestep(&mut self, a: &[&str]) -> R<FixKind> {
        let what = format!("fix {} check/timestep/gran", a[1]);
        if a.len() != 7 && a.len() != 9 {
            return Err(format!("{what}: expected 'N fraction_r fraction_h [warn yes|no]'"));
        }
        let every = int(a[4])?;
        if every < 1 {
            return Err(format!("{what}: N must be >= 1, got {}", a[4]));
        }
        let warn = match a.get(7..9) {
            None => true,
            Some(["warn", "yes"]) => true,
            Some(["warn", "no"]) => false,
            Some(other) => {
                return Err(format!("{what}: expected 'warn yes' or 'warn no', got '{}'", other.join(" ")))
            }
        };
        let c = CheckTimestep {
            every: every as u64,
            fraction_rayleigh: num(a[5])?,
            fraction_hertz: num(a[6])?,
            warn,
            values: [0.0; 3],
        };
        self.checks.push(Some(c));
        Ok(FixKind::CheckTimestep(self.checks.len() - 1))
    }

    /// The checks due at the end of this step.
    pub(in crate::deck) fn check_timesteps(&mut self) {
        let step = self.world.step;
        for k in 0..self.checks.len() {
            let Some(c) = self.checks[k].as_ref() else { continue };
            if step % c.every != 0 {
                continue;
            }
            let (values, warnings) = self.timestep_estimate(c);
            if let Some(c) = self.checks[k].as_mut() {
                c.values = values;
            }
            for m in warnings {
                self.warn(&m);
            }
        }
    }

    fn timestep_estimate(&self, c: &CheckTimestep) -> ([f64; 3], Vec<String>) {
        let w = &self.world;
        let p = &w.p;
        let (mut t_rayleigh, mut r_min, mut vmax) = (BIG, BIG, 0.0f64);
        for i in 0..p.len() {
            let m = &w.materials[p.typ[i]];
            let t = rayleigh_time(p.radius[i], p.density[i], m.youngs_modulus, m.poisson_ratio);
            t_rayleigh = t_rayleigh.min(t);
            vmax = vmax.max(p.v[i].norm());
            r_min = r_min.min(p.radius[i]);
        }
        // The moving meshes of the last mesh wall (LIGGGHTS keeps the last `wall/gran` on meshes).
        let mut vmax_mesh = 0.0f64;
        if let Some(WallGeom::Meshes(ms)) =
            w.walls.iter().rev().map(|f| &f.geom).find(|g| matches!(g, WallGeom::Meshes(_)))
        {
            for &m in ms {
                vmax_mesh = vmax_mesh.max(w.meshes[m].max_node_speed());
            }
        }
        let vmax = (2.0 * vmax).max(vmax + vmax_mesh);
        let mut t_hertz = BIG;
        for i in 0..p.len() {
            let m = &w.materials[p.typ[i]];
            let e = effective_modulus(m.youngs_modulus, m.poisson_ratio, m.youngs_modulus, m.poisson_ratio);
            let r = p.radius[i];
            let mass = 4.0 * r * r * r * PI / 3.0 * p.density[i];
            t_hertz = t_hertz.min(hertz_time(mass, r / 2.0, e, vmax));
        }
        let (dt, skin) = (w.dt, w.skin);
        let values = [dt / t_rayleigh, dt / t_hertz, vmax * dt / skin];
        let mut warnings = Vec::new();
        if c.warn {
            if values[2] >= 0.5 {
                warnings.push(format!(
                    "time step too large or skin too small - particles may travel a distance of {:.6} per time-step, but half skin is {:.6}",
                    vmax * dt,
                    0.5 * skin
                ));
            }
            if vmax * dt > r_min {
                warnings.push(
                    "time step way too large - particles move further than the minimum radius in one step"
                        .into(),
                );
            }
            if values[0] > c.fraction_rayleigh {
                warnings.push(format!("time-step is {:.6} % of rayleigh time", values[0] * 100.0));
            }
            if values[1] > c.fraction_hertz {
                warnings.push(format!("time-step is {:.6} % of hertz time", values[1] * 100.0));
            }
        }
        (values, warnings)
    }
}

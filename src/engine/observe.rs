//! Observables read between steps: energies, the Eq. 4 stress, contact counts (coordination), the
//! touching contacts and the per-face mesh forces.

use crate::physics::{NormalLaw, Vec3};

use super::contacts::PairContact;
use super::pair_eval::{ContactHistory, PairCtx};
use super::particles::INERTIA;
use super::sinks::Touching;
use super::{Closure, StepError, WallGeom, World};

impl World {
    /// Force the particles exerted on each triangle of mesh `mesh` in the last force pass (the
    /// per-face share of `Mesh::force`, for `dump mesh/vtk`'s stresses).
    pub fn mesh_face_forces(&self, mesh: usize) -> Vec<Vec3> {
        let mut f = vec![Vec3::zeros(); self.meshes[mesh].tris.len()];
        for (c, wf) in self.contacts.wc.iter().zip(&self.contacts.wall_force) {
            if c.mesh as usize == mesh && matches!(self.walls[c.wall as usize].geom, WallGeom::Meshes(_)) {
                f[c.tri as usize] -= *wf;
            }
        }
        f
    }

    /// Kernel calls that (re)computed an influence matrix under the geometry tolerance.
    pub fn mc_influence_updates(&self) -> u64 {
        self.multi.mc_cache.as_ref().map_or(0, |c| c.recomputed)
    }

    /// Translational kinetic energy ½ Σ m v² [J] (thermo `ke`).
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.p.v.iter().zip(&self.p.mass).map(|(v, m)| v.norm_squared() * m).sum::<f64>()
    }

    /// Rotational kinetic energy ½ Σ I ω² [J] (`compute erotate/sphere`).
    pub fn rotational_energy(&self) -> f64 {
        0.5 * INERTIA
            * (0..self.p.len())
                .map(|i| {
                    self.p.omega[i].norm_squared() * self.p.radius[i] * self.p.radius[i] * self.p.mass[i]
                })
                .sum::<f64>()
    }

    /// Elastic energy stored in the contacts, Σ (2/5) k_n δ² (Hertz potential, undamped part;
    /// ½ k_n δ² under `model hooke`). Used by the energy-conservation checks; exact without
    /// multi-contact. `hooke/hysteresis` and `cohesion sjkr` have no potential (they dissipate by
    /// design): the loading branch ½ k_n δ² is counted and the cohesion is left out.
    pub fn elastic_energy(&self) -> f64 {
        let domain = match self.domain {
            Some(d) => d,
            None => return 0.0,
        };
        let mut e = 0.0;
        let nt = self.ntypes;
        for pr in &self.contacts.pairs {
            let (i, j) = (pr.i as usize, pr.j as usize);
            let mut d = self.p.x[i] - self.p.x[j];
            domain.minimum_image(&mut d);
            let (ri, rj) = (self.p.radius[i], self.p.radius[j]);
            let delta = ri + rj - d.norm();
            if delta > 0.0 {
                let c = &self.coeffs[self.p.typ[i] * nt + self.p.typ[j]];
                let reff = ri * rj / (ri + rj);
                let (mi, mj) = (self.p.mass[i], self.p.mass[j]);
                e += stored_energy(c, reff, mi * mj / (mi + mj), delta);
            }
        }
        for c in &self.contacts.wc {
            let i = c.p as usize;
            let delta = self.p.radius[i] - (self.p.x[i] - c.point).norm();
            if delta > 0.0 {
                let wt = self.walls[c.wall as usize].geom.wall_type(&self.meshes, c.mesh);
                let co = &self.wall_coeffs()[self.p.typ[i] * nt + wt];
                e += stored_energy(co, self.p.radius[i], self.p.mass[i], delta);
            }
        }
        e
    }

    /// Number of touching contacts: particle pairs and particle–wall.
    /// Eq. 4 stress tensor (compression positive), row-major, as (contact, kinetic) parts:
    /// contact Σ_pairs r_ij ⊗ F_ij / V (= Σ_i Σ_j ½ r_ij F_ij / V), kinetic Σ m v'⊗v' / V with v'
    /// the velocity about the Lees–Edwards streaming profile u_x = γ̇ (y − y_mid).
    pub fn stress_parts(&self) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
        let mut sc = [[0.0; 3]; 3];
        let mut sk = [[0.0; 3]; 3];
        let Some(domain) = self.domain else { return (sc, sk) };
        let vol = domain.volume();
        for (pr, force) in self.contacts.pairs.iter().zip(&self.contacts.pair_force) {
            if *force == Vec3::zeros() {
                continue;
            }
            let mut d = self.p.x[pr.i as usize] - self.p.x[pr.j as usize];
            domain.minimum_image(&mut d);
            add_outer(&mut sc, &d, &(force / vol));
        }
        for i in 0..self.p.len() {
            let mut v = self.p.v[i];
            v.x -= domain.streaming_vx(self.p.x[i].y);
            add_outer(&mut sk, &v, &(v * (self.p.mass[i] / vol)));
        }
        (sc, sk)
    }

    /// Every touching particle–particle contact with what `compute pair/gran/local` reports.
    /// Re-evaluates every pair at the current positions and velocities without advancing contact
    /// histories or touching particle forces: per-contact output at the end of a step sees the
    /// full-step velocities, as LIGGGHTS's `compute pair/gran/local` (which calls the pair style
    /// again with history updates off) does.
    pub fn touching_pairs(&mut self) -> Result<Vec<PairContact>, StepError> {
        let Some(domain) = self.domain else { return Ok(Vec::new()) };
        let ctx = PairCtx::new(
            &self.p,
            &self.coeffs,
            self.ntypes,
            domain,
            self.dt,
            false,
            self.step,
            self.liggghts_radii,
        );
        let np = self.contacts.pairs.len();
        let mc = self.closure == Some(Closure::MultiContact)
            && self.contacts.pair_hist.len() == np
            && self.contacts.pair_dr.len() == np;
        let closure = mc.then_some((&self.contacts.pair_dr[..], &mut self.contacts.pair_hist[..]));
        let dmax = ContactHistory::of(&mut self.contacts.pair_dmax, &mut self.contacts.pair_roll, np);
        let mut touching = Touching { x: &self.p.x, domain, out: Vec::new(), pair: Vec::new() };
        ctx.pass(&mut self.contacts.pairs, closure, dmax, false, &mut touching).map_err(|e| *e)?;
        let mut out = touching.out;
        for (c, &k) in out.iter_mut().zip(&touching.pair) {
            c.shear = self.contacts.pairs[k].shear;
        }
        Ok(out)
    }

    /// Particle–particle contacts carrying a force at the last force pass (set-up pass included).
    pub fn pair_contacts(&self) -> usize {
        self.contacts.pair_force.iter().filter(|f| **f != Vec3::zeros()).count()
    }

    /// Contacts carrying a normal force at the last force pass: (particle pairs, particle–wall).
    /// Under Hertz, which keeps no normal force per pair, the pairs carrying a force.
    pub fn contact_counts(&self) -> (usize, usize) {
        let pp = if self.contacts.pair_hist.len() == self.contacts.pairs.len() {
            self.contacts.pair_hist.iter().filter(|h| h.fn_prev > 0.0).count()
        } else {
            self.pair_contacts()
        };
        let pw = self.contacts.wc.iter().filter(|c| c.fn_prev > 0.0).count();
        (pp, pw)
    }
}

/// s += u ⊗ w.
pub(super) fn add_outer(s: &mut [[f64; 3]; 3], u: &Vec3, w: &Vec3) {
    for (row, ua) in s.iter_mut().zip(u.iter()) {
        for (sab, wb) in row.iter_mut().zip(w.iter()) {
            *sab += ua * wb;
        }
    }
}

/// Elastic energy of one contact of overlap `delta` > 0 under the pair's normal law.
fn stored_energy(c: &crate::physics::PairCoeffs, reff: f64, meff: f64, delta: f64) -> f64 {
    match &c.normal {
        NormalLaw::Hertz => 0.4 * crate::physics::hertz::hertz_force(c.e_star, reff, delta) * delta,
        NormalLaw::Hooke(h) | NormalLaw::HookeHysteresis(h, _) => {
            0.5 * crate::physics::hooke::normal(c.e_star, h, delta, reff, meff, 0.0).elastic * delta
        }
    }
}

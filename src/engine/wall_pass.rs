//! The wall stage: which wall elements each particle is close to (candidates, then the exact search
//! of `wall_contacts`), and the particle–wall forces through [`crate::physics::pair`].

use crate::physics::pair::{particle_wall_with_history, Body, RollSpring, WallLanes, WallPoint, LANES};
use crate::physics::{PairCoeffs, Vec3};
use crate::team::{share, SplitMut};

use super::contacts::{contact_error, WallCandidate, WallContact};
use super::{mesh, wall_contacts, Mesh, StepError, WallFix, WallGeom, World};

/// What the wall stage keeps between steps to find the wall contacts.
#[derive(Debug, Default)]
pub(super) struct WallSearch {
    pub(super) wc_scratch: wall_contacts::GroupScratch,
    /// Wall elements that may touch a particle before the next candidate build, in the wall scan's
    /// order (`update_wall_contacts`); built at every neighbour build (`wall_cand_builds`) and when
    /// the meshes have moved half a skin since (`wall_travel`).
    pub(super) wall_cand: Vec<WallCandidate>,
    pub(super) wall_cand_builds: Option<u64>,
    /// Upper bound on how far any mesh moved since the wall candidates were built [m].
    pub(super) wall_travel: f64,
}

/// Fewest wall contacts worth a threaded wall pass.
pub(super) const MIN_THREADED_WALL_CONTACTS: usize = 64;

impl World {
    /// Finds the wall elements each particle is close to and carries their history over.
    pub(super) fn update_wall_contacts(&mut self) {
        // A particle moves at most half a skin from where it was at the last neighbour build
        // (`neighbor_check`), so two particle positions between builds are at most a skin apart;
        // candidates found within reach + 1.5 skin stay a superset of the contacts while the
        // meshes move less than half a skin more. The exact test below then finds the same
        // contacts, in the same order, as a scan of every particle against every wall element.
        let margin = 1.5 * self.skin;
        if self.wall_search.wall_cand_builds != Some(self.builds)
            || self.wall_search.wall_travel > 0.5 * self.skin
        {
            self.build_wall_candidates(margin);
        }
        std::mem::swap(&mut self.contacts.wc, &mut self.contacts.wc_old);
        // Taken out for the search (no allocation: the vectors move back with their capacity).
        let (mut wc, mut scratch) =
            (std::mem::take(&mut self.contacts.wc), std::mem::take(&mut self.wall_search.wc_scratch));
        wall_contacts::collect(
            &wall_contacts::Scene::of(self),
            &self.wall_search.wall_cand,
            &self.contacts.wc_old,
            &mut wc,
            &mut scratch,
        );
        (self.contacts.wc, self.wall_search.wc_scratch) = (wc, scratch);
        if self.contacts.wc.len() != self.contacts.wc_old.len()
            || self.contacts.wc.iter().zip(&self.contacts.wc_old).any(|(a, b)| a.key() != b.key())
        {
            self.multi.slots_stale = true;
        }
    }

    /// Every particle against every wall element, in particle, wall, mesh, triangle order:
    /// the elements within reach + `margin` (by their distance whatever the element's active
    /// edges, so that the list holds every contact the exact test can find).
    pub(super) fn build_wall_candidates(&mut self, margin: f64) {
        self.wall_search.wall_cand.clear();
        self.wall_search.wall_cand_builds = Some(self.builds);
        self.wall_search.wall_travel = 0.0;
        let p = &self.p;
        for i in 0..p.len() {
            let x = p.x[i];
            let reach = p.radius[i] * self.mc_range + margin;
            for (w, wall) in self.walls.iter().enumerate() {
                let cand = |mesh: usize, tri: usize| WallCandidate {
                    p: i as u32,
                    wall: w as u32,
                    mesh: mesh as u32,
                    tri: tri as u32,
                };
                match &wall.geom {
                    WallGeom::Plane(pl) => {
                        if (x[pl.axis] - pl.pos).abs() < reach {
                            self.wall_search.wall_cand.push(cand(0, 0));
                        }
                    }
                    WallGeom::Cylinder(cy) => {
                        if cy.nearest(&x).is_some_and(|q| (x - q).norm_squared() < reach * reach) {
                            self.wall_search.wall_cand.push(cand(0, 0));
                        }
                    }
                    WallGeom::Meshes(list) => {
                        for &mi in list {
                            let m = &self.meshes[mi];
                            if m.far(&x, reach) {
                                continue;
                            }
                            for (t, tri) in m.tris.iter().enumerate() {
                                if mesh::distance_squared(tri, &x) < reach * reach {
                                    self.wall_search.wall_cand.push(cand(mi, t));
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}

/// A wall contact's result: (force, torque on the particle, |F·n|) when it touches.
pub(super) type WallOut = Option<(Vec3, Vec3, f64)>;

/// Read-only view of what the wall-contact forces need (shared between threads).
pub(super) struct WallCtx<'a> {
    pub(super) walls: &'a [WallFix],
    pub(super) meshes: &'a [Mesh],
    pub(super) coeffs: &'a [PairCoeffs],
    pub(super) nt: usize,
    pub(super) typ: &'a [usize],
    pub(super) x: &'a [Vec3],
    pub(super) v: &'a [Vec3],
    pub(super) omega: &'a [Vec3],
    pub(super) radius: &'a [f64],
    pub(super) mass: &'a [f64],
    pub(super) id: &'a [i64],
    pub(super) dt: f64,
    /// The run's time step, whatever `update` (see `PairCtx::roll_dt`).
    pub(super) roll_dt: f64,
    pub(super) update: bool,
    pub(super) step: u64,
    /// Evaluate the contacts that reach their wall in vectorised batches ([`WallLanes`]).
    pub(super) batched: bool,
}

impl WallCtx<'_> {
    /// Forces of the wall contacts `wc`, whose particles are `base..base + f.len()`, added into
    /// those particles' sums `f`, `torque` in contact order; each contact's force on the particle
    /// into `force` (for the mesh sums), and, on a time step, its history updated.
    pub(super) fn forces(
        &self,
        wc: &mut [WallContact],
        force: &mut [Vec3],
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) -> Result<(), StepError> {
        if self.batched {
            return self.forces_batched(wc, force, f, torque, base);
        }
        for (c, fc) in wc.iter_mut().zip(force) {
            let (out, shear, roll) = self.one(c)?;
            if self.update {
                c.roll = roll;
            }
            self.finish(c, fc, shear, out, f, torque, base);
        }
        Ok(())
    }

    /// One contact by [`particle_wall_with_history`]: (force, torque, |F·n|) if it touches, and
    /// its new tangential history and rolling spring; a contact that cannot be integrated stops
    /// the step, naming the particle.
    pub(super) fn one(&self, c: &WallContact) -> Result<(WallOut, Vec3, Vec3), StepError> {
        let i = c.p as usize;
        let (mut shear, mut roll) = (c.shear, c.roll);
        let spring = RollSpring { spring: &mut roll, dt: self.roll_dt };
        let r = particle_wall_with_history(
            self.coeff(c),
            &self.body(i),
            &self.wall_point(c),
            c.dr,
            self.dt,
            &mut shear,
            spring,
        )
        .map_err(|e| contact_error(self.step, self.id[i], None, e))?;
        Ok((r.map(|cf| (cf.force_i, cf.torque_i, cf.force_i.dot(&cf.en).abs())), shear, roll))
    }

    /// [`WallCtx::forces`] with the contacts that reach their wall evaluated in batches of
    /// [`LANES`] ([`WallLanes`], vectorised) and the results added in contact order afterwards:
    /// the same sums. A contact that does not reach its wall adds nothing, so settling it at
    /// once, ahead of the batch still open, changes no sum.
    pub(super) fn forces_batched(
        &self,
        wc: &mut [WallContact],
        force: &mut [Vec3],
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) -> Result<(), StepError> {
        let mut lanes = WallLanes::default();
        let mut slot = [0usize; LANES];
        let mut n = 0;
        for k in 0..wc.len() {
            let c = &wc[k];
            let i = c.p as usize;
            let ri = self.radius[i] + c.dr;
            let d = self.x[i] - c.point;
            if d.norm_squared() >= ri * ri {
                self.finish(&mut wc[k], &mut force[k], Vec3::zeros(), None, f, torque, base);
                continue;
            }
            let cf = self.coeff(c);
            let (l, v) = (n, self.v[i] - c.velocity);
            for a in 0..3 {
                lanes.d[a][l] = d[a];
                lanes.vr[a][l] = v[a];
                lanes.omega[a][l] = self.omega[i][a];
                lanes.shear[a][l] = c.shear[a];
            }
            (lanes.radius[l], lanes.dr[l], lanes.mass[l]) = (self.radius[i], c.dr, self.mass[i]);
            lanes.coeffs.set(l, cf);
            slot[n] = k;
            n += 1;
            if n == LANES {
                self.flush(&mut lanes, &slot, wc, force, f, torque, base)?;
                n = 0;
            }
        }
        if n > 0 {
            lanes.pad_from_first(n);
            self.flush(&mut lanes, &slot[..n], wc, force, f, torque, base)?;
        }
        Ok(())
    }

    /// Evaluates a batch and settles its contacts `slot` in order. A lane that cannot be
    /// integrated is evaluated again by [`WallCtx::one`] for the error it reports.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn flush(
        &self,
        lanes: &mut WallLanes,
        slot: &[usize],
        wc: &mut [WallContact],
        force: &mut [Vec3],
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) -> Result<(), StepError> {
        lanes.evaluate(self.dt);
        for (l, &k) in slot.iter().enumerate() {
            let c = &mut wc[k];
            if !lanes.ok[l] {
                self.one(c)?;
            }
            let lane = |a: &[[f64; LANES]; 3]| Vec3::new(a[0][l], a[1][l], a[2][l]);
            let out = Some((lane(&lanes.force), lane(&lanes.torque), lanes.fnorm[l]));
            self.finish(c, &mut force[k], lane(&lanes.shear), out, f, torque, base);
        }
        Ok(())
    }

    /// Settles one contact: its force and torque (if it touches) into the particle's sums, its
    /// force recorded for the mesh sums, and on a time step its history.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn finish(
        &self,
        c: &mut WallContact,
        fc: &mut Vec3,
        shear: Vec3,
        out: WallOut,
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) {
        let i = c.p as usize;
        let fnorm = match out {
            Some((force, tq, fnorm)) => {
                f[i - base] += force;
                torque[i - base] += tq;
                *fc = force;
                fnorm
            }
            None => {
                *fc = Vec3::zeros();
                0.0
            }
        };
        if self.update {
            c.shear = shear;
            c.fn_prev = fnorm;
            let rel = c.point - self.x[i];
            c.rel_prev = if fnorm > 0.0 {
                rel
            } else {
                let l = rel.norm();
                if l > 0.0 {
                    rel * ((self.radius[i] + c.dr) / l)
                } else {
                    Vec3::zeros()
                }
            };
        }
    }

    pub(super) fn coeff(&self, c: &WallContact) -> &PairCoeffs {
        let wall_type = self.walls[c.wall as usize].geom.wall_type(self.meshes, c.mesh);
        &self.coeffs[self.typ[c.p as usize] * self.nt + wall_type]
    }

    pub(super) fn body(&self, i: usize) -> Body {
        Body { x: self.x[i], v: self.v[i], omega: self.omega[i], radius: self.radius[i], mass: self.mass[i] }
    }

    pub(super) fn wall_point(&self, c: &WallContact) -> WallPoint {
        WallPoint { point: c.point, velocity: c.velocity }
    }
}

impl World {
    /// Body forces, then the wall contacts' forces into the particles' sums (the order of the
    /// example decks' fixes), and each mesh's total force. With threads, each member adds both
    /// to its own particles.
    pub(super) fn wall_pass(&mut self, update: bool, threads: usize, batched: bool) -> Result<(), StepError> {
        let n = self.p.len();
        let nt = self.ntypes;
        let dt = if update { self.dt } else { 0.0 };

        // Body forces come next, then the walls (the order of the example decks' fixes); with
        // threads, each member adds both to its own particles (below).
        let walls_threaded = threads > 1 && self.contacts.wc.len() >= MIN_THREADED_WALL_CONTACTS;
        if let Some(g) = self.gravity.filter(|_| !walls_threaded) {
            for i in 0..n {
                self.p.f[i] += self.p.mass[i] * g;
            }
        }
        // Walls, in wall-contact order, which is particle order. With threads the list splits at
        // a particle boundary and each half adds into its own particles' sums: every particle
        // gets its terms in the serial order. A mesh's total force is summed afterwards, in
        // contact order, from each contact's force.
        let ctx = WallCtx {
            walls: &self.walls,
            meshes: &self.meshes,
            coeffs: self.wall_coeffs.as_deref().unwrap_or(&self.coeffs),
            nt,
            typ: &self.p.typ,
            x: &self.p.x,
            v: &self.p.v,
            omega: &self.p.omega,
            radius: &self.p.radius,
            mass: &self.p.mass,
            id: &self.p.id,
            dt,
            roll_dt: self.dt,
            update,
            step: self.step,
            batched,
        };
        if self.contacts.wall_force.len() != self.contacts.wc.len() {
            self.contacts.wall_force.resize(self.contacts.wc.len(), Vec3::zeros());
        }
        if walls_threaded {
            // Member k's contacts start at its equal share's start moved back to the first
            // contact of that particle, its particles at that contact's (0 for the first member,
            // n after the last): non-decreasing in k, since the contacts are in particle order.
            let (wc, cuts) = (&self.contacts.wc, &mut self.blocks.wall_cuts);
            cuts.clear();
            cuts.extend((0..threads).map(|k| {
                let mut c = share(wc.len(), threads, k).start;
                while c > 0 && c < wc.len() && wc[c - 1].p == wc[c].p {
                    c -= 1;
                }
                [c, if k == 0 { 0 } else { wc.get(c).map_or(n, |w| w.p as usize) }]
            }));
            cuts.push([wc.len(), n]);
        }
        match self.blocks.team.as_ref().filter(|_| walls_threaded) {
            Some(team) => {
                let (cuts, gravity, mass) = (&self.blocks.wall_cuts, self.gravity, &self.p.mass);
                let (cs, wf) =
                    (SplitMut::new(&mut self.contacts.wc), SplitMut::new(&mut self.contacts.wall_force));
                let (fs, ts) = (SplitMut::new(&mut self.p.f), SplitMut::new(&mut self.p.torque));
                team.run(|k| {
                    let ([c0, p0], [c1, p1]) = (cuts[k], cuts[k + 1]);
                    // SAFETY: the cuts do not decrease with k, so the members' ranges of
                    // contacts and of particles are disjoint.
                    let (c, w, f, t) =
                        unsafe { (cs.range(c0..c1), wf.range(c0..c1), fs.range(p0..p1), ts.range(p0..p1)) };
                    if let Some(g) = gravity {
                        for (fi, m) in f.iter_mut().zip(&mass[p0..p1]) {
                            *fi += *m * g;
                        }
                    }
                    ctx.forces(c, w, f, t, p0)
                })?;
            }
            None => ctx.forces(
                &mut self.contacts.wc,
                &mut self.contacts.wall_force,
                &mut self.p.f,
                &mut self.p.torque,
                0,
            )?,
        }
        for (c, wf) in self.contacts.wc.iter().zip(&self.contacts.wall_force) {
            if let WallGeom::Meshes(_) = self.walls[c.wall as usize].geom {
                self.meshes[c.mesh as usize].force -= *wf;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{Closure, Domain, PlaneWall};
    use crate::physics::hertz::Tangential;
    use crate::physics::Material;

    /// The wall contacts a scan of every particle against every wall element finds (what the
    /// candidate list must reproduce), as keys in scan order, from the same last-step contacts.
    fn scanned_keys(w: &World) -> Vec<(u32, u32, u32, u32)> {
        let mut all = Vec::new();
        for i in 0..w.p.len() as u32 {
            for (wi, wall) in w.walls.iter().enumerate() {
                let cand = |mesh: usize, tri: usize| WallCandidate {
                    p: i,
                    wall: wi as u32,
                    mesh: mesh as u32,
                    tri: tri as u32,
                };
                match &wall.geom {
                    WallGeom::Plane(_) | WallGeom::Cylinder(_) => all.push(cand(0, 0)),
                    WallGeom::Meshes(list) => {
                        for &mi in list {
                            all.extend((0..w.meshes[mi].tris.len()).map(|t| cand(mi, t)));
                        }
                    }
                }
            }
        }
        let scene = wall_contacts::Scene::of(w);
        let (mut out, mut scratch) = (Vec::new(), Vec::new());
        wall_contacts::collect(&scene, &all, &w.contacts.wc_old, &mut out, &mut scratch);
        out.iter().map(WallContact::key).collect()
    }

    /// A piston of two tilted triangles oscillating onto two layers of resting spheres (no
    /// integration, so that no neighbour build happens and only the mesh's travel rebuilds the
    /// candidates) at a fifth of the skin per step: every step the contacts equal the full scan's.
    #[test]
    fn wall_candidates_find_every_contact_of_a_moving_mesh() {
        let (r, l) = (1e-3, 1e-2);
        let mut w = World::new();
        w.domain = Some(Domain::new(Vec3::zeros(), Vec3::repeat(l), [false; 3]));
        w.set_materials(vec![Material::hertz(1e6, 0.4).unwrap()], &[0.7], &[0.5], Tangential::History)
            .unwrap();
        w.closure = Some(Closure::Hertz);
        w.skin = 1e-4;
        w.dt = 1e-5;
        let lattice = (0..4).flat_map(|i| (0..4).flat_map(move |j| (0..2).map(move |k| (i, j, k))));
        for (id, (i, j, k)) in (1..).zip(lattice) {
            // Heights staggered by up to 0.9 r, so contacts start at many different steps.
            let dz = 1e-4 * ((7 * i + 3 * j + 5 * k) % 10) as f64;
            let x = Vec3::new(
                1.3e-3 + 2.5e-3 * i as f64,
                1.3e-3 + 2.5e-3 * j as f64,
                1.5e-3 + 2.5e-3 * k as f64 + dz,
            );
            w.p.push(id, 0, x, 2.0 * r, 1000.0);
        }
        for (axis, pos) in [(0, 0.0), (0, l), (1, 0.0), (1, l), (2, 0.0)] {
            let geom = WallGeom::Plane(PlaneWall { axis, pos, wall_type: 0 });
            w.walls.push(WallFix { name: format!("plane{axis}"), geom });
        }
        let (z0, z1) = (6.0e-3, 6.3e-3);
        let raw = vec![
            [Vec3::new(0.0, 0.0, z0), Vec3::new(l, 0.0, z0), Vec3::new(l, l, z1)],
            [Vec3::new(0.0, 0.0, z0), Vec3::new(l, l, z1), Vec3::new(0.0, l, z1)],
        ];
        w.meshes.push(Mesh::new("piston", 0, raw).unwrap());
        w.walls.push(WallFix { name: "piston".into(), geom: WallGeom::Meshes(vec![0]) });
        w.setup().unwrap();
        let keys = |w: &World| w.contacts.wc.iter().map(WallContact::key).collect::<Vec<_>>();
        assert_eq!(keys(&w), scanned_keys(&w));
        let (mut travel_builds, mut onsets, mut before) = (0, 0, 0);
        for s in 0..240 {
            // Down and up by 8e-4 m at 2 m/s: 2e-5 m per step.
            if s % 40 == 0 {
                let v = Vec3::new(0.0, 0.0, if (s / 40) % 2 == 0 { -2.0 } else { 2.0 });
                w.meshes[0].mover = Some(crate::engine::Mover::new(crate::engine::Motion::Linear { v }));
            }
            let travel = w.wall_search.wall_travel;
            w.step().unwrap();
            travel_builds += usize::from(w.wall_search.wall_travel < travel);
            let scan = scanned_keys(&w);
            let on_piston = scan.iter().filter(|k| k.1 == 5).count();
            onsets += on_piston.saturating_sub(before);
            before = on_piston;
            assert_eq!(keys(&w), scan, "step {s}");
        }
        assert_eq!(w.builds, 1, "no neighbour build after set-up");
        assert!(travel_builds > 50, "the mesh's travel rebuilt the candidates {travel_builds} times");
        assert!(onsets >= 20, "{onsets} piston contacts began");
    }
}

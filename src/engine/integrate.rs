//! Velocity Verlet with rotation (LIGGGHTS `fix nve/sphere`): the two half-kicks and the drift.

use std::ops::Range;

use crate::physics::Vec3;
use crate::team::SplitMut;

use super::particles::INERTIA;
use super::{StepError, World};

impl World {
    /// The boundaries' part of the drift: the Lees–Edwards offset and the meshes of `fix
    /// move/mesh` advance by one step (`mesh_motion`), and the neighbour and wall-candidate checks learn how far.
    pub(super) fn move_boundaries(&mut self) {
        let dt = self.dt;
        if let Some(d) = self.domain.as_mut() {
            d.advance_shear(dt);
            self.lists.le_travel += d.le_vjump * dt;
        }
        let mut travel: f64 = 0.0;
        for m in &mut self.meshes {
            travel = travel.max(m.advance_motion(dt));
        }
        self.wall_search.wall_travel += travel;
    }

    /// First half of velocity Verlet: half-kick, drift, rotational half-kick (of the particles of
    /// [`World::integrate_group`] only, when it is set). On the team's
    /// threads each member moves its own range of particles (the range it will also finish and,
    /// roughly, the particles of its pair block): a particle's state then stays in one core's
    /// cache from step to step instead of travelling between them.
    pub(super) fn initial_integrate(&mut self) {
        let (dtf, dtv) = (0.5 * self.dt, self.dt);
        let dtfrot = dtf / INERTIA;
        let n = self.p.len();
        let group = self.integrate_group;
        let p = &mut self.p;
        let (f, torque, mass, radius, mask) = (&p.f, &p.torque, &p.mass, &p.radius, &p.mask);
        let kick = |r: Range<usize>, x: &mut [Vec3], v: &mut [Vec3], omega: &mut [Vec3]| {
            for (i, ((x, v), omega)) in r.zip(x.iter_mut().zip(v.iter_mut()).zip(omega.iter_mut())) {
                if group.is_some_and(|bit| mask[i] & bit == 0) {
                    continue;
                }
                let dtfm = dtf / mass[i];
                *v += dtfm * f[i];
                *x += dtv * *v;
                let dtirot = dtfrot / (radius[i] * radius[i] * mass[i]);
                *omega += dtirot * torque[i];
            }
        };
        match self.blocks.team.as_ref().filter(|_| self.blocks.parallel) {
            Some(team) => {
                let (xs, vs, os) =
                    (SplitMut::new(&mut p.x), SplitMut::new(&mut p.v), SplitMut::new(&mut p.omega));
                team.for_shares(n, |_, r| {
                    // SAFETY: the members' shares are disjoint ranges of particles.
                    let (x, v, o) =
                        unsafe { (xs.range(r.clone()), vs.range(r.clone()), os.range(r.clone())) };
                    kick(r, x, v, o);
                });
            }
            None => kick(0..n, &mut p.x, &mut p.v, &mut p.omega),
        }
    }

    /// Second half-kick of velocity Verlet (on the team's threads as [`World::initial_integrate`]);
    /// stops at the first particle (lowest index) whose position or velocity is not finite.
    pub(super) fn final_integrate(&mut self) -> Result<(), StepError> {
        let dtf = 0.5 * self.dt;
        let dtfrot = dtf / INERTIA;
        let (n, step, group) = (self.p.len(), self.step, self.integrate_group);
        let p = &mut self.p;
        let (f, torque, mass, radius, x, id, mask) =
            (&p.f, &p.torque, &p.mass, &p.radius, &p.x, &p.id, &p.mask);
        let kick = |r: Range<usize>, v: &mut [Vec3], omega: &mut [Vec3]| {
            for (i, (v, omega)) in r.zip(v.iter_mut().zip(omega.iter_mut())) {
                if group.is_some_and(|bit| mask[i] & bit == 0) {
                    continue;
                }
                let dtfm = dtf / mass[i];
                *v += dtfm * f[i];
                let dtirot = dtfrot / (radius[i] * radius[i] * mass[i]);
                *omega += dtirot * torque[i];
                if !(x[i].iter().all(|c| c.is_finite()) && v.iter().all(|c| c.is_finite())) {
                    return Err(StepError {
                        step,
                        particle: id[i],
                        cause: "position or velocity is not finite".into(),
                        contact: None,
                    });
                }
            }
            Ok(())
        };
        match self.blocks.team.as_ref().filter(|_| self.blocks.parallel) {
            Some(team) => {
                let (vs, os) = (SplitMut::new(&mut p.v), SplitMut::new(&mut p.omega));
                team.run_shares(n, |_, r| {
                    // SAFETY: the members' shares are disjoint ranges of particles.
                    let (v, o) = unsafe { (vs.range(r.clone()), os.range(r.clone())) };
                    kick(r, v, o)
                })
            }
            None => kick(0..n, &mut p.v, &mut p.omega),
        }
    }
}

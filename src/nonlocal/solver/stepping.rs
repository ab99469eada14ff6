//! Load stepping: increments of the loading parameter, restored and halved when Newton (and the
//! FIRE fallback) fail, with the affine predictor of the wall motion.

use super::{Contact, Nonlocal, SolveError, StepStats};
use crate::physics::Vec3;

impl Nonlocal {
    /// Advances the loading parameter from `t0` to `t1`: `load_at(t)` gives every wall's point [m]
    /// and the body-force factor.
    /// A failing increment is restored and halved, at most `Settings::max_subdivisions` times deep.
    pub fn advance(
        &mut self,
        load_at: &dyn Fn(f64) -> (Vec<Vec3>, f64),
        t0: f64,
        t1: f64,
    ) -> Result<StepStats, SolveError> {
        self.advance_depth(load_at, t0, t1, 0)
    }

    pub(super) fn advance_depth(
        &mut self,
        load_at: &dyn Fn(f64) -> (Vec<Vec3>, f64),
        t0: f64,
        t1: f64,
        depth: u32,
    ) -> Result<StepStats, SolveError> {
        let saved_x = self.x.clone();
        let saved_c = self.contacts.clone();
        let saved_w: Vec<Vec3> = self.walls.iter().map(|w| w.point).collect();
        let saved_b = self.body_factor;
        let (points, factor) = load_at(t1);
        for (w, p) in points.into_iter().enumerate() {
            self.set_wall_point(w, p);
        }
        self.body_factor = factor;
        if self.settings.affine_predictor {
            self.predict_affine(&saved_w);
        }
        let predicted_x = self.x.clone();
        let result = if self.settings.fire_first && self.settings.fire_fallback_steps > 0 {
            // FIRE to 1e-4, Newton on a short budget; if Newton fails (a nearly floppy particle far
            // from its equilibrium), FIRE again to 1e-7 from the prediction, Newton with the full
            // budget.
            let (fire_steps, fire_rel) = self.relax(self.settings.fire_fallback_steps, 1e-4, true);
            if self.last_fire_stalled {
                // The second FIRE below would start from the same state and retrace the same
                // stall, and Newton from an unrelaxed state does not converge: go straight to halving.
                return self.restore_and_halve(
                    load_at,
                    (t0, t1, depth),
                    (saved_x, saved_c, saved_w, saved_b),
                    SolveError {
                        message: format!(
                            "FIRE stalled after {fire_steps} steps (the lagged nonlocal iteration oscillates)"
                        ),
                        residual: fire_rel,
                        worst_particle: Some(self.ids[self.last_fire_worst]),
                    },
                );
            }
            // From a relaxed state Newton converges in a few iterations or not at all.
            let full = self.settings;
            self.settings.max_newton = full.max_newton.min(12);
            self.settings.max_active_rounds = full.max_active_rounds.min(4);
            let first = self.solve();
            self.settings = full;
            match first {
                Ok(mut s) => {
                    s.fire_steps += fire_steps;
                    Ok(s)
                }
                Err(_) => {
                    self.x = predicted_x;
                    self.contacts = saved_c.clone();
                    let (more, _) = self.relax(self.settings.fire_fallback_steps, 1e-7, true);
                    self.solve().map(|mut s| {
                        s.fire_steps += fire_steps + more;
                        s
                    })
                }
            }
        } else {
            self.newton_then_fire(predicted_x)
        };
        match result {
            Ok(s) => Ok(s),
            Err(e) => {
                self.restore_and_halve(load_at, (t0, t1, depth), (saved_x, saved_c, saved_w, saved_b), e)
            }
        }
    }

    /// Restores the state saved before a failed increment and solves it in two halves (or reports
    /// the failure when no halving is left).
    #[allow(clippy::type_complexity)]
    pub(super) fn restore_and_halve(
        &mut self,
        load_at: &dyn Fn(f64) -> (Vec<Vec3>, f64),
        (t0, t1, depth): (f64, f64, u32),
        (saved_x, saved_c, saved_w, saved_b): (Vec<Vec3>, Vec<Contact>, Vec<Vec3>, f64),
        e: SolveError,
    ) -> Result<StepStats, SolveError> {
        self.x = saved_x;
        self.contacts = saved_c;
        for (w, p) in saved_w.into_iter().enumerate() {
            self.walls[w].point = p;
        }
        self.body_factor = saved_b;
        // Nothing to halve when the increment is empty (the initial equilibrium).
        if depth >= self.settings.max_subdivisions || t1 <= t0 {
            return Err(SolveError {
                message: format!("{} after {depth} halvings of the load increment", e.message),
                ..e
            });
        }
        let tm = 0.5 * (t0 + t1);
        let a = self.advance_depth(load_at, t0, tm, depth + 1)?;
        let b = self.advance_depth(load_at, tm, t1, depth + 1)?;
        Ok(StepStats {
            newton_iterations: a.newton_iterations + b.newton_iterations,
            active_set_rounds: a.active_set_rounds + b.active_set_rounds,
            subdivisions: a.subdivisions + b.subdivisions + 1,
            fire_steps: a.fire_steps + b.fire_steps,
            residual: b.residual,
            relation_residual: b.relation_residual,
        })
    }

    /// Warm-started Newton on a short budget, then (if it fails and a fallback is allowed) FIRE and
    /// Newton with the full budget.
    pub(super) fn newton_then_fire(&mut self, predicted_x: Vec<Vec3>) -> Result<StepStats, SolveError> {
        // Warm-started Newton first, on a short budget when a FIRE fallback is available: a step
        // that needs a rearrangement does not converge in a few iterations, and FIRE is cheaper than
        // a long Newton stall.
        let full = self.settings;
        if full.fire_fallback_steps > 0 {
            self.settings.max_newton = full.max_newton.min(8);
            self.settings.max_active_rounds = full.max_active_rounds.min(2);
        }
        let first = self.solve();
        self.settings = full;
        // A failed increment is usually a rearrangement (contacts opening, particles sliding into
        // new positions), which Newton cannot follow: relax by FIRE with the lagged nonlocal
        // relation at this load, then let Newton make it exact, before halving the increment.
        match first {
            Ok(s) => Ok(s),
            Err(_) if self.settings.fire_fallback_steps > 0 => {
                self.x = predicted_x;
                let (fire_steps, _) = self.relax(self.settings.fire_fallback_steps, 1e-4, true);
                self.solve().map(|mut s| {
                    s.fire_steps += fire_steps;
                    s
                })
            }
            Err(e) => Err(e),
        }
    }

    /// The affine predictor of [`Settings::affine_predictor`]: `old` are the wall points (scaled)
    /// before the increment. For every wall that moved along its normal n and has an opposite wall
    /// (normal −n), the coordinate s = (x − p_opposite)·n_opposite of every particle is multiplied by
    /// gap_new / gap_old.
    pub(super) fn predict_affine(&mut self, old: &[Vec3]) {
        for w in 0..self.walls.len() {
            let n = self.walls[w].normal;
            let moved = (self.walls[w].point - old[w]).dot(&n);
            if moved == 0.0 {
                continue;
            }
            let Some(o) = (0..self.walls.len()).find(|&o| self.walls[o].normal.dot(&n) < -1.0 + 1e-12) else {
                continue;
            };
            let (po, no) = (self.walls[o].point, self.walls[o].normal);
            let gap_old = (old[w] - old[o]).dot(&no);
            let gap_new = (self.walls[w].point - po).dot(&no);
            if !(gap_old > 0.0 && gap_new > 0.0) {
                continue;
            }
            let f = gap_new / gap_old;
            for x in self.x.iter_mut() {
                let s = (*x - po).dot(&no);
                *x += no * (s * (f - 1.0));
            }
        }
    }
}

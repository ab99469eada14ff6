//! Newton with backtracking line search and pseudo-transient continuation for one active set,
//! the active-set update, and [`Nonlocal::solve`] that alternates the two.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::SparseColMat;
use faer::Mat;

use super::{Contact, Eval, Geo, Nonlocal, Other, SolveError, StepStats};
use crate::physics::Vec3;

/// Largest centre displacement per Newton iteration, in mean radii (see the step cap in `newton`).
const MAX_MOVE: f64 = 0.05;

/// Pseudo-transient continuation (Kelley & Keyes, SIAM J. Numer. Anal. 35 (1998) 508): when the
/// Newton step fails its line search, a drag σ·k_ref·I is added to the position block of the Jacobian
/// (residual untouched), making the step a damped relaxation; σ shrinks with the residual (switched
/// evolution relaxation) and Newton is recovered near the solution.
const PTC_START: f64 = 1.0;
const PTC_MAX: f64 = 1e10;
const PTC_OFF: f64 = 1e-6;

impl Nonlocal {
    pub(super) fn store(&mut self, x: Vec<Vec3>, delta: &[f64], iterations: usize) {
        self.last_iterations = iterations;
        self.x = x;
        for (c, d) in self.contacts.iter_mut().zip(delta) {
            c.delta = *d;
        }
    }

    pub(super) fn fail(&self, message: String, ev: &Eval) -> SolveError {
        SolveError { message, residual: ev.force_rel, worst_particle: Some(self.ids[ev.worst]) }
    }

    /// Newton with backtracking line search for the current active set. Returns iterations.
    pub(super) fn newton(&mut self) -> Result<(usize, f64, f64), SolveError> {
        let n = self.x.len();
        let nc = self.contacts.len();
        let dim = 3 * n + nc;
        let adj = self.adjacency();
        let mut x = self.x.clone();
        let mut delta: Vec<f64> = self.contacts.iter().map(|c| c.delta).collect();
        let tol = self.settings.tolerance;
        let mut sigma = 0.0;
        let mut ev = self.evaluate(&x, &delta, &adj, true, sigma);
        let mut iters = 0;
        let max_iters = self.settings.max_newton;
        loop {
            if !(ev.force_rel.is_finite() && ev.relation_rel.is_finite()) {
                return Err(self.fail("non-finite residual".into(), &ev));
            }
            if ev.force_rel <= tol && ev.relation_rel <= tol {
                break;
            }
            if iters >= max_iters {
                let e = self.fail(format!("Newton did not converge in {iters} iterations"), &ev);
                self.store(x, &delta, iters);
                return Err(e);
            }
            iters += 1;
            if std::env::var_os("MCDEM_NONLOCAL_TRACE").is_some() {
                eprintln!(
                    "  newton {iters}: contacts {nc} force {:.3e} (mean P {:.3e}, worst {}) relation {:.3e} nnz {} sigma {sigma:.1e}",
                    ev.force_rel,
                    ev.p_mean,
                    self.ids[ev.worst],
                    ev.relation_rel,
                    ev.trip.len()
                );
            }
            let jm = SparseColMat::<usize, f64>::try_new_from_triplets(dim, dim, &ev.trip)
                .map_err(|e| self.fail(format!("cannot assemble the Jacobian: {e:?}"), &ev))?;
            let pattern = jm.symbolic();
            let symbolic = match &self.lu_pattern {
                Some((cp, ri, sym)) if cp == pattern.col_ptr() && ri == pattern.row_idx() => sym.clone(),
                _ => {
                    let sym = SymbolicLu::try_new(pattern)
                        .map_err(|e| self.fail(format!("sparse LU (symbolic) failed: {e:?}"), &ev))?;
                    self.lu_pattern =
                        Some((pattern.col_ptr().to_vec(), pattern.row_idx().to_vec(), sym.clone()));
                    sym
                }
            };
            let lu = Lu::try_new_with_symbolic(symbolic, jm.as_ref())
                .map_err(|e| self.fail(format!("sparse LU failed: {e:?}"), &ev))?;
            let mut rhs = Mat::<f64>::from_fn(dim, 1, |i, _| -ev.res[i]);
            lu.solve_in_place(rhs.as_mut());
            let mut step: Vec<f64> = (0..dim).map(|i| rhs[(i, 0)]).collect();
            if step.iter().any(|v| !v.is_finite()) {
                return Err(self.fail("singular Jacobian (non-finite Newton step)".into(), &ev));
            }
            // Step cap: a particle on a floppy mode (tether only) with a non-zero net force gets a
            // Newton move of order force/tether, far beyond the range where the linearisation (and
            // the active set) is valid. Scale the whole step so that no centre moves more than
            // MAX_MOVE mean radii per iteration.
            let max_move = (0..n)
                .map(|i| (step[3 * i].powi(2) + step[3 * i + 1].powi(2) + step[3 * i + 2].powi(2)).sqrt())
                .fold(0.0, f64::max);
            if max_move > MAX_MOVE {
                let f = MAX_MOVE / max_move;
                step.iter_mut().for_each(|v| *v *= f);
            }
            let m0 = Self::merit(&ev.res);
            let mut alpha = 1.0;
            // Armijo backtracking for the Newton step; with continuation on, a plain decrease
            // within four halvings (the shifted step is not a descent direction of the merit in general).
            let min_alpha = if sigma > 0.0 { 1.0 / 16.0 } else { 1.0 / 4096.0 };
            let accepted = loop {
                let xt: Vec<Vec3> = (0..n)
                    .map(|i| x[i] + alpha * Vec3::new(step[3 * i], step[3 * i + 1], step[3 * i + 2]))
                    .collect();
                let dt: Vec<f64> = (0..nc).map(|c| delta[c] + alpha * step[3 * n + c]).collect();
                let trial = self.evaluate(&xt, &dt, &adj, false, 0.0);
                let m1 = Self::merit(&trial.res);
                let armijo = if sigma > 0.0 { 1.0 } else { 1.0 - 1e-4 * alpha };
                if m1.is_finite() && m1 < armijo * m0 {
                    break Some((xt, dt, m1));
                }
                alpha *= 0.5;
                if alpha < min_alpha {
                    break None;
                }
            };
            match accepted {
                Some((xt, dt, m1)) => {
                    x = xt;
                    delta = dt;
                    if sigma > 0.0 {
                        sigma *= (m1 / m0).sqrt().max(0.01);
                        if sigma < PTC_OFF {
                            sigma = 0.0;
                        }
                    }
                    ev = self.evaluate(&x, &delta, &adj, true, sigma);
                }
                None => {
                    sigma = if sigma == 0.0 { PTC_START } else { sigma * 10.0 };
                    if sigma > PTC_MAX {
                        let e = self.fail(format!("no descent at Newton iteration {iters}"), &ev);
                        self.store(x, &delta, iters);
                        return Err(e);
                    }
                    ev = self.evaluate(&x, &delta, &adj, true, sigma);
                }
            }
        }
        self.store(x, &delta, iters);
        Ok((iters, ev.force_rel, ev.relation_rel))
    }

    /// Sum over particle s's active contacts of G_s(·,k) P_k at direction `dir` (unit, from s).
    pub(super) fn approach(&self, s: usize, dir: &Vec3, adj: &[Vec<(usize, f64)>], geo: &[Geo]) -> f64 {
        if self.kernel.is_zero() {
            return 0.0;
        }
        adj[s]
            .iter()
            .map(|&(k, sk)| {
                let mu = dir.dot(&(geo[k].e * sk));
                let g = self.bound[s].value(mu);
                g * Self::force_of(&self.contacts[k], self.contacts[k].delta).0
            })
            .sum()
    }

    /// Active-set update after a Newton solve: releases contacts with δ < −tol and adds every
    /// inactive pair or wall contact whose relation would give P ≥ 0 (within tol/2: contacts that
    /// just touch are taken in, so a load can be carried by a contact that is closing right now;
    /// the gap between the two thresholds prevents cycling). Returns whether anything changed.
    pub(super) fn update_active_set(&mut self) -> bool {
        let tol = self.settings.tolerance;
        let before = self.contacts.len();
        self.contacts.retain(|c| c.delta >= -tol);
        let mut changed = self.contacts.len() != before;
        let adj = self.adjacency();
        let geo: Vec<Geo> = self.contacts.iter().map(|c| self.geometry(&self.x, c.i, c.other)).collect();
        let n = self.x.len();
        let mut active_pairs: std::collections::HashSet<(usize, Other)> =
            self.contacts.iter().map(|c| (c.i, c.other)).collect();
        let mut new = Vec::new();
        // Candidate search: the nonlocal growth of a radius is a small fraction of it, so pairs whose
        // gap exceeds 20 % of the smaller radius cannot close.
        for i in 0..n {
            for w in 0..self.walls.len() {
                let other = Other::Wall(w);
                if active_pairs.contains(&(i, other)) {
                    continue;
                }
                let g = self.geometry(&self.x, i, other);
                if g.gamma < -0.2 * self.r[i] {
                    continue;
                }
                let trial = g.gamma - self.approach(i, &g.e, &adj, &geo);
                if trial > -0.5 * tol {
                    new.push(Contact { i, other, delta: trial.max(0.0), k: self.stiffness(i, other) });
                }
            }
            for j in i + 1..n {
                let other = Other::Particle(j);
                if active_pairs.contains(&(i, other)) {
                    continue;
                }
                let v = self.x[j] - self.x[i];
                let reach = self.r[i] + self.r[j];
                let margin = 0.2 * self.r[i].min(self.r[j]);
                if v.x.abs() > reach + margin || v.y.abs() > reach + margin || v.z.abs() > reach + margin {
                    continue;
                }
                let g = self.geometry(&self.x, i, other);
                if g.gamma < -margin || g.d.is_nan() || g.d <= 0.0 {
                    continue;
                }
                let trial =
                    g.gamma - self.approach(i, &g.e, &adj, &geo) - self.approach(j, &(-g.e), &adj, &geo);
                if trial > -0.5 * tol {
                    new.push(Contact { i, other, delta: trial.max(0.0), k: self.stiffness(i, other) });
                }
            }
        }
        for c in new {
            active_pairs.insert((c.i, c.other));
            self.contacts.push(c);
            changed = true;
        }
        changed
    }

    /// Solves the equilibrium at the current wall positions, starting from the current state.
    pub fn solve(&mut self) -> Result<StepStats, SolveError> {
        let mut stats = StepStats::default();
        for c in self.contacts.iter() {
            if !c.k.is_finite() {
                return Err(SolveError {
                    message: "invalid contact stiffness (check the materials)".into(),
                    residual: f64::NAN,
                    worst_particle: Some(self.ids[c.i]),
                });
            }
        }
        // Contacts present in the initial geometry.
        self.update_active_set();
        loop {
            if stats.active_set_rounds >= self.settings.max_active_rounds {
                return Err(SolveError {
                    message: format!("active set did not settle in {} rounds", stats.active_set_rounds),
                    residual: stats.residual,
                    worst_particle: None,
                });
            }
            stats.active_set_rounds += 1;
            // A failed Newton solve leaves its last iterate in place: if that iterate closes or
            // opens contacts, the failure was the active set's, so update it and go on.
            let (it, fr, rr) = match self.newton() {
                Ok(v) => v,
                Err(e) => {
                    if self.update_active_set() {
                        stats.newton_iterations += self.last_iterations;
                        continue;
                    }
                    return Err(e);
                }
            };
            stats.newton_iterations += it;
            stats.residual = fr;
            stats.relation_residual = rr;
            if !self.update_active_set() {
                break;
            }
        }
        assert!(
            stats.residual <= self.settings.tolerance,
            "converged state violates the force-balance tolerance: {}",
            stats.residual
        );
        Ok(stats)
    }
}

//! The implicit time step of the finite-strain MPM (Nezamabadi et al. 2019, Section 4 and App. A)
//! for one body with rigid frictionless planar walls.
//!
//! Within a step the grid carries the configuration at time t: a trial nodal displacement u
//! (Eq. 10: u = Δt v_node(t+Δt), u(t) = 0) moves each material point by the incremental gradient
//! ΔF_p = I + Σ_I u_I ⊗ ∇N_I(x_p), so F_p(t+Δt) = ΔF_p F_p(t). The internal force is written on
//! the initial configuration, f_int,I = −Σ_p V_p⁰ P(F_p) G_Ip with G_Ip = F_p(t)ᵀ ∇N_I(x_p); this
//! equals Eq. 4's −Σ_p G_p σ_p V_p (Eq. 9: σ = P Fᵀ/J, V = J V⁰) and makes the consistent tangent
//! the plain chain rule of ∂P/∂F (App. A, Eq. A.3):
//! K = M/Δt² + Σ_p V_p⁰ G_Ip · A_p · G_Jp.
//!
//! Walls are Moreau's velocity-Signorini condition at grid nodes (Section 2.2, Fig. 2a) written on
//! the step's displacement: a node may close an open gap d > 0 to the wall but not move further,
//! and a node already past the wall plane (d ≤ 0, possible because the grid is reset every step
//! and a node carries mass up to one cell away from the body) may not approach it further:
//! s (u − Δt v_wall) ≥ −max(d, 0), with the reaction f ≥ 0 and complementarity. This is solved
//! exactly by an active set inside the Newton loop; the reaction is −R at a bound dof.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat as FMat;

use super::constitutive::{det, Constitutive, Law, Mat, Tangent};
use super::fbar::{fbar_stiffness, FBarState};
use super::grid::{Grid, Stencil, Vector};
use super::points::Points;

/// One body: its proper grid, its material points and its law.
#[derive(Clone, Debug)]
pub struct Body<const D: usize> {
    pub grid: Grid<D>,
    pub points: Points<D>,
    pub law: Law,
}

impl<const D: usize> Body<D> {
    /// Kinetic plus strain energy, Σ_p ½ m_p |v_p|² + V⁰_p W(F_p) (J, or J/m in 2-D), at the points'
    /// own F (the energy the plain formulation conserves up to the backward-Euler loss).
    pub fn energy(&self) -> Result<f64, super::constitutive::Inverted> {
        let mut w = 0.0;
        for (f, v) in self.points.f.iter().zip(&self.points.vol0) {
            w += v * <Law as Constitutive<D>>::energy(&self.law, f)?;
        }
        Ok(self.points.kinetic_energy() + w)
    }
}

/// A rigid frictionless plane x_axis = position, the body on the side `side` (+1: above/right,
/// −1: below/left), moving along its normal at `velocity`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wall {
    pub axis: usize,
    pub side: f64,
    pub position: f64,
    pub velocity: f64,
}

/// Newton parameters: the two criteria of Eq. 16 and an iteration cap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Newton {
    /// ε₁ on C₁ = ‖Δu^k‖ / max_j ‖Δu^j‖.
    pub eps1: f64,
    /// ε₂ on C₂ = |Δu^k · R^k| / |Δu¹ · R¹|.
    pub eps2: f64,
    pub max_iter: usize,
}

impl Default for Newton {
    fn default() -> Self {
        // Newton converges quadratically: once C₁ < 1e-10 the next iterate is at round-off, so
        // these are the values at which the solution is exact to the digits the tests ask for.
        Self { eps1: 1e-10, eps2: 1e-20, max_iter: 40 }
    }
}

/// Treatment of volumetric locking of nearly incompressible points (λ ≫ μ).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Locking {
    /// Each point's energy at its own F (the plain formulation of the paper).
    #[default]
    None,
    /// F-bar (de Souza Neto, Perić, Dunne & Owen 1996, Int. J. Solids Struct. 33, 3277–3296): the
    /// points of a grid cell share the cell's mean Jacobian J̄ = Σ V⁰J / Σ V⁰, each point's energy is
    /// taken at F̄ = (J̄/J)^{1/D} F, and the Newton tangent is the exact Hessian of that energy.
    FBar,
}

/// How the points' velocities are updated from the grid: FLIP (`flip` = 1, the increment of the
/// nodal velocity, conserves the particle kinetic energy best) blended with PIC (`flip` = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOptions {
    pub dt: f64,
    pub gravity: [f64; 3],
    pub newton: Newton,
    pub flip: f64,
    pub locking: Locking,
}

/// What one step reports.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    pub iterations: usize,
    /// Normal force of each wall on the body, positive when it pushes (N, or N/m in 2-D).
    pub wall_load: Vec<f64>,
    /// Final values of the criteria of Eq. 16.
    pub c1: f64,
    pub c2: f64,
}

/// A Dirichlet condition on one grid dof for this step: node, component, displacement over the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fixed {
    pub node: usize,
    pub comp: usize,
    pub u: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum DofState {
    Free,
    /// At the bound of wall w.
    Wall(usize),
    Fixed(f64),
}

/// Buffers of a step, kept between steps so that the loops do not allocate.
#[derive(Clone, Debug, Default)]
pub struct Workspace<const D: usize> {
    pub(super) stencils: Vec<Stencil<D>>,
    pub(super) node_mass: Vec<f64>,
    pub(super) node_mom: Vec<Vector<D>>,
    /// Grid node → active node (mass > 0) or usize::MAX.
    pub(super) dof_of: Vec<usize>,
    pub(super) active: Vec<usize>,
    pub(super) v_old: Vec<f64>,
    pub(super) u: Vec<f64>,
    pub(super) du: Vec<f64>,
    pub(super) trial: Vec<f64>,
    pub(super) res: Vec<f64>,
    pub(super) fext: Vec<f64>,
    pub(super) mass_dof: Vec<f64>,
    pub(super) lo: Vec<(f64, usize)>,
    pub(super) hi: Vec<(f64, usize)>,
    pub(super) state: Vec<DofState>,
    pub(super) trip: Vec<Triplet<usize, usize, f64>>,
    /// Stress conjugate to the point's own F (P, or P_eff under F-bar).
    pub(super) pk1: Vec<Mat<D>>,
    pub(super) tangent: Vec<Tangent<D>>,
    pub(super) fbar: FBarState<D>,
    /// Body force Σ_p N_p m_p g of the step (Eq. 4); `fext` is this plus the contact forces.
    pub(super) fbody: Vec<f64>,
    /// References of Eq. 16 over the step's Newton iterations (max ‖Δu‖, |Δu¹·R¹|), carried over
    /// warm re-solves: a re-solve starts at the solution of nearly the same problem, and its own
    /// first increment, at the noise floor, is no reference for "converged".
    pub(super) du_ref: f64,
    pub(super) energy_ref: Option<f64>,
    /// LU factorization of the last assembled Newton matrix (the contact solver's compliance).
    pub(super) lu: Option<Lu<usize, f64>>,
}

/// Advances the body by one implicit step of size `opt.dt` (Eqs. 10–16). `step` numbers the step in
/// error messages. Walls are given at time t; the caller moves them afterwards.
pub fn step<const D: usize>(
    body: &mut Body<D>,
    walls: &[Wall],
    fixed: &[Fixed],
    opt: &StepOptions,
    step: usize,
    ws: &mut Workspace<D>,
) -> Result<StepReport, String> {
    prepare(body, walls, fixed, opt, step, ws)?;
    let report = solve(body, walls, opt, step, ws, false)?;
    finish(body, opt, step, ws)?;
    Ok(report)
}

/// First part of a step: shape functions, lumped mass, nodal velocity (Eq. 5), body force, wall
/// bounds and Dirichlet conditions of every grid dof. The contact forces are zero after it.
pub(super) fn prepare<const D: usize>(
    body: &Body<D>,
    walls: &[Wall],
    fixed: &[Fixed],
    opt: &StepOptions,
    step: usize,
    ws: &mut Workspace<D>,
) -> Result<(), String> {
    let dt = opt.dt;
    let grid = &body.grid;
    let pts = &body.points;
    let gravity = Vector::<D>::from_fn(|d, _| opt.gravity[d]);
    // The active dofs are renumbered below: a factorization of the last step no longer applies.
    ws.lu = None;

    // Shape functions of every point; a point outside the grid is an error of the scene or a body
    // that travelled out of its grid.
    ws.stencils.clear();
    for (p, x) in pts.x.iter().enumerate() {
        match grid.stencil(x) {
            Some(s) => ws.stencils.push(s),
            None => {
                return Err(format!(
                    "step {step}: material point {p} at {:?} is outside the grid [{:?}, {:?}]",
                    x.as_slice(),
                    grid.origin.as_slice(),
                    grid.upper().as_slice()
                ))
            }
        }
    }

    // Lumped mass and momentum, nodal velocity by Eq. 5.
    let nn = grid.n_nodes();
    ws.node_mass.clear();
    ws.node_mass.resize(nn, 0.0);
    ws.node_mom.clear();
    ws.node_mom.resize(nn, Vector::<D>::zeros());
    for (p, st) in ws.stencils.iter().enumerate() {
        for c in 0..Stencil::<D>::LEN {
            let w = st.n[c] * pts.mass[p];
            ws.node_mass[st.nodes[c]] += w;
            ws.node_mom[st.nodes[c]] += pts.v[p] * w;
        }
    }
    // Active nodes: every node of a cell holding a point. A point exactly on a cell face (a body
    // translated by whole sub-cells does land there) has N = 0 but ∇N ≠ 0 at the far nodes, so a
    // node may be active with zero mass; its row of K is then the stiffness alone.
    ws.dof_of.clear();
    ws.dof_of.resize(nn, usize::MAX);
    for st in &ws.stencils {
        for c in 0..Stencil::<D>::LEN {
            ws.dof_of[st.nodes[c]] = 0;
        }
    }
    ws.active.clear();
    for i in 0..nn {
        if ws.dof_of[i] != usize::MAX {
            ws.dof_of[i] = ws.active.len();
            ws.active.push(i);
        }
    }
    let na = ws.active.len();
    let ndof = na * D;
    let resize = |v: &mut Vec<f64>| {
        v.clear();
        v.resize(ndof, 0.0);
    };
    resize(&mut ws.v_old);
    resize(&mut ws.u);
    resize(&mut ws.du);
    resize(&mut ws.res);
    resize(&mut ws.fbody);
    resize(&mut ws.mass_dof);
    for (a, &i) in ws.active.iter().enumerate() {
        for d in 0..D {
            let m = ws.node_mass[i];
            ws.v_old[a * D + d] = if m > 0.0 { ws.node_mom[i][d] / m } else { 0.0 };
            ws.mass_dof[a * D + d] = ws.node_mass[i];
        }
    }
    // Body force f_ext = Σ_p N_p m_p g (Eq. 4).
    for (p, st) in ws.stencils.iter().enumerate() {
        for c in 0..Stencil::<D>::LEN {
            let a = ws.dof_of[st.nodes[c]];
            for d in 0..D {
                ws.fbody[a * D + d] += st.n[c] * pts.mass[p] * gravity[d];
            }
        }
    }

    // Bounds of every dof from the walls (tightest one wins) and the Dirichlet conditions.
    ws.lo.clear();
    ws.lo.resize(ndof, (f64::NEG_INFINITY, usize::MAX));
    ws.hi.clear();
    ws.hi.resize(ndof, (f64::INFINITY, usize::MAX));
    for (w, wall) in walls.iter().enumerate() {
        for (a, &i) in ws.active.iter().enumerate() {
            let gap = wall.side * (grid.node_position(i)[wall.axis] - wall.position);
            let bound = wall.velocity * dt - wall.side * gap.max(0.0);
            let k = a * D + wall.axis;
            if wall.side > 0.0 && bound > ws.lo[k].0 {
                ws.lo[k] = (bound, w);
            } else if wall.side < 0.0 && bound < ws.hi[k].0 {
                ws.hi[k] = (bound, w);
            }
        }
    }
    for k in 0..ndof {
        if ws.lo[k].0 > ws.hi[k].0 {
            let node = ws.active[k / D];
            return Err(format!(
                "step {step}: grid node {node} is pinched between walls {} and {} (the gap is thinner than one cell)",
                ws.lo[k].1, ws.hi[k].1
            ));
        }
    }
    ws.state.clear();
    ws.state.resize(ndof, DofState::Free);
    for fx in fixed {
        let a = ws.dof_of[fx.node];
        if a != usize::MAX {
            ws.state[a * D + fx.comp] = DofState::Fixed(fx.u);
        }
    }

    ws.fext.clear();
    ws.fext.extend_from_slice(&ws.fbody);
    ws.du_ref = 0.0;
    ws.energy_ref = None;
    Ok(())
}

/// Solves the step's nonlinear equations (Eqs. 10–16) for the nodal displacement `ws.u` under the
/// current `ws.fext` (body force plus contact forces), the points untouched. With `warm` the
/// previous solution and wall active set are the starting point (the contact iterations re-solve
/// after a small change of the contact forces); otherwise the predictor of the nodal velocities.
pub(super) fn solve<const D: usize>(
    body: &Body<D>,
    walls: &[Wall],
    opt: &StepOptions,
    step: usize,
    ws: &mut Workspace<D>,
    warm: bool,
) -> Result<StepReport, String> {
    let dt = opt.dt;
    let grid = &body.grid;
    let pts = &body.points;
    let np = pts.len();
    let ndof = ws.u.len();
    // Predictor: the nodes keep their velocity, projected on the admissible set.
    for k in 0..ndof {
        if warm {
            if ws.state[k] == DofState::Free {
                clamp(ws, k);
            }
            continue;
        }
        ws.u[k] = dt * ws.v_old[k];
        match ws.state[k] {
            DofState::Fixed(v) => ws.u[k] = v,
            _ => {
                ws.state[k] = DofState::Free;
                clamp(ws, k);
            }
        }
    }

    let mut report = StepReport { wall_load: vec![0.0; walls.len()], ..Default::default() };
    let (mut du_max, mut energy1, mut first) = match (warm, ws.energy_ref) {
        (true, Some(e)) => (ws.du_ref, e, false),
        _ => (0.0, 0.0, true),
    };
    // A node within round-off of its wall bound is on it (displacements are O(h), their
    // round-off O(1e-16 h)).
    let tol = 1e-10 * grid.h;
    ws.pk1.resize(np, Mat::<D>::zeros());
    if opt.locking == Locking::FBar {
        ws.fbar.group(&ws.stencils);
    }
    ws.tangent.resize(np, super::constitutive::zero_tangent::<D>());
    // Active-set strategy: Newton on the equality-constrained problem (bound dofs held at their
    // walls) to convergence, then the Signorini conditions are checked (a free node past its wall
    // is put on it, a bound node whose wall would have to pull is released) and Newton resumes
    // until the set no longer changes.
    for iter in 1..=opt.newton.max_iter {
        evaluate(pts, &body.law, opt.locking, ws, dt, step, iter)?;
        // Projected Newton (Bertsekas): a free node resting on its wall (within round-off) that
        // the residual pushes into the wall is bound for the solve; otherwise the projection of
        // the line-search path would drop part of the increment and what remains need not descend.
        for k in 0..ndof {
            if ws.state[k] == DofState::Free {
                let (lo, hi) = (ws.lo[k], ws.hi[k]);
                let (at_lo, at_hi) = (ws.u[k] <= lo.0 + tol, ws.u[k] >= hi.0 - tol);
                if (at_lo && ws.res[k] < 0.0) || (at_hi && ws.res[k] > 0.0) {
                    ws.u[k] = if at_lo { lo.0 } else { hi.0 };
                    ws.state[k] = DofState::Wall(if at_lo { lo.1 } else { hi.1 });
                }
            }
        }
        // A residual already at round-off of the forces (a body in free flight, or a warm start
        // at the solution) is converged: a Newton increment would be noise and the line search
        // could find no decrease along it.
        let fscale = force_scale(pts, &body.law, ws, dt);
        let r0: f64 =
            (0..ndof).filter(|&k| ws.state[k] == DofState::Free).map(|k| ws.res[k] * ws.res[k]).sum();
        let converged = if r0.sqrt() <= ROUNDOFF * fscale * (ndof as f64).sqrt() {
            report.iterations = iter;
            true
        } else {
            // Globalisation: the backward-Euler step (Eqs. 10–12) is the minimiser of the incremental
            // potential Π(u) = |u − Δt v|²_M /(2Δt²) + Σ_p V_p⁰ W(F_p(u)) − f_ext·u, whose gradient is
            // −R. A full Newton increment of a large step can overshoot (or invert a point, where the
            // laws are undefined): halve it until Π decreases (Armijo).
            //
            // The increment must descend (Δu·R > 0). Neo-Hookean W is polyconvex, not convex in F,
            // so a strongly sheared point can make the tangent indefinite and the increment point
            // uphill; the search then accepts only tiny steps along a poor direction (measured:
            // the 12-disc compaction at step 1128, a node of 3.6e-8 kg/m under a contact force of
            // 1.9 N/m, Δu·R < 0 for 35 iterations at α = 1/32 and |R| stuck near 2 N/m until the
            // iteration limit). Modified Newton: the inertia diagonal is raised, (1 + s) M/Δt² with
            // s = 1/64, 1/16, …, until the increment descends; as s grows the increment turns into the
            // mass-scaled gradient Δt² R/((1 + s) m), which always descends. F-bar has its own
            // remedy (see `descending_increment`). A descending increment (every step of every scene but this kind) is
            // solved once, unshifted.
            let (slope, shift) = descending_increment(pts, opt.locking, ws, dt, step).map_err(|e| {
                format!("step {step}, Newton iteration {iter}: {e} (|R| = {:.3e})", r0.sqrt())
            })?;
            let (pi0, pi_scale) =
            potential(pts, &body.law, opt.locking, ws, dt, false).ok_or_else(|| {
            format!("step {step}, Newton iteration {iter}: a material point is inverted (J ≤ 0) after the wall projection; reduce Δt or refine the grid")
        })?;
            let mut alpha = 1.0;
            let mut gradient = false;
            let mut inverted = false;
            loop {
                // The trial point is projected onto the walls: a free node never passes its wall
                // along the search, so the active-set snap before the next solve moves nodes by
                // round-off only and the residual stays that of the position (an unprojected
                // search carried nodes past their walls; the snap then made the residual stale
                // and stopped a compaction at Φ = 0.71). Armijo on the projected step.
                ws.trial.clear();
                let mut pred = 0.0;
                for k in 0..ndof {
                    let mut t = ws.u[k] + alpha * ws.du[k];
                    if ws.state[k] == DofState::Free {
                        t = t.max(ws.lo[k].0).min(ws.hi[k].0);
                        pred += ws.res[k] * (t - ws.u[k]);
                    }
                    ws.trial.push(t);
                }
                match potential(pts, &body.law, opt.locking, ws, dt, true) {
                    Some((pi, _)) if pi <= pi0 - 1e-4 * pred.max(0.0) + PI_ROUNDOFF * pi_scale => break,
                    Some(_) => alpha *= 0.5,
                    None => {
                        inverted = true;
                        alpha *= 0.5
                    }
                }
                if alpha < 1e-8 {
                    if gradient {
                        let why = if inverted {
                            "a material point inverts (J ≤ 0) along both"
                        } else {
                            "the incremental potential does not decrease along either"
                        };
                        return Err(format!(
                            "step {step}, Newton iteration {iter}: line search failed: {why} the Newton increment and the gradient (|R| = {:.3e} against a force scale {fscale:.3e}); refine the grid or reduce Δt",
                            r0.sqrt()
                        ));
                    }
                    // The increment descends at α = 0 (`descending_increment`) yet no halving
                    // decreases Π: points invert along it, or the decrease is below round-off.
                    // The mass-scaled gradient Δt² R/m always descends (−R is ∇Π, M > 0), so this
                    // iteration takes it and Newton resumes from the better point. (The compaction
                    // stop at Φ = 0.71 that first led here was a stale residual, cured by the
                    // projected search above; no scene is yet known to need this.)
                    for k in 0..ndof {
                        ws.du[k] = if ws.state[k] == DofState::Free && ws.mass_dof[k] > 0.0 {
                            ws.res[k] * dt * dt / ws.mass_dof[k]
                        } else {
                            0.0
                        };
                    }
                    // A node of little mass would take a huge step: the direction is scaled so
                    // that no node moves by more than a tenth of a cell.
                    let big = ws.du.iter().fold(0.0f64, |m, d| m.max(d.abs()));
                    if big > 0.1 * grid.h {
                        let f = 0.1 * grid.h / big;
                        ws.du.iter_mut().for_each(|d| *d *= f);
                    }
                    gradient = true;
                    alpha = 1.0;
                }
            }
            for k in 0..ndof {
                ws.du[k] = ws.trial[k] - ws.u[k];
            }
            // Eq. 16 on the free dofs.
            let mut norm = 0.0;
            let mut energy = 0.0;
            for k in 0..ndof {
                if ws.state[k] == DofState::Free {
                    norm += ws.du[k] * ws.du[k];
                    energy += ws.du[k] * ws.res[k];
                }
            }
            let norm = norm.sqrt();
            du_max = du_max.max(norm);
            if first {
                energy1 = energy.abs();
                first = false;
            }
            let c1 = if du_max > 0.0 { norm / du_max } else { 0.0 };
            let c2 = if energy1 > 0.0 { energy.abs() / energy1 } else { 0.0 };
            report.c1 = c1;
            report.c2 = c2;
            report.iterations = iter;
            for k in 0..ndof {
                ws.u[k] += ws.du[k];
            }
            // A residual at round-off of the forces makes both ratios meaningless (their references
            // can vanish, e.g. a body at rest): that is convergence too.
            let at_roundoff = r0.sqrt() <= ROUNDOFF * fscale * (ndof as f64).sqrt();
            if std::env::var_os("MCDEM_MPM_TRACE").is_some() {
                let nb = ws.state.iter().filter(|s| **s != DofState::Free).count();
                // The largest increment, where a stall usually sits: its dof's mass, state, gaps to
                // its wall bounds and contact force (external force beyond the body force). One
                // line per iteration: the bodies are solved in parallel.
                let k = (0..ndof).fold(0, |m, k| if ws.du[k].abs() > ws.du[m].abs() { k } else { m });
                eprintln!(
                    "  step {step} newton {iter}: C1 {c1:.3e} C2 {c2:.3e} |R| {:.3e} scale {fscale:.3e} alpha {alpha} bound {nb} shift {shift}; largest |du| {:.3e} h at dof {k}: mass {:.3e} {:?} gaps {:.3e} {:.3e} contact {:.3e} slope {slope:.3e}",
                    r0.sqrt(),
                    ws.du[k].abs() / grid.h,
                    ws.mass_dof[k],
                    ws.state[k],
                    ws.u[k] - ws.lo[k].0,
                    ws.hi[k].0 - ws.u[k],
                    ws.fext[k] - ws.fbody[k]
                );
            }
            (c1 < opt.newton.eps1 && c2 < opt.newton.eps2) || at_roundoff
        };
        if !converged {
            continue;
        }
        // Converged for this active set: check the Signorini conditions.
        let mut changed = false;
        for k in 0..ndof {
            if ws.state[k] == DofState::Free && clamp(ws, k) {
                changed = true;
            }
        }
        evaluate(pts, &body.law, opt.locking, ws, dt, step, iter)?;
        for k in 0..ndof {
            if let DofState::Wall(w) = ws.state[k] {
                // Reaction −R; released only when it pulls beyond the residual's round-off.
                if walls[w].side * -ws.res[k] < -1e-12 * fscale {
                    ws.state[k] = DofState::Free;
                    changed = true;
                }
            }
        }
        if changed {
            du_max = 0.0;
            first = true;
            continue;
        }
        for k in 0..ndof {
            if let DofState::Wall(w) = ws.state[k] {
                report.wall_load[w] += walls[w].side * -ws.res[k];
            }
        }
        if !first {
            ws.du_ref = du_max;
            ws.energy_ref = Some(energy1);
        }
        return Ok(report);
    }
    Err(format!(
        "step {step}: Newton did not converge in {} iterations: C1 = {:.3e} (ε1 = {:.1e}), C2 = {:.3e} (ε2 = {:.1e}) (Eq. 16)",
        opt.newton.max_iter, report.c1, opt.newton.eps1, report.c2, opt.newton.eps2
    ))
}

/// Last part of a step: moves the points with the converged grid motion of `solve`.
pub(super) fn finish<const D: usize>(
    body: &mut Body<D>,
    opt: &StepOptions,
    step: usize,
    ws: &Workspace<D>,
) -> Result<(), String> {
    update_points(&mut body.points, &body.law, opt.locking, ws, opt.dt, opt.flip, step)
}

/// Relative round-off of the incremental potential against the magnitude `potential` reports (a
/// few ulps: each point's energy is a short sum of O(1) invariants times the moduli).
const PI_ROUNDOFF: f64 = 4.0 * f64::EPSILON;

/// Relative size of the round-off of a sum of forces of magnitude `force_scale` (a few hundred
/// ulps: the residual adds O(10) terms per dof, each with its own round-off).
const ROUNDOFF: f64 = 1e-13;

/// The Newton increment into `ws.du` with its slope Δu·R over the free dofs and the shift it took:
/// the increment of M/Δt² + K when it descends (slope > 0); otherwise, under F-bar, its opposite,
/// and without, that of (1 + s) M/Δt² + K with the smallest s of 1/64, 1/16, … that descends (see
/// `solve` for why).
fn descending_increment<const D: usize>(
    pts: &Points<D>,
    locking: Locking,
    ws: &mut Workspace<D>,
    dt: f64,
    step: usize,
) -> Result<(f64, f64), String> {
    let free_slope = |ws: &Workspace<D>| -> f64 {
        (0..ws.du.len()).filter(|&k| ws.state[k] == DofState::Free).map(|k| ws.du[k] * ws.res[k]).sum()
    };
    assemble_and_solve(pts, locking, ws, dt, step, 0.0)?;
    let mut slope = free_slope(ws);
    // The F-bar energy is not convex in u even where W(F) is (J̄/J couples the points of a cell),
    // so far from the solution K can be indefinite and the increment point uphill (Δu·R < 0 while
    // −R is the gradient of Π); its opposite then descends.
    if locking == Locking::FBar && slope < 0.0 {
        for k in 0..ws.du.len() {
            if ws.state[k] == DofState::Free {
                ws.du[k] = -ws.du[k];
            }
        }
        slope = -slope;
    }
    let mut shift = 0.0;
    while locking == Locking::None && slope <= 0.0 {
        shift = if shift == 0.0 { 1.0 / 64.0 } else { 4.0 * shift };
        if shift > 1e12 {
            return Err("no descent direction even with the inertia raised 1e12 times".into());
        }
        assemble_and_solve(pts, locking, ws, dt, step, shift)?;
        slope = free_slope(ws);
    }
    Ok((slope, shift))
}

/// The largest force term of the residual (inertia, external, internal): the scale of its
/// round-off.
fn force_scale<const D: usize>(pts: &Points<D>, law: &Law, ws: &Workspace<D>, dt: f64) -> f64 {
    let mut fscale: f64 = 0.0;
    for k in 0..ws.u.len() {
        fscale = fscale.max(ws.mass_dof[k] * (ws.u[k] / (dt * dt)).abs()).max(ws.fext[k].abs());
    }
    fscale.max(internal_force_scale(pts, law, ws))
}

/// The incremental potential Π of the step (see `step`) at `ws.u` (or `ws.trial` when `trial`),
/// with the magnitude of what is summed to compute it (the scale of its round-off); `None` when a
/// point inverts there.
///
/// The magnitude counts the terms before they cancel, not the result: the kinetic term
/// |u − Δt v|² is computed from u and Δt v, and W(F) from invariants of order one times the moduli
/// (tr C − D, ln J, …), so a point carries round-off of ε V₀ (λ + 2μ) D however small its strain
/// energy. Near the solution of a step the Newton increment's predicted decrease of Π falls below
/// that noise, and a line search that ignores it halves α for ever (measured: a discs' collision
/// where the increment was 3.5e-12 m, its predicted decrease 2e-16 J/m and the noise of Π 2e-15
/// J/m, so Newton stalled with |R| at 1e-6 of the force scale).
fn potential<const D: usize>(
    pts: &Points<D>,
    law: &Law,
    locking: Locking,
    ws: &Workspace<D>,
    dt: f64,
    trial: bool,
) -> Option<(f64, f64)> {
    let u = if trial { &ws.trial } else { &ws.u };
    let mut pi = 0.0;
    let mut scale = 0.0;
    for k in 0..u.len() {
        let kin = 0.5 * ws.mass_dof[k] * (u[k] - dt * ws.v_old[k]).powi(2) / (dt * dt);
        pi += kin - ws.fext[k] * u[k];
        scale += 0.5 * ws.mass_dof[k] * (u[k].powi(2) + (dt * ws.v_old[k]).powi(2)) / (dt * dt)
            + (ws.fext[k] * u[k]).abs();
    }
    let (lambda, mu) = law.lame();
    scale += pts.vol0.iter().sum::<f64>() * (lambda.abs() + 2.0 * mu.abs()) * D as f64;
    match locking {
        Locking::None => {
            for (p, st) in ws.stencils.iter().enumerate() {
                let f = incremental_gradient(st, &ws.dof_of, u) * pts.f[p];
                pi += pts.vol0[p] * law.energy(&f).ok()?;
            }
        }
        Locking::FBar => {
            let fb = &ws.fbar;
            let grad = |p: usize| incremental_gradient(&ws.stencils[p], &ws.dof_of, u) * pts.f[p];
            for c in 0..fb.start.len() - 1 {
                let cell = &fb.order[fb.start[c]..fb.start[c + 1]];
                let (mut v, mut vj) = (0.0, 0.0);
                for &p in cell {
                    let j = det(&grad(p));
                    if j <= 0.0 {
                        return None;
                    }
                    v += pts.vol0[p];
                    vj += pts.vol0[p] * j;
                }
                let jbar = vj / v;
                for &p in cell {
                    let f = grad(p);
                    let fbar = f * (jbar / det(&f)).powf(1.0 / D as f64);
                    pi += pts.vol0[p] * law.energy(&fbar).ok()?;
                }
            }
        }
    }
    Some((pi, scale))
}

/// Projects dof k onto its wall bounds; true when it was on or past one (the bound becomes active).
fn clamp<const D: usize>(ws: &mut Workspace<D>, k: usize) -> bool {
    if ws.u[k] <= ws.lo[k].0 {
        ws.u[k] = ws.lo[k].0;
        ws.state[k] = DofState::Wall(ws.lo[k].1);
        true
    } else if ws.u[k] >= ws.hi[k].0 {
        ws.u[k] = ws.hi[k].0;
        ws.state[k] = DofState::Wall(ws.hi[k].1);
        true
    } else {
        false
    }
}

/// ΔF_p = I + Σ_I u_I ⊗ ∇N_I(x_p).
pub(super) fn incremental_gradient<const D: usize>(st: &Stencil<D>, dof_of: &[usize], u: &[f64]) -> Mat<D> {
    let mut df = Mat::<D>::identity();
    for c in 0..Stencil::<D>::LEN {
        let a = dof_of[st.nodes[c]];
        for i in 0..D {
            for j in 0..D {
                df[(i, j)] += u[a * D + i] * st.grad[c][j];
            }
        }
    }
    df
}

/// Stress and tangent at the trial displacement; residual R = f_ext + f_int − M a (Eq. A.4) with
/// a from Eq. 12.
fn evaluate<const D: usize>(
    pts: &Points<D>,
    law: &Law,
    locking: Locking,
    ws: &mut Workspace<D>,
    dt: f64,
    step: usize,
    iter: usize,
) -> Result<(), String> {
    for k in 0..ws.res.len() {
        let acc = ws.u[k] / (dt * dt) - ws.v_old[k] / dt;
        ws.res[k] = ws.fext[k] - ws.mass_dof[k] * acc;
    }
    let inverted = |p: usize, j: f64| {
        format!(
            "step {step}, Newton iteration {iter}: material point {p} inverted (J = {j:.3e}); reduce Δt or refine the grid"
        )
    };
    match locking {
        Locking::None => {
            for (p, st) in ws.stencils.iter().enumerate() {
                let f = incremental_gradient(st, &ws.dof_of, &ws.u) * pts.f[p];
                let (pk1, a) = law.pk1_tangent(&f).map_err(|e| inverted(p, e.det))?;
                ws.pk1[p] = pk1;
                ws.tangent[p] = a;
            }
        }
        Locking::FBar => {
            let fb = &mut ws.fbar;
            fb.kinematics(pts, &ws.stencils, &ws.dof_of, &ws.u).map_err(|(p, j)| inverted(p, j))?;
            // δ(V⁰W(F̄)) summed over a cell = Σ_p V⁰_p P_eff,p : δF_p with (from δF̄ = s δF +
            // F̄ (δJ̄/J̄ − δJ/J)/D, δJ = J F⁻ᵀ : δF)
            // P_eff = s P̄ + F⁻ᵀ (τ̄ J/J̄ − τ), τ = P̄ : F̄ / D, τ̄ the cell's V⁰-mean of τ.
            for c in 0..fb.start.len() - 1 {
                let mut vt = 0.0;
                for &p in &fb.order[fb.start[c]..fb.start[c + 1]] {
                    let (pb, a) = law.pk1_tangent(&fb.fb[p]).map_err(|e| inverted(p, e.det))?;
                    fb.pb[p] = pb;
                    fb.tau[p] = pb.dot(&fb.fb[p]) / D as f64;
                    fb.finv_t[p] = super::constitutive::inverse(&fb.f[p]).transpose();
                    ws.tangent[p] = a;
                    vt += pts.vol0[p] * fb.tau[p];
                }
                fb.taubar[c] = vt / fb.vol0[c];
                for &p in &fb.order[fb.start[c]..fb.start[c + 1]] {
                    ws.pk1[p] =
                        fb.pb[p] * fb.s[p] + fb.finv_t[p] * (fb.taubar[c] * fb.j[p] / fb.jbar[c] - fb.tau[p]);
                }
            }
        }
    }
    for (p, st) in ws.stencils.iter().enumerate() {
        let pk1 = ws.pk1[p];
        for c in 0..Stencil::<D>::LEN {
            let g = pts.f[p].transpose() * st.grad[c];
            let fi = pk1 * g * pts.vol0[p];
            let a = ws.dof_of[st.nodes[c]];
            for i in 0..D {
                ws.res[a * D + i] -= fi[i];
            }
        }
    }
    Ok(())
}

/// Largest nodal contribution of the internal force, the scale of the residual's round-off.
///
/// The stress enters with the magnitude of its terms before they cancel: P(F) is computed from
/// terms of order (λ + 2μ)|F| (μF, μF⁻ᵀ, λ ln J F⁻ᵀ) whose sum is small under small strain, so
/// its round-off is ε (λ + 2μ) however small the stress (measured: a block resting under gravity,
/// stresses of 20 Pa against moduli of 1 MPa, whose residual stalled at 5e-10 of the gravity
/// load, i.e. at ε (λ + 2μ) V₀ |∇N|).
fn internal_force_scale<const D: usize>(pts: &Points<D>, law: &Law, ws: &Workspace<D>) -> f64 {
    let (lambda, mu) = law.lame();
    let modulus = lambda.abs() + 2.0 * mu.abs();
    let mut s: f64 = 0.0;
    for (p, st) in ws.stencils.iter().enumerate() {
        let stress = ws.pk1[p].norm().max(modulus * pts.f[p].norm());
        for c in 0..Stencil::<D>::LEN {
            let g = pts.f[p].transpose() * st.grad[c];
            s = s.max(stress * g.norm() * pts.vol0[p]);
        }
    }
    s
}

/// Builds K = M/Δt² + Σ_p V_p⁰ G·A·G (Eq. A.3) with the bound dofs' rows replaced by identity, and
/// solves K Δu = R (Eq. 15); bound dofs get Δu = their target − u. `shift` raises the inertia
/// term as in [`factorize`].
fn assemble_and_solve<const D: usize>(
    pts: &Points<D>,
    locking: Locking,
    ws: &mut Workspace<D>,
    dt: f64,
    step: usize,
    shift: f64,
) -> Result<(), String> {
    factorize(pts, locking, ws, dt, step, shift)?;
    let ndof = ws.res.len();
    let lu = ws.lu.as_ref().expect("factorized above");
    let mut rhs = FMat::<f64>::from_fn(ndof, 1, |r, _| match ws.state[r] {
        DofState::Free => ws.res[r],
        DofState::Fixed(v) => v - ws.u[r],
        DofState::Wall(_) => 0.0,
    });
    lu.solve_in_place(rhs.as_mut());
    for r in 0..ndof {
        ws.du[r] = rhs[(r, 0)];
        if !ws.du[r].is_finite() {
            return Err(format!("step {step}: singular stiffness matrix (non-finite Newton increment)"));
        }
    }
    Ok(())
}

/// Compliance of the body at its current state and active set: for each dof in `dofs`, the
/// displacement of every dof in `dofs` under a unit force on it, row-major in `out`
/// (|dofs|² entries), from the factorization of the last assembled tangent M/Δt² + K. Bound and
/// prescribed dofs do not move (their rows are identities with zero right-hand side), so their
/// rows and columns are zero. This is the body's block of the Delassus operator of Contact Dynamics.
pub(super) fn compliance<const D: usize>(ws: &Workspace<D>, dofs: &[usize], out: &mut Vec<f64>) {
    let m = dofs.len();
    out.clear();
    out.resize(m * m, 0.0);
    let Some(lu) = ws.lu.as_ref() else { return };
    let ndof = ws.res.len();
    let free = |k: usize| ws.state[k] == DofState::Free;
    let mut rhs = FMat::<f64>::zeros(ndof, m);
    for (j, &k) in dofs.iter().enumerate() {
        if free(k) {
            rhs[(k, j)] = 1.0;
        }
    }
    lu.solve_in_place(rhs.as_mut());
    for (j, &kj) in dofs.iter().enumerate() {
        for (i, &ki) in dofs.iter().enumerate() {
            if free(ki) && free(kj) {
                out[i * m + j] = rhs[(ki, j)];
            }
        }
    }
}

/// Assembles the Newton matrix (1 + shift) M/Δt² + K at the current state (identity rows for bound
/// and prescribed dofs) and keeps its sparse LU factorization in `ws.lu`. Shift 0 is the tangent
/// itself; a positive shift is the modified Newton matrix of `descending_increment`.
pub(super) fn factorize<const D: usize>(
    pts: &Points<D>,
    locking: Locking,
    ws: &mut Workspace<D>,
    dt: f64,
    step: usize,
    shift: f64,
) -> Result<(), String> {
    let ndof = ws.res.len();
    ws.trip.clear();
    for k in 0..ndof {
        if ws.state[k] == DofState::Free {
            ws.trip.push(Triplet::new(k, k, (1.0 + shift) * ws.mass_dof[k] / (dt * dt)));
        } else {
            ws.trip.push(Triplet::new(k, k, 1.0));
        }
    }
    let n = Stencil::<D>::LEN;
    if locking == Locking::FBar {
        fbar_stiffness(pts, ws);
    }
    for (p, st) in ws.stencils.iter().enumerate() {
        if locking == Locking::FBar {
            break;
        }
        let a4 = &ws.tangent[p];
        let ft = pts.f[p].transpose();
        for ca in 0..n {
            let ga = ft * st.grad[ca];
            let ra = ws.dof_of[st.nodes[ca]];
            for cb in 0..n {
                let gb = ft * st.grad[cb];
                let rb = ws.dof_of[st.nodes[cb]];
                for i in 0..D {
                    let row = ra * D + i;
                    if ws.state[row] != DofState::Free {
                        continue;
                    }
                    for k in 0..D {
                        let mut v = 0.0;
                        for aa in 0..D {
                            for bb in 0..D {
                                v += ga[aa] * a4[i][aa][k][bb] * gb[bb];
                            }
                        }
                        ws.trip.push(Triplet::new(row, rb * D + k, v * pts.vol0[p]));
                    }
                }
            }
        }
    }
    let k = SparseColMat::<usize, f64>::try_new_from_triplets(ndof, ndof, &ws.trip)
        .map_err(|e| format!("step {step}: cannot assemble the stiffness matrix: {e:?}"))?;
    let sym = SymbolicLu::try_new(k.symbolic())
        .map_err(|e| format!("step {step}: sparse LU (symbolic) failed: {e:?}"))?;
    let lu = Lu::try_new_with_symbolic(sym, k.as_ref())
        .map_err(|e| format!("step {step}: sparse LU failed: {e:?}"))?;
    ws.lu = Some(lu);
    Ok(())
}

/// Moves the points with the converged grid motion: x += Σ N u, v by FLIP/PIC, F = ΔF F,
/// V = J V⁰ (Eq. 13), σ = P Fᵀ / J (Eq. 9).
fn update_points<const D: usize>(
    pts: &mut Points<D>,
    law: &Law,
    locking: Locking,
    ws: &Workspace<D>,
    dt: f64,
    flip: f64,
    step: usize,
) -> Result<(), String> {
    for (p, st) in ws.stencils.iter().enumerate() {
        let mut dx = Vector::<D>::zeros();
        let mut v_new = Vector::<D>::zeros();
        let mut dv = Vector::<D>::zeros();
        for c in 0..Stencil::<D>::LEN {
            let a = ws.dof_of[st.nodes[c]];
            for d in 0..D {
                let u = ws.u[a * D + d];
                dx[d] += st.n[c] * u;
                v_new[d] += st.n[c] * u / dt;
                dv[d] += st.n[c] * (u / dt - ws.v_old[a * D + d]);
            }
        }
        let f = incremental_gradient(st, &ws.dof_of, &ws.u) * pts.f[p];
        let j = det(&f);
        // The points keep their own F (F-bar is recomputed from it every step, in the cells that
        // then hold them); the stress is the one the energy was taken at, σ = P(F̄) F̄ᵀ / J̄.
        let fs = match locking {
            Locking::None => f,
            Locking::FBar => ws.fbar.fb[p],
        };
        let pk1 = law
            .pk1(&fs)
            .map_err(|e| format!("step {step}: material point {p} inverted (J = {:.3e})", e.det))?;
        pts.x[p] += dx;
        pts.v[p] = (pts.v[p] + dv) * flip + v_new * (1.0 - flip);
        pts.f[p] = f;
        pts.vol[p] = j * pts.vol0[p];
        pts.sigma[p] = pk1 * fs.transpose() / det(&fs);
    }
    Ok(())
}

#[cfg(test)]
#[path = "implicit_tests.rs"]
mod tests;

//! Rigid walls acting on the material points' domains rather than on grid nodes (scene option
//! `"walls_on": "points"`).
//!
//! Why: with the nodal condition of Section 2.2 (Nezamabadi et al. 2019, Fig. 2a) a body's material
//! lies up to a cell past a wall (the paper's "gap of one element", Fig. 8), which keeps the disc
//! between plates from converging under refinement and lets a compaction reach Φ > 1 (docs/mpm.md).
//!
//! Constraint. Each point p carries the domain of its lattice sub-cell, a square (cube) of side
//! l_p = (V_p⁰)^{1/D} in the reference configuration, mapped by the point's own affine motion
//! x(X) = x_p + F_p (X − X_p) (the map the MPM uses at the point). The domain is convex, so it stays
//! on the body's side of a plane when its 2^D corners c (±l_p/2 along each axis) do: all are
//! constrained, since a point that has turned (a rolling disc) brings other corners towards the
//! wall; the ones facing away are inactive and cost only their gap. With the step's nodal
//! displacement u (F = ΔF(u) F(t), ΔF = I + Σ u_I ⊗ ∇N_I) the corner's gap to the wall at the end
//! of the step is **linear** in u:
//!
//!   g_c(u) = s (x_p + F(t) c + Σ_I w_I u_I − x_wall(t + Δt))_a,  w_I = N_I(x_p) + ∇N_I(x_p)·F(t)c,
//!
//! (Σ_I w_I = 1: a rigid translation moves the corner with it) and the condition is g_c ≥ 0.
//!
//! Enforcement: augmented Lagrangian (Powell–Hestenes–Rockafellar; e.g. Wriggers, Computational
//! Contact Mechanics, 2nd ed. 2006, Sect. 6.3.3) inside the Newton loop on the incremental
//! potential: Π gains Σ_c ψ(g_c) with ψ(g) = −λ g + κ g²/2 while λ − κ g > 0 and −λ²/(2κ)
//! otherwise (C¹; dψ/dg = −r, r = max(0, λ − κ g) the corner's reaction, pushing the body along
//! s e_a). The residual gains r_c w_I s e_a, the tangent κ Σ_c w_I w_J (e_a ⊗ e_a) for corners with
//! r_c > 0. After Newton converges the multipliers are updated (Uzawa, λ ← r) and Newton resumes,
//! until no corner's reaction changes by more than κ · `GAP_TOL` h, i.e. no corner is past its
//! wall, or open while pushing, by more than `GAP_TOL` h. The wall's load is Σ_c r_c.
//!
//! Penalty κ (per corner): β (λ + 2μ) A_c / l_p with A_c = l_p^{D−1} / 2^{D−1} the share of the
//! point's face carried by each of the 2^{D−1} corners facing a wall: (λ + 2μ) A_c / l_p is the uniaxial-strain stiffness of the
//! point's own column of material under that share of its face, the stiffness the body itself
//! offers there. A Uzawa update divides an isolated corner's violation by about 1 + β; several
//! corners acting on the same few nodes (2^{D−1} per point, 2 points per cell and axis) are nearly
//! redundant, and their combinations converge much more slowly, at 1/(1 + β c) with c ≪ 1 (measured
//! on scene 2, h = 1 mm: 0.69 per update at β = 100, 30 updates not enough to reach 1e-9 h at
//! step 26). β = 1000 passes every step of scene 2 in 3–7 updates and raises the conditioning of
//! the Newton matrix by about 10³, harmless for its sparse LU. The converged answer does not depend
//! on κ (the multipliers carry the load), only the cost.
//!
//! Frictionless only: wall friction in this mode stops the scene setup with a message.

use super::{DofState, Workspace};
use crate::mpm::constitutive::Law;
use crate::mpm::grid::Stencil;
use crate::mpm::points::Points;

use super::Wall;

/// Penalty factor β of κ over the material's own stiffness at the point (module doc).
const BETA: f64 = 1000.0;

/// Uzawa stop: no corner past its wall (or open while pushing) by more than this many cells. The
/// tests ask 1e-6 relative on a plate load of a 4-cell block at 5 % strain: a violation δ changes
/// the strain by δ/(4h), i.e. the load by δ/(0.2 h) relative, 5e-8 at this tolerance.
const GAP_TOL: f64 = 1e-8;

/// After this many updates in one solve a violation below `LOOSE_GAP_TOL` h is accepted.
const SLOW_UZAWA: usize = 20;

/// The tolerance accepted after `SLOW_UZAWA` updates: 1e-6 of a cell, orders below the
/// discretisation error of the scenes (a plate load changes by about this fraction of a cell's
/// strain).
const LOOSE_GAP_TOL: f64 = 1e-6;

/// Multiplier updates allowed in one solve before it stops with an error (each divides the largest
/// violation by about 1 + β; 30 is far beyond what a violation of a cell needs).
const MAX_UZAWA: usize = 50;

/// The corner constraints of one step and their multipliers.
#[derive(Clone, Debug, Default)]
pub(in crate::mpm) struct PointWalls {
    /// Whether the walls act on the points in this step (else this is empty and unused).
    pub enabled: bool,
    /// Per constraint, `LEN` entries: the dof (node's dof index · D + wall axis) and s w_I.
    dofs: Vec<usize>,
    w: Vec<f64>,
    /// Gap at u = 0, penalty κ, wall index.
    g0: Vec<f64>,
    kappa: Vec<f64>,
    wall: Vec<usize>,
    /// Multipliers λ, kept between steps as the start of the next step's updates: the constraint
    /// of point p, wall w, corner c is (w · n_p + p) · 2^D + c, the same every step.
    lambda: Vec<f64>,
    /// Uzawa updates in the current solve (reset at the start of each Newton solve).
    pub updates: usize,
    /// Cell size, for the tolerance.
    h: f64,
}

impl PointWalls {
    fn len(&self) -> usize {
        self.g0.len()
    }

    /// Gap of constraint i at displacement u.
    fn gap(&self, i: usize, len: usize, u: &[f64]) -> f64 {
        let mut g = self.g0[i];
        for k in i * len..(i + 1) * len {
            g += self.w[k] * u[self.dofs[k]];
        }
        g
    }

    /// Reaction of constraint i at displacement u: r = max(0, λ − κ g).
    fn reaction(&self, i: usize, len: usize, u: &[f64]) -> f64 {
        (self.lambda[i] - self.kappa[i] * self.gap(i, len, u)).max(0.0)
    }
}

/// Builds the corner constraints of the step (module doc) from the points at time t and the walls
/// at t (each moved to t + Δt for the gap). Keeps the multipliers of the last step when the
/// constraint set has the same size, otherwise starts them at zero.
pub(super) fn prepare<const D: usize>(
    pts: &Points<D>,
    law: &Law,
    walls: &[Wall],
    dt: f64,
    h: f64,
    ws: &mut Workspace<D>,
) {
    let len = Stencil::<D>::LEN;
    let nc = 1usize << D;
    let np = pts.len();
    let (lambda, mu) = law.lame();
    let modulus = lambda + 2.0 * mu;
    let pw = &mut ws.pw;
    pw.enabled = true;
    pw.h = h;
    pw.updates = 0;
    pw.dofs.clear();
    pw.w.clear();
    pw.g0.clear();
    pw.kappa.clear();
    pw.wall.clear();
    let n = walls.len() * np * nc;
    if pw.lambda.len() != n {
        pw.lambda.clear();
        pw.lambda.resize(n, 0.0);
    }
    for (wi, wall) in walls.iter().enumerate() {
        let (a, s) = (wall.axis, wall.side);
        let xw = wall.position + wall.velocity * dt;
        for p in 0..np {
            let st = &ws.stencils[p];
            let l = pts.vol0[p].powf(1.0 / D as f64);
            let half = 0.5 * l;
            // The face's share of each of the 2^{D−1} corners facing the wall.
            let kappa = BETA * modulus * l.powi(D as i32 - 1) / (nc / 2) as f64 / l;
            for c in 0..nc {
                // Reference corner: ±l/2 along each axis (bit d of c).
                let corner =
                    crate::mpm::grid::Vector::<D>::from_fn(
                        |d, _| {
                            if (c >> d) & 1 == 1 {
                                half
                            } else {
                                -half
                            }
                        },
                    );
                let delta = pts.f[p] * corner;
                pw.g0.push(s * (pts.x[p][a] + delta[a] - xw));
                for k in 0..len {
                    pw.dofs.push(ws.dof_of[st.nodes[k]] * D + a);
                    pw.w.push(s * (st.n[k] + st.grad[k].dot(&delta)));
                }
                pw.kappa.push(kappa);
                pw.wall.push(wi);
            }
        }
    }
}

/// Adds the corners' reactions to the residual R at `ws.u` (R = −∂Π/∂u: r w_I s at the wall axis).
pub(super) fn add_residual<const D: usize>(ws: &mut Workspace<D>) {
    let len = Stencil::<D>::LEN;
    let pw = &ws.pw;
    for i in 0..pw.len() {
        let r = pw.reaction(i, len, &ws.u);
        if r > 0.0 {
            for k in i * len..(i + 1) * len {
                ws.res[pw.dofs[k]] += r * pw.w[k];
            }
        }
    }
}

/// The corners' share Σ ψ(g_c) of the incremental potential at u, with the magnitude of its terms
/// (for the round-off scale of the line search).
pub(super) fn potential<const D: usize>(ws: &Workspace<D>, u: &[f64]) -> (f64, f64) {
    let len = Stencil::<D>::LEN;
    let pw = &ws.pw;
    let (mut pi, mut scale) = (0.0, 0.0);
    for i in 0..pw.len() {
        let (l, k) = (pw.lambda[i], pw.kappa[i]);
        let g = pw.gap(i, len, u);
        // Written without the difference of squares (λ − κg)² − λ², which cancels for small g.
        if l - k * g > 0.0 {
            pi += -l * g + 0.5 * k * g * g;
            scale += (l * g).abs() + 0.5 * k * g * g;
        } else {
            pi -= 0.5 * l * l / k;
            scale += 0.5 * l * l / k;
        }
    }
    (pi, scale)
}

/// Pushes the penalty stiffness κ w_I w_J of every pushing corner onto the free rows.
pub(super) fn add_tangent<const D: usize>(ws: &mut Workspace<D>) {
    let len = Stencil::<D>::LEN;
    let pw = &ws.pw;
    for i in 0..pw.len() {
        if pw.lambda[i] - pw.kappa[i] * pw.gap(i, len, &ws.u) <= 0.0 {
            continue;
        }
        for ka in i * len..(i + 1) * len {
            let row = pw.dofs[ka];
            if ws.state[row] != DofState::Free {
                continue;
            }
            for kb in i * len..(i + 1) * len {
                let v = pw.kappa[i] * pw.w[ka] * pw.w[kb];
                ws.trip.push(faer::sparse::Triplet::new(row, pw.dofs[kb], v));
            }
        }
    }
}

/// Uzawa update λ ← max(0, λ − κ g) at the converged `ws.u`. Returns Ok(true) when some
/// multiplier moved by more than κ · `GAP_TOL` h (Newton must resume), Ok(false) when the
/// constraints hold to the tolerance, an error past `MAX_UZAWA` updates.
pub(super) fn update_multipliers<const D: usize>(ws: &mut Workspace<D>, step: usize) -> Result<bool, String> {
    let len = Stencil::<D>::LEN;
    let pw = &mut ws.pw;
    let (mut worst, mut at): (f64, usize) = (0.0, 0);
    for i in 0..pw.len() {
        let r = pw.reaction(i, len, &ws.u);
        let e = (r - pw.lambda[i]).abs() / pw.kappa[i];
        if e > worst {
            (worst, at) = (e, i);
        }
    }
    if std::env::var_os("MCDEM_MPM_TRACE").is_some() && pw.len() > 0 {
        let active = (0..pw.len()).filter(|&i| pw.reaction(i, len, &ws.u) > 0.0).count();
        eprintln!(
            "  step {step} multipliers {}: largest change {worst:.3e} m at constraint {at} (λ {:.3e}, r {:.3e}, gap {:.3e} m); {active} pushing",
            pw.updates,
            pw.lambda[at],
            pw.reaction(at, len, &ws.u),
            pw.gap(at, len, &ws.u)
        );
    }
    if worst <= GAP_TOL * pw.h {
        return Ok(false);
    }
    // Nearly redundant corners can converge slowly (module doc): after `SLOW_UZAWA` updates a
    // violation below `LOOSE_GAP_TOL` h is accepted.
    if pw.updates >= SLOW_UZAWA && worst <= LOOSE_GAP_TOL * pw.h {
        return Ok(false);
    }
    if pw.updates >= MAX_UZAWA {
        return Err(format!(
            "step {step}: the walls on the material points did not converge in {MAX_UZAWA} multiplier updates: a point's domain is still {worst:.3e} m past its wall or open while pushing (tolerance {:.1e} h)",
            GAP_TOL
        ));
    }
    for i in 0..pw.len() {
        pw.lambda[i] = pw.reaction(i, len, &ws.u);
    }
    pw.updates += 1;
    Ok(true)
}

/// Adds each wall's load on the body (Σ of its corners' reactions at `ws.u`) to `load`.
pub(in crate::mpm) fn add_loads<const D: usize>(ws: &Workspace<D>, load: &mut [f64]) {
    let len = Stencil::<D>::LEN;
    let pw = &ws.pw;
    if !pw.enabled {
        return;
    }
    for i in 0..pw.len() {
        load[pw.wall[i]] += pw.reaction(i, len, &ws.u);
    }
}

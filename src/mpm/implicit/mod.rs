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

mod assembly;
mod newton;
mod point_walls;
#[cfg(test)]
mod tests;
mod transfer;
mod walls;

pub(super) use assembly::{compliance, factorize};
pub(super) use newton::solve;
pub(super) use point_walls::add_loads as add_point_wall_loads;
pub(super) use transfer::prepare;

use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{Argsort, Pair, SymbolicSparseColMat, Triplet};

use super::constitutive::{Constitutive, Law, Mat, Tangent};
use super::fbar::FBarState;
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

/// Where the rigid walls act on a body.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WallsOn {
    /// On grid nodes: Moreau's velocity-Signorini condition per node (Section 2.2, Fig. 2a), an
    /// exact active set; a body's material can lie up to a cell past a wall.
    #[default]
    Nodes,
    /// On the material points' domains: no domain corner crosses a wall (augmented Lagrangian,
    /// `point_walls`); frictionless only.
    Points,
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
    pub walls_on: WallsOn,
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

/// A Newton matrix's sparsity pattern: the triplets' positions in assembly order, the compressed
/// structure with the order its values are read in, and the symbolic LU.
#[derive(Clone, Debug)]
pub(super) struct Pattern {
    pub(super) idx: Vec<Pair<usize, usize>>,
    pub(super) symbolic: SymbolicSparseColMat<usize>,
    pub(super) argsort: Argsort<usize>,
    pub(super) lu: SymbolicLu<usize>,
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
    /// The last Newton matrix's sparsity pattern with its symbolic analysis (`factorize`), the
    /// spare index buffer of the next one, and the values in triplet order.
    pub(super) pattern: Option<Pattern>,
    pub(super) pattern_idx: Vec<Pair<usize, usize>>,
    pub(super) vals: Vec<f64>,
    /// The walls' corner constraints on the points (`WallsOn::Points`).
    pub(super) pw: point_walls::PointWalls,
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

/// Last part of a step: moves the points with the converged grid motion of `solve`.
pub(super) fn finish<const D: usize>(
    body: &mut Body<D>,
    opt: &StepOptions,
    step: usize,
    ws: &Workspace<D>,
) -> Result<(), String> {
    transfer::update_points(&mut body.points, &body.law, opt.locking, ws, opt.dt, opt.flip, step)
}

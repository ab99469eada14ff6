//! Static equilibrium of elastic, frictionless spheres between rigid plane walls with the nonlocal
//! contact relation of Gonzalez & Cuitiño (2012) (docs/spec.md §4):
//!
//! ```text
//! force balance, particle i:   Σ_{c ∈ C_i} −P_c e_ic = 0
//! contact c = (i, j):          γ_c(x) − δ_c − Σ_{k ∈ C_i, k≠c} G_i(c,k) P_k − Σ_{l ∈ C_j, l≠c} G_j(c,l) P_l = 0
//!                              P_c = (4/3) E*_c √R*_c δ_c^{3/2}
//! ```
//!
//! e_ic is the unit vector from the centre of i toward contact c, γ_c the geometric overlap, δ_c the
//! local Hertz overlap (γ_c minus the nonlocal approach). The unknowns are the centres and δ_c
//! rather than P_c: dγ/dP = (2/3)γ/P is infinite at P = 0, while dP/dδ = (3/2)K√δ is finite, so the
//! Jacobian stays bounded for contacts that are just closing. P(δ) = K max(δ, 0)^{3/2} is C¹, so
//! contacts that open during the iterations carry no force; a converged contact with δ < 0 is
//! released by the active set, a closing pair is added to it.
//!
//! Newton's method with the exact Jacobian (including the motion of the contact directions inside
//! G), assembled as triplets and factorised by a sparse LU with partial pivoting (faer): the system is
//! nonsymmetric and indefinite (compressive contacts soften the geometric stiffness), which rules out
//! Cholesky and LDLᵀ without pivoting, and dense LU is O(n³) for n ≈ 3N + N_c.
//!
//! Rigid-body modes: a sphere with fewer than three non-coplanar contacts (a rattler, or one held
//! by two contacts) has translations with no stiffness, which makes J singular. Every particle's
//! position block of J gets a weak tether −ε·k_ref·I (ε = `Settings::regularisation`, k_ref the
//! mean contact stiffness dP/dγ). Only the Jacobian is modified, never the residual, so a converged
//! state is an exact equilibrium; free particles simply do not move (their residual is zero).
//!
//! Internally lengths are in units of the mean radius and forces in E_ref·L² (E_ref the largest
//! particle modulus), so the Newton merit function weighs force balance and overlaps alike.
//!
//! The solver is split by what each part does: `residual` (contact geometry, the residual and
//! its exact Jacobian), `newton` (Newton with line search and pseudo-transient continuation, the
//! active set, [`Nonlocal::solve`]), `stepping` (load increments with halving and the affine
//! predictor, [`Nonlocal::advance`]) and `fire` (the FIRE relaxation that starts from a packing
//! out of equilibrium, [`Nonlocal::relax`]).

mod fire;
mod newton;
mod residual;
mod stepping;
#[cfg(test)]
mod tests;

use std::fmt;

use faer::sparse::linalg::solvers::SymbolicLu;
use faer::sparse::Triplet;

use super::kernel::{BoundKernel, Kernel};
use crate::physics::material::Material;
use crate::physics::Vec3;

/// Smallest reference force for the relative force-balance residual, in units of E_ref·L².
/// 1e-9 E_ref·L² is the Hertz force of an overlap of about 1e-6 radii: below it a packing is
/// force-free (unjammed), and the criterion becomes absolute.
const FORCE_FLOOR: f64 = 1e-9;

/// One sphere of the scene (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Identifier reported in outputs and errors (the LIGGGHTS atom id, or the 1-based index).
    pub id: u64,
    /// Centre [m].
    pub x: Vec3,
    /// Radius [m].
    pub radius: f64,
    /// Elastic constants (E, ν); the multi-contact fields are ignored here.
    pub material: Material,
}

/// A rigid plane wall: the half-space `(y − point)·normal ≥ 0` is the inside of the box.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall {
    pub name: String,
    /// A point of the plane [m].
    pub point: Vec3,
    /// Unit normal pointing into the domain.
    pub normal: Vec3,
}

impl Wall {
    /// The six walls of the box [0, lx] × [0, ly] × [0, lz], normals into the box, in the order
    /// xlo, xhi, ylo, yhi, bottom, top; `top` names the last one (a die's "top", a "piston").
    pub fn rigid_box(lx: f64, ly: f64, lz: f64, top: &str) -> Vec<Wall> {
        let w = |name: &str, p: [f64; 3], n: [f64; 3]| Wall {
            name: name.into(),
            point: Vec3::from(p),
            normal: Vec3::from(n),
        };
        vec![
            w("xlo", [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
            w("xhi", [lx, 0.0, 0.0], [-1.0, 0.0, 0.0]),
            w("ylo", [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            w("yhi", [0.0, ly, 0.0], [0.0, -1.0, 0.0]),
            w("bottom", [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            w(top, [0.0, 0.0, lz], [0.0, 0.0, -1.0]),
        ]
    }
}

/// Solver controls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Convergence: max |net force on a particle| / mean contact force, and max relation residual
    /// / mean radius, both below this.
    pub tolerance: f64,
    /// Newton iterations per active-set round.
    pub max_newton: usize,
    /// Active-set rounds (solve, release tensile, add closing) per load increment.
    pub max_active_rounds: usize,
    /// How many times a failing load increment may be halved.
    pub max_subdivisions: u32,
    /// ε of the Jacobian tether (see the module documentation).
    pub regularisation: f64,
    /// FIRE steps allowed when Newton fails on an increment (0: no fallback, halve at once).
    pub fire_fallback_steps: usize,
    /// Affine predictor for load increments: when a wall moves along its normal, the particle
    /// coordinates along that normal are stretched between it and the opposite (antiparallel) wall
    /// in proportion to the change of the gap, before Newton starts. Only the initial guess
    /// changes, never the equations.
    pub affine_predictor: bool,
    /// Relax every load increment by FIRE (nonlocal, lagged) before Newton instead of trying
    /// Newton first: for packings that rearrange at nearly every increment (loose, frictionless
    /// packings under compression) the warm-started Newton attempt is wasted work.
    pub fire_first: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            tolerance: 1e-9,
            max_newton: 40,
            max_active_rounds: 30,
            max_subdivisions: 6,
            regularisation: 1e-8,
            fire_fallback_steps: 100_000,
            affine_predictor: false,
            fire_first: false,
        }
    }
}

/// The other body of a contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Other {
    Particle(usize),
    Wall(usize),
}

#[derive(Debug, Clone, Copy)]
struct Contact {
    i: usize,
    other: Other,
    /// Local Hertz overlap (scaled units).
    delta: f64,
    /// (4/3) E* √R* (scaled units).
    k: f64,
}

/// One active contact in SI units, for output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactState {
    /// Index of the first particle (0-based, order of the input).
    pub i: usize,
    pub other: Other,
    /// Compressive normal force P [N].
    pub force: f64,
    /// Geometric overlap γ [m].
    pub overlap: f64,
    /// Local Hertz overlap δ [m] (γ minus the nonlocal approach).
    pub hertz_overlap: f64,
    /// Unit vector from the centre of i toward the contact.
    pub direction: Vec3,
}

/// Counters of one solved load increment.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepStats {
    pub newton_iterations: usize,
    pub active_set_rounds: usize,
    pub subdivisions: usize,
    /// FIRE relaxation steps spent on this increment (0 when Newton alone converged).
    pub fire_steps: usize,
    /// Force-balance residual: max over particles of |net force| / mean contact force.
    pub residual: f64,
    /// Max |relation residual| / mean radius.
    pub relation_residual: f64,
}

/// A solve that did not converge: what, where, how far.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveError {
    pub message: String,
    /// Force-balance residual (relative) at the failure.
    pub residual: f64,
    /// Id of the particle with the largest net force.
    pub worst_particle: Option<u64>,
}

impl fmt::Display for SolveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (force-balance residual {:.3e}", self.message, self.residual)?;
        if let Some(id) = self.worst_particle {
            write!(f, ", worst particle id {id}")?;
        }
        write!(f, ")")
    }
}

impl std::error::Error for SolveError {}

/// Geometry of one contact at the current centres.
#[derive(Debug, Clone, Copy)]
struct Geo {
    /// Unit vector from the centre of i toward the contact.
    e: Vec3,
    /// Centre distance for a particle pair; ∞ for a wall (its direction does not move).
    d: f64,
    /// Geometric overlap γ.
    gamma: f64,
}

struct Eval {
    res: Vec<f64>,
    trip: Vec<Triplet<usize, usize, f64>>,
    force_rel: f64,
    relation_rel: f64,
    worst: usize,
    p_mean: f64,
}

/// The nonlocal static solver: scene, current state (centres, active contacts) and controls.
pub struct Nonlocal {
    len: f64,
    e_ref: f64,
    ids: Vec<u64>,
    mats: Vec<Material>,
    x: Vec<Vec3>,
    r: Vec<f64>,
    e: Vec<f64>,
    nu: Vec<f64>,
    walls: Vec<Wall>,
    wall_material: Material,
    kernel: Kernel,
    /// The kernel bound to each particle's E, ν, r (scaled units).
    bound: Vec<BoundKernel>,
    settings: Settings,
    contacts: Vec<Contact>,
    /// Iterations of the last Newton solve, successful or not.
    last_iterations: usize,
    /// Whether the last FIRE relaxation stopped on a stall (see [`Self::relax`]), and the particle
    /// with the largest net force at its end.
    last_fire_stalled: bool,
    last_fire_worst: usize,
    /// Symbolic LU of the last Jacobian and its sparsity pattern (column pointers, row indices):
    /// reused while the pattern is unchanged (same active set, same structural non-zeros).
    lu_pattern: Option<(Vec<usize>, Vec<usize>, SymbolicLu<usize>)>,
    /// External body force per particle (scaled units), e.g. weight, times `body_factor`.
    body: Vec<Vec3>,
    body_factor: f64,
}

fn finite3(v: &Vec3) -> bool {
    v.iter().all(|c| c.is_finite())
}

impl Nonlocal {
    /// Validates the scene and sets up the solver with no active contact (the first [`Self::solve`]
    /// finds them).
    pub fn new(
        spheres: &[Sphere],
        walls: &[Wall],
        wall_material: Material,
        kernel: Kernel,
        settings: Settings,
    ) -> Result<Self, String> {
        if spheres.is_empty() {
            return Err("the scene has no particle".into());
        }
        for s in spheres {
            if !finite3(&s.x) {
                return Err(format!("particle {}: centre is not finite", s.id));
            }
            if !(s.radius.is_finite() && s.radius > 0.0) {
                return Err(format!("particle {}: radius {} must be finite and > 0", s.id, s.radius));
            }
        }
        let mut ws = Vec::with_capacity(walls.len());
        for w in walls {
            let n = w.normal.norm();
            if !finite3(&w.point) || !finite3(&w.normal) || n.is_nan() || n <= 0.0 {
                return Err(format!("wall '{}': point and a non-zero normal must be finite", w.name));
            }
            ws.push(Wall { name: w.name.clone(), point: w.point, normal: w.normal / n });
        }
        if !(settings.tolerance > 0.0 && settings.regularisation >= 0.0 && settings.max_newton > 0) {
            return Err("invalid solver settings: tolerance > 0, regularisation >= 0, max_newton > 0".into());
        }
        let len = spheres.iter().map(|s| s.radius).sum::<f64>() / spheres.len() as f64;
        let e_ref = spheres.iter().map(|s| s.material.youngs_modulus).fold(0.0, f64::max);
        let mut me = Self {
            len,
            e_ref,
            ids: spheres.iter().map(|s| s.id).collect(),
            mats: spheres.iter().map(|s| s.material).collect(),
            x: spheres.iter().map(|s| s.x / len).collect(),
            r: spheres.iter().map(|s| s.radius / len).collect(),
            e: spheres.iter().map(|s| s.material.youngs_modulus / e_ref).collect(),
            nu: spheres.iter().map(|s| s.material.poisson_ratio).collect(),
            walls: Vec::new(),
            wall_material,
            kernel,
            bound: Vec::new(),
            settings,
            contacts: Vec::new(),
            last_iterations: 0,
            last_fire_stalled: false,
            last_fire_worst: 0,
            lu_pattern: None,
            body: vec![Vec3::zeros(); spheres.len()],
            body_factor: 0.0,
        };
        me.bound = (0..me.x.len()).map(|i| kernel.bind(me.e[i], me.nu[i], me.r[i])).collect();
        me.walls =
            ws.into_iter().map(|w| Wall { name: w.name, point: w.point / len, normal: w.normal }).collect();
        Ok(me)
    }

    pub fn particle_count(&self) -> usize {
        self.x.len()
    }

    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    pub fn walls(&self) -> Vec<Wall> {
        self.walls
            .iter()
            .map(|w| Wall { name: w.name.clone(), point: w.point * self.len, normal: w.normal })
            .collect()
    }

    /// Sets an external body force on every particle [N] (e.g. its weight m·g), applied times the
    /// factor of [`Self::set_body_force_factor`] (initially 0). Used to release gravity
    /// quasi-statically from a packing settled under gravity.
    pub fn set_body_forces(&mut self, forces: &[Vec3]) -> Result<(), String> {
        if forces.len() != self.x.len() || forces.iter().any(|f| !finite3(f)) {
            return Err("body forces: one finite vector per particle is required".into());
        }
        let f0 = self.force_unit();
        self.body = forces.iter().map(|f| f / f0).collect();
        Ok(())
    }

    pub fn set_body_force_factor(&mut self, factor: f64) {
        self.body_factor = factor;
    }

    /// Moves wall `w` so that its plane passes through `point` [m].
    pub fn set_wall_point(&mut self, w: usize, point: Vec3) {
        self.walls[w].point = point / self.len;
    }

    /// Centres [m].
    pub fn positions(&self) -> Vec<Vec3> {
        self.x.iter().map(|x| x * self.len).collect()
    }

    pub fn ids(&self) -> &[u64] {
        &self.ids
    }

    /// Active contacts in SI units.
    pub fn contacts(&self) -> Vec<ContactState> {
        let f0 = self.force_unit();
        self.contacts
            .iter()
            .map(|c| {
                let g = self.geometry(&self.x, c.i, c.other);
                ContactState {
                    i: c.i,
                    other: c.other,
                    force: Self::force_of(c, c.delta).0 * f0,
                    overlap: g.gamma * self.len,
                    hertz_overlap: c.delta * self.len,
                    direction: g.e,
                }
            })
            .collect()
    }

    /// Force exerted by the particles on each wall [N].
    pub fn wall_forces(&self) -> Vec<Vec3> {
        let mut f = vec![Vec3::zeros(); self.walls.len()];
        for c in self.contacts() {
            if let Other::Wall(w) = c.other {
                f[w] += c.force * c.direction;
            }
        }
        f
    }

    /// Number of particle–particle and particle–wall contacts carrying a positive force.
    pub fn contact_counts(&self) -> (usize, usize) {
        let mut pp = 0;
        let mut pw = 0;
        for c in &self.contacts {
            if c.delta > 0.0 {
                match c.other {
                    Other::Particle(_) => pp += 1,
                    Other::Wall(_) => pw += 1,
                }
            }
        }
        (pp, pw)
    }
}

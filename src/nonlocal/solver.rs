//! Static equilibrium of elastic, frictionless spheres between rigid plane walls with the nonlocal
//! contact relation of Gonzalez & Cuitiño (2012) (SPEC §4):
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

use std::fmt;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use super::kernel::{BoundKernel, Kernel};
use crate::physics::material::{Material, PairCoeffs};
use crate::physics::Vec3;
use crate::team::{SplitMut, Team};

/// Smallest reference force for the relative force-balance residual, in units of E_ref·L².
/// 1e-9 E_ref·L² is the Hertz force of an overlap of about 1e-6 radii: below it a packing is
/// force-free (unjammed), and the criterion becomes absolute.
const FORCE_FLOOR: f64 = 1e-9;

/// Largest centre displacement per Newton iteration, in mean radii (see the step cap in `newton`).
const MAX_MOVE: f64 = 0.05;

/// FIRE stall test (see [`Nonlocal::relax`]): the time step has collapsed below this fraction of the
/// initial one ...
const FIRE_STALL_DT: f64 = 1e-4;
/// ... and the residual has not reached a new low (by 1 %) for this many steps.
const FIRE_STALL_STEPS: usize = 2000;

/// Fewest candidates (pairs and particle-wall contacts) for which FIRE's force evaluation uses
/// the team of threads: a step of the 514-particle compression has a few thousand, so each of two
/// members gets tens of microseconds of work, well above the cost of handing it out.
const FIRE_MIN_LEN: usize = 1024;

/// The buffers of [`Nonlocal::fire_forces`] that grow with the packing, kept across the steps of
/// one relaxation instead of allocated every step, and the relaxation's team of threads.
#[derive(Default)]
struct FireScratch {
    /// The threads of the force evaluation (as many as the rayon pool the solver runs in has),
    /// started by the first evaluation that is large enough.
    team: Option<Team>,
    /// A team of this thread alone, for evaluations too small to share.
    solo: Option<Team>,
    /// Per member of the team: the kernel values of one particle's contact pairs.
    vals: Vec<Vec<f64>>,
    /// Per candidate: its geometry, if its gap may close.
    geo: Vec<Option<Geo>>,
    /// Loaded contacts per particle, compressed rows: (contact, direction from the particle).
    adj_start: Vec<usize>,
    adj: Vec<(usize, Vec3)>,
    fill: Vec<usize>,
    /// Per row entry, then per contact and side: the approach from the particle's other loads.
    app: Vec<f64>,
    app_i: Vec<f64>,
    app_j: Vec<f64>,
    /// Per particle: the lowest possible approach (see `fire_forces`).
    floor: Vec<f64>,
    /// Net force per particle.
    f: Vec<Vec3>,
}

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

/// Pseudo-transient continuation (Kelley & Keyes, SIAM J. Numer. Anal. 35 (1998) 508): when the
/// Newton step fails its line search, a drag σ·k_ref·I is added to the position block of the Jacobian
/// (residual untouched), making the step a damped relaxation; σ shrinks with the residual (switched
/// evolution relaxation) and Newton is recovered near the solution.
const PTC_START: f64 = 1.0;
const PTC_MAX: f64 = 1e10;
const PTC_OFF: f64 = 1e-6;

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

    fn force_unit(&self) -> f64 {
        self.e_ref * self.len * self.len
    }

    /// (4/3) E* √R* for a new contact (scaled), E* from [`PairCoeffs`] (Eq. C.3).
    fn stiffness(&self, i: usize, other: Other) -> f64 {
        let (mj, rstar) = match other {
            Other::Particle(j) => (self.mats[j], self.r[i] * self.r[j] / (self.r[i] + self.r[j])),
            Other::Wall(_) => (self.wall_material, self.r[i]),
        };
        // Restitution 1 and friction 0 are placeholders: only E* is read.
        let e_star = PairCoeffs::new(&self.mats[i], &mj, 1.0, 0.0).map(|c| c.e_star).unwrap_or(f64::NAN);
        4.0 / 3.0 * e_star / self.e_ref * rstar.sqrt()
    }

    fn geometry(&self, x: &[Vec3], i: usize, other: Other) -> Geo {
        match other {
            Other::Particle(j) => {
                let v = x[j] - x[i];
                let d = v.norm();
                Geo { e: v / d, d, gamma: self.r[i] + self.r[j] - d }
            }
            Other::Wall(w) => {
                let wall = &self.walls[w];
                Geo {
                    e: -wall.normal,
                    d: f64::INFINITY,
                    gamma: self.r[i] - (x[i] - wall.point).dot(&wall.normal),
                }
            }
        }
    }

    /// Hertz P(δ) = K max(δ, 0)^{3/2} and dP/dδ (Hertz, Eq. 5 static part). C¹ at δ = 0, so a
    /// contact that opens during the iterations simply stops carrying force (no artificial tension)
    /// while its relation row keeps tracking the gap, and it re-engages if the gap closes again.
    #[inline]
    fn force_of(c: &Contact, delta: f64) -> (f64, f64) {
        if delta <= 0.0 {
            return (0.0, 0.0);
        }
        let s = delta.sqrt();
        (c.k * delta * s, 1.5 * c.k * s)
    }

    /// Per particle: (contact index, sign) with e_sc = sign · e_c.
    fn adjacency(&self) -> Vec<Vec<(usize, f64)>> {
        let mut adj = vec![Vec::new(); self.x.len()];
        for (c, ct) in self.contacts.iter().enumerate() {
            adj[ct.i].push((c, 1.0));
            if let Other::Particle(j) = ct.other {
                adj[j].push((c, -1.0));
            }
        }
        adj
    }

    fn other_particle(ct: &Contact, side: f64) -> Option<usize> {
        if side > 0.0 {
            match ct.other {
                Other::Particle(j) => Some(j),
                Other::Wall(_) => None,
            }
        } else {
            Some(ct.i)
        }
    }

    /// Residual (and Jacobian triplets) of the current active set at centres `x`, overlaps `delta`.
    fn evaluate(&self, x: &[Vec3], delta: &[f64], adj: &[Vec<(usize, f64)>], jac: bool, shift: f64) -> Eval {
        let n = x.len();
        let nc = self.contacts.len();
        let row_c = |c: usize| 3 * n + c;
        let mut res = vec![0.0; 3 * n + nc];
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut push = |r: usize, c: usize, v: f64| {
            if jac && v != 0.0 {
                trip.push(Triplet::new(r, c, v));
            }
        };
        let geo: Vec<Geo> = self.contacts.iter().map(|c| self.geometry(x, c.i, c.other)).collect();
        let pf: Vec<(f64, f64)> =
            self.contacts.iter().zip(delta).map(|(c, &d)| Self::force_of(c, d)).collect();

        if self.body_factor != 0.0 {
            for (i, b) in self.body.iter().enumerate() {
                for a in 0..3 {
                    res[3 * i + a] += self.body_factor * b[a];
                }
            }
        }
        let mut k_sum = 0.0;
        for (c, ct) in self.contacts.iter().enumerate() {
            let (p, dp) = pf[c];
            let g = &geo[c];
            k_sum += dp;
            // Force on i is −P e, on j +P e.
            for a in 0..3 {
                res[3 * ct.i + a] -= p * g.e[a];
            }
            res[row_c(c)] += g.gamma - delta[c];
            for a in 0..3 {
                push(3 * ct.i + a, row_c(c), -dp * g.e[a]);
                // ∂γ/∂x_i = e_ic.
                push(row_c(c), 3 * ct.i + a, g.e[a]);
            }
            push(row_c(c), row_c(c), -1.0);
            if let Other::Particle(j) = ct.other {
                for a in 0..3 {
                    res[3 * j + a] += p * g.e[a];
                    push(3 * j + a, row_c(c), dp * g.e[a]);
                    push(row_c(c), 3 * j + a, -g.e[a]);
                }
                // ∂e/∂x_j = T/d, ∂e/∂x_i = −T/d with T = I − e eᵀ.
                if jac {
                    let t = (nalgebra::Matrix3::identity() - g.e * g.e.transpose()) * (p / g.d);
                    for a in 0..3 {
                        for b in 0..3 {
                            let v = t[(a, b)];
                            push(3 * ct.i + a, 3 * j + b, -v);
                            push(3 * ct.i + a, 3 * ct.i + b, v);
                            push(3 * j + a, 3 * j + b, v);
                            push(3 * j + a, 3 * ct.i + b, -v);
                        }
                    }
                }
            }
        }

        // Nonlocal terms: for particle s, the load at b moves the surface at a.
        if !self.kernel.is_zero() {
            // G(μ) of each pair once (μ is symmetric in the pair); the derivative only with the
            // Jacobian.
            let mut gvals: Vec<(f64, f64)> = Vec::new();
            for (s, list) in adj.iter().enumerate() {
                let z = list.len();
                gvals.clear();
                gvals.resize(z * z, (0.0, 0.0));
                for p in 0..z {
                    let ep = geo[list[p].0].e * list[p].1;
                    for q in p + 1..z {
                        let mu = ep.dot(&(geo[list[q].0].e * list[q].1));
                        let v = if jac { self.bound[s].eval(mu) } else { (self.bound[s].value(mu), 0.0) };
                        gvals[p * z + q] = v;
                        gvals[q * z + p] = v;
                    }
                }
                for (p, &(a, sa)) in list.iter().enumerate() {
                    let ea = geo[a].e * sa;
                    for (q, &(b, sb)) in list.iter().enumerate() {
                        if a == b {
                            continue;
                        }
                        let eb = geo[b].e * sb;
                        let mu = ea.dot(&eb);
                        let (gk, dgk) = gvals[p * z + q];
                        let (pb, dpb) = pf[b];
                        res[row_c(a)] -= gk * pb;
                        push(row_c(a), row_c(b), -gk * dpb);
                        if jac && dgk != 0.0 {
                            let coef = -dgk * pb;
                            // ∂μ/∂x: direction a moves with s and its partner, direction b likewise;
                            // T_a e_b = e_b − μ e_a.
                            if geo[a].d.is_finite() {
                                let v = (eb - ea * mu) * (coef / geo[a].d);
                                let oa = Self::other_particle(&self.contacts[a], sa).unwrap_or(s);
                                for q in 0..3 {
                                    push(row_c(a), 3 * s + q, -v[q]);
                                    push(row_c(a), 3 * oa + q, v[q]);
                                }
                            }
                            if geo[b].d.is_finite() {
                                let v = (ea - eb * mu) * (coef / geo[b].d);
                                let ob = Self::other_particle(&self.contacts[b], sb).unwrap_or(s);
                                for q in 0..3 {
                                    push(row_c(a), 3 * s + q, -v[q]);
                                    push(row_c(a), 3 * ob + q, v[q]);
                                }
                            }
                        }
                    }
                }
            }
        }

        // Tether of the rigid-body modes (Jacobian only).
        if jac {
            let k_ref = if nc > 0 && k_sum > 0.0 { k_sum / nc as f64 } else { 1.0 };
            let eps = (self.settings.regularisation + shift) * k_ref;
            for i in 0..3 * n {
                push(i, i, -eps);
            }
        }

        let p_mean = {
            let (sum, cnt) =
                pf.iter().filter(|p| p.0 > 0.0).fold((0.0, 0usize), |(s, k), p| (s + p.0, k + 1));
            // Forces below FORCE_FLOOR (scaled units) are round-off level: without a floor a lone
            // vanishing contact would be judged relative to itself.
            if cnt > 0 {
                (sum / cnt as f64).max(FORCE_FLOOR)
            } else {
                1.0
            }
        };
        let mut force_max = 0.0;
        let mut worst = 0;
        for i in 0..n {
            let f = (res[3 * i].powi(2) + res[3 * i + 1].powi(2) + res[3 * i + 2].powi(2)).sqrt();
            if f > force_max || f.is_nan() {
                force_max = f;
                worst = i;
            }
        }
        let relation_rel = res[3 * n..].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        Eval { res, trip, force_rel: force_max / p_mean, relation_rel, worst, p_mean }
    }

    fn merit(r: &[f64]) -> f64 {
        r.iter().map(|v| v * v).sum::<f64>()
    }

    fn store(&mut self, x: Vec<Vec3>, delta: &[f64], iterations: usize) {
        self.last_iterations = iterations;
        self.x = x;
        for (c, d) in self.contacts.iter_mut().zip(delta) {
            c.delta = *d;
        }
    }

    fn fail(&self, message: String, ev: &Eval) -> SolveError {
        SolveError { message, residual: ev.force_rel, worst_particle: Some(self.ids[ev.worst]) }
    }

    /// Newton with backtracking line search for the current active set. Returns iterations.
    fn newton(&mut self) -> Result<(usize, f64, f64), SolveError> {
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
    fn approach(&self, s: usize, dir: &Vec3, adj: &[Vec<(usize, f64)>], geo: &[Geo]) -> f64 {
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
    fn update_active_set(&mut self) -> bool {
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

    fn advance_depth(
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
    fn restore_and_halve(
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
    fn newton_then_fire(&mut self, predicted_x: Vec<Vec3>) -> Result<StepStats, SolveError> {
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
    fn predict_affine(&mut self, old: &[Vec3]) {
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

    /// Contact forces for the FIRE relaxation at centres `x`: every candidate pair and every wall
    /// of every particle whose geometric overlap exceeds −`margin`, P = K max(δ, 0)^{3/2} with
    /// δ = γ − Σ G P_lagged (the nonlocal approach from the forces of the previous FIRE step, `lag`,
    /// indexed like the candidates: pairs first, then particle × wall; all zero for Hertz).
    /// Leaves the net forces (with body forces) in `s.f`, returns the mean contact force, and
    /// writes the new forces and Hertz overlaps into `p_out`, `d_out`.
    ///
    /// The per-contact and per-particle work (geometry, kernel sums, overlaps) runs on the rayon
    /// pool; every value is computed as in a serial pass and the forces are summed serially in
    /// contact order, so the result does not depend on the number of threads, bit for bit.
    #[allow(clippy::too_many_arguments)]
    fn fire_forces(
        &self,
        s: &mut FireScratch,
        x: &[Vec3],
        candidates: &[(usize, usize)],
        lag: &[f64],
        margin: f64,
        p_out: &mut [f64],
        d_out: &mut [f64],
    ) -> f64 {
        let n = x.len();
        let nw = self.walls.len();
        let np = candidates.len();
        let other_of = |k: usize| -> (usize, Other) {
            if k < np {
                (candidates[k].0, Other::Particle(candidates[k].1))
            } else {
                ((k - np) / nw, Other::Wall((k - np) % nw))
            }
        };
        let total = np + n * nw;
        let threads = rayon::current_num_threads();
        if total >= FIRE_MIN_LEN && threads > 1 && s.team.as_ref().is_none_or(|t| t.size() != threads) {
            s.team = Some(Team::new(threads));
        }
        // Every pass below on the team's members, each on its own range (of candidates, or of
        // particles), or on this thread alone: the same values either way.
        let team = match s.team.as_ref().filter(|_| total >= FIRE_MIN_LEN && threads > 1) {
            Some(t) => t,
            None => s.solo.get_or_insert_with(|| Team::new(1)),
        };
        let size = team.size();
        s.vals.resize_with(size, Vec::new);
        s.geo.clear();
        s.geo.resize(total, None);
        {
            let geo = SplitMut::new(&mut s.geo);
            team.for_shares(total, |_, r| {
                // SAFETY: the members' shares are disjoint ranges of candidates.
                let out = unsafe { geo.range(r.clone()) };
                for (k, g) in r.zip(out) {
                    let (i, o) = other_of(k);
                    let v = self.geometry(x, i, o);
                    *g = (v.gamma > -margin).then_some(v);
                }
            });
        }
        let geo = &s.geo;
        // Per particle, in compressed rows: the loaded contacts of the previous step (index,
        // direction from the particle), in contact order.
        let nonlocal = !self.kernel.is_zero();
        s.adj_start.clear();
        s.adj.clear();
        if nonlocal {
            s.adj_start.resize(n + 1, 0);
            for k in 0..total {
                if let (Some(_), true) = (&geo[k], lag[k] > 0.0) {
                    let (i, o) = other_of(k);
                    s.adj_start[i + 1] += 1;
                    if let Other::Particle(j) = o {
                        s.adj_start[j + 1] += 1;
                    }
                }
            }
            for i in 0..n {
                s.adj_start[i + 1] += s.adj_start[i];
            }
            s.adj.resize(s.adj_start[n], (0, Vec3::zeros()));
            s.fill.clear();
            s.fill.extend_from_slice(&s.adj_start[..n]);
            for k in 0..total {
                if let (Some(g), true) = (&geo[k], lag[k] > 0.0) {
                    let (i, o) = other_of(k);
                    s.adj[s.fill[i]] = (k, g.e);
                    s.fill[i] += 1;
                    if let Other::Particle(j) = o {
                        s.adj[s.fill[j]] = (k, -g.e);
                        s.fill[j] += 1;
                    }
                }
            }
        }
        let (adj, start) = (&s.adj, &s.adj_start);
        let list = |p: usize| &adj[start[p]..start[p + 1]];
        let approach = |p: usize, c: usize, dir: &Vec3| -> f64 {
            list(p)
                .iter()
                .filter(|(k, _)| *k != c)
                .map(|(k, e)| self.bound[p].value(dir.dot(e)) * lag[*k])
                .sum()
        };
        // The approach at the loaded contacts themselves, with every pair's kernel value computed
        // once (G depends on the pair's direction cosine only): the same values, summed in the same
        // order, as `approach`, at half the kernel evaluations. One value per row entry, then
        // indexed by contact: the side of its first particle, then of the second.
        s.app.clear();
        s.app_i.clear();
        s.app_j.clear();
        if nonlocal {
            s.app.resize(adj.len(), 0.0);
            // Each member the rows of its own range of particles, i.e. its own entries.
            let (app, vals) = (SplitMut::new(&mut s.app), SplitMut::new(&mut s.vals));
            team.for_shares(n, |m, ps| {
                // SAFETY: the members' shares are disjoint ranges of particles, hence of row
                // entries, and each member m takes its own value buffer.
                let (out, vals) =
                    unsafe { (app.range(start[ps.start]..start[ps.end]), &mut vals.range(m..m + 1)[0]) };
                let mut at = 0;
                for p in ps {
                    let row = list(p);
                    let z = row.len();
                    vals.clear();
                    vals.resize(z * z, 0.0);
                    for a in 0..z {
                        for c in a + 1..z {
                            let v = self.bound[p].value(row[a].1.dot(&row[c].1));
                            vals[a * z + c] = v;
                            vals[c * z + a] = v;
                        }
                    }
                    for a in 0..z {
                        out[at + a] =
                            (0..z).filter(|&c| c != a).map(|c| vals[a * z + c] * lag[row[c].0]).sum();
                    }
                    at += z;
                }
            });
            s.app_i.resize(total, 0.0);
            s.app_j.resize(total, 0.0);
            for p in 0..n {
                for (&(k, _), &a) in list(p).iter().zip(&s.app[start[p]..start[p + 1]]) {
                    if other_of(k).0 == p {
                        s.app_i[k] = a;
                    } else {
                        s.app_j[k] = a;
                    }
                }
            }
        }
        // Per particle: lower bound of the approach at any point, lower_bound · Σ lag (≤ 0).
        s.floor.clear();
        if nonlocal {
            s.floor
                .extend((0..n).map(|p| {
                    self.bound[p].lower_bound() * list(p).iter().map(|&(k, _)| lag[k]).sum::<f64>()
                }));
        }
        // Each contact's overlap and force (d_out, p_out), then the sums in contact order.
        let (app_i, app_j, floor) = (&s.app_i, &s.app_j, &s.floor);
        let (ds, ps) = (SplitMut::new(&mut d_out[..total]), SplitMut::new(&mut p_out[..total]));
        team.for_shares(total, |_, r| {
            // SAFETY: the members' shares are disjoint ranges of contacts.
            let (ds, ps) = unsafe { (ds.range(r.clone()), ps.range(r.clone())) };
            for (k, (d_out, p_out)) in r.zip(ds.iter_mut().zip(ps.iter_mut())) {
                *p_out = 0.0;
                *d_out = f64::NEG_INFINITY;
                let Some(g) = &geo[k] else { continue };
                let (i, o) = other_of(k);
                let mut delta = g.gamma;
                if nonlocal {
                    let loaded = lag[k] > 0.0;
                    if !loaded {
                        // The approach is at least lower_bound · Σ lag at each particle: when even
                        // the largest possible bulge leaves the gap open, the contact stays
                        // unloaded (its overlap is not used).
                        let mut most = g.gamma - floor[i];
                        if let Other::Particle(j) = o {
                            most -= floor[j];
                        }
                        if most < 0.0 {
                            *d_out = most;
                            continue;
                        }
                    }
                    delta -= if loaded { app_i[k] } else { approach(i, k, &g.e) };
                    if let Other::Particle(j) = o {
                        delta -= if loaded { app_j[k] } else { approach(j, k, &(-g.e)) };
                    }
                }
                *d_out = delta;
                if delta > 0.0 {
                    let c = Contact { i, other: o, delta, k: self.stiffness(i, o) };
                    *p_out = Self::force_of(&c, delta).0;
                }
            }
        });
        s.f.clear();
        s.f.extend(self.body.iter().map(|b| b * self.body_factor));
        let (mut sum, mut cnt) = (0.0, 0usize);
        for k in 0..total {
            // Overlap positive: a force was computed (d_out is −∞ or negative otherwise).
            if d_out[k] <= 0.0 {
                continue;
            }
            let (p, Some(g)) = (p_out[k], &geo[k]) else { continue };
            let (i, o) = other_of(k);
            s.f[i] -= g.e * p;
            if let Other::Particle(j) = o {
                s.f[j] += g.e * p;
            }
            sum += p;
            cnt += 1;
        }
        if cnt > 0 {
            sum / cnt as f64
        } else {
            0.0
        }
    }

    /// Pre-relaxation of a packing that is not in equilibrium (e.g. a DEM snapshot in motion):
    /// FIRE energy minimisation (Bitzek et al., Phys. Rev. Lett. 97 (2006) 170201) with plain Hertz
    /// contacts, unit masses, at the current walls and body forces. See [`Self::relax`].
    pub fn relax_hertz(&mut self, max_steps: usize, ftol: f64) -> (usize, f64) {
        self.relax(max_steps, ftol, false)
    }

    /// FIRE relaxation (Bitzek et al., Phys. Rev. Lett. 97 (2006) 170201, unit masses) at the current
    /// walls and body forces. Newton cannot do this job: far from equilibrium the packing has to
    /// rearrange, which is a minimisation, not a root-finding problem. With `nonlocal` the contact
    /// law is the nonlocal relation with the approach lagged by one FIRE step (the fixed-point
    /// iteration that standard multi-contact performs in the DEM, SPEC §4 (b)); without it, plain
    /// Hertz. Stops when max |net force| ≤ `ftol` × mean contact force, after `max_steps`, or on a
    /// stall (dt below [`FIRE_STALL_DT`] × the initial dt and no new low of the residual for
    /// [`FIRE_STALL_STEPS`] steps: the lagged iteration oscillates; recorded for the caller).
    /// Returns (steps, final relative residual). The active set is replaced by the loaded contacts
    /// of the relaxed state (with their lagged Hertz overlaps), a warm start for Newton.
    pub fn relax(&mut self, max_steps: usize, ftol: f64, nonlocal: bool) -> (usize, f64) {
        let n = self.x.len();
        let nw = self.walls.len();
        let mut x = self.x.clone();
        let mut v = vec![Vec3::zeros(); n];
        let (dt0, dt_max): (f64, f64) = (0.05, 0.5);
        let (mut dt, mut alpha, mut since_neg) = (dt0, 0.1, 0usize);
        let mut candidates: Vec<(usize, usize)> = Vec::new();
        let mut x_list = x.clone();
        let rmax = self.r.iter().cloned().fold(0.0, f64::max);
        let rmin = self.r.iter().cloned().fold(f64::INFINITY, f64::min);
        let skin = 0.3 * rmax;
        // Contacts whose geometric gap is below this may be closed by the nonlocal bulge.
        let margin = if nonlocal && !self.kernel.is_zero() { 0.2 * rmin } else { 0.0 };
        let rebuild = |x: &[Vec3], c: &mut Vec<(usize, usize)>| {
            c.clear();
            for i in 0..n {
                for j in i + 1..n {
                    if (x[j] - x[i]).norm() < self.r[i] + self.r[j] + skin {
                        c.push((i, j));
                    }
                }
            }
        };
        // The lagged forces start from the current active set.
        let saved_kernel = self.kernel;
        if !nonlocal {
            self.kernel = Kernel::new(crate::nonlocal::KernelKind::None, 0.0).unwrap_or(saved_kernel);
        }
        let start: std::collections::HashMap<(usize, Other), f64> =
            self.contacts.iter().map(|c| ((c.i, c.other), Self::force_of(c, c.delta).0)).collect();
        rebuild(&x, &mut candidates);
        let index_of = |c: &[(usize, usize)], map: &std::collections::HashMap<(usize, Other), f64>| {
            let mut lag = vec![0.0; c.len() + n * nw];
            for (k, &(i, j)) in c.iter().enumerate() {
                lag[k] = map.get(&(i, Other::Particle(j))).copied().unwrap_or(0.0);
            }
            for i in 0..n {
                for w in 0..nw {
                    lag[c.len() + i * nw + w] = map.get(&(i, Other::Wall(w))).copied().unwrap_or(0.0);
                }
            }
            lag
        };
        let mut lag = index_of(&candidates, &start);
        let mut p = vec![0.0; lag.len()];
        let mut d = vec![0.0; lag.len()];
        let mut rel;
        let mut step = 0;
        let mut scratch = FireScratch::default();
        let trace = std::env::var_os("MCDEM_NONLOCAL_TRACE").is_some();
        let (mut best, mut best_step, mut min_dt, mut longest) = (f64::INFINITY, 0usize, dt0, 0usize);
        self.last_fire_stalled = false;
        loop {
            if x.iter().zip(&x_list).any(|(a, b)| (a - b).norm() > 0.5 * skin) {
                let np = candidates.len();
                let map: std::collections::HashMap<(usize, Other), f64> = (0..lag.len())
                    .filter(|&k| lag[k] > 0.0)
                    .map(|k| {
                        if k < np {
                            ((candidates[k].0, Other::Particle(candidates[k].1)), lag[k])
                        } else {
                            (((k - np) / nw, Other::Wall((k - np) % nw)), lag[k])
                        }
                    })
                    .collect();
                rebuild(&x, &mut candidates);
                x_list = x.clone();
                lag = index_of(&candidates, &map);
                p = vec![0.0; lag.len()];
                d = vec![0.0; lag.len()];
            }
            let pmean = self.fire_forces(&mut scratch, &x, &candidates, &lag, margin, &mut p, &mut d);
            let f = &scratch.f;
            std::mem::swap(&mut lag, &mut p);
            let fmax = f.iter().map(|f| f.norm()).fold(0.0, f64::max);
            rel = fmax / pmean.max(FORCE_FLOOR);
            // Below the force floor the packing is unjammed: relax on until every overlap has
            // opened (all forces exactly zero, an exact equilibrium) rather than leave Newton a
            // degenerate problem (P ∝ δ^{3/2} with dP/dδ → 0).
            let unjammed = pmean < FORCE_FLOOR && fmax > 0.0;
            if trace && step % 2000 == 0 {
                eprintln!(
                    "  fire {step}: force {rel:.3e} (mean P {pmean:.3e}) dt {dt:.3e} candidates {}",
                    candidates.len()
                );
            }
            if rel < 0.99 * best {
                (best, best_step) = (rel, step);
            }
            min_dt = min_dt.min(dt);
            longest = longest.max(step - best_step);
            // Stall: the lagged nonlocal iteration oscillates (its fixed-point map is not a
            // contraction at this load), FIRE keeps reversing, dt collapses and the residual stays
            // put; more steps change nothing.
            let stalled = dt < FIRE_STALL_DT * dt0 && step - best_step >= FIRE_STALL_STEPS;
            if (rel <= ftol && !unjammed) || step >= max_steps || stalled {
                if trace {
                    eprintln!(
                        "  fire done at {step}: force {rel:.3e} (tolerance {ftol:.0e}) min dt {min_dt:.3e} longest without progress {longest}{}",
                        if stalled { " STALLED" } else { "" }
                    );
                }
                self.last_fire_stalled = stalled;
                self.last_fire_worst =
                    (0..n).max_by(|&a, &b| f[a].norm().total_cmp(&f[b].norm())).unwrap_or(0);
                break;
            }
            step += 1;
            let power: f64 = f.iter().zip(&v).map(|(f, v)| f.dot(v)).sum();
            let fnorm = f.iter().map(|f| f.norm_squared()).sum::<f64>().sqrt();
            let vnorm = v.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt();
            if power > 0.0 {
                for (vi, fi) in v.iter_mut().zip(f) {
                    *vi = *vi * (1.0 - alpha) + fi * (alpha * vnorm / fnorm.max(1e-300));
                }
                since_neg += 1;
                if since_neg > 5 {
                    dt = (dt * 1.1).min(dt_max);
                    alpha *= 0.99;
                }
            } else {
                since_neg = 0;
                dt *= 0.5;
                alpha = 0.1;
                v.iter_mut().for_each(|v| *v = Vec3::zeros());
            }
            // Semi-implicit Euler with unit masses; a move cap keeps contacts in the list valid.
            for i in 0..n {
                v[i] += f[i] * dt;
                let mut dx = v[i] * dt;
                let m = dx.norm();
                if m > 0.1 * skin {
                    dx *= 0.1 * skin / m;
                }
                x[i] += dx;
            }
        }
        self.kernel = saved_kernel;
        // Warm start for Newton: the loaded contacts with their (lagged) Hertz overlaps.
        let np = candidates.len();
        self.contacts = (0..lag.len())
            .filter(|&k| lag[k] > 0.0)
            .map(|k| {
                let (i, o) = if k < np {
                    (candidates[k].0, Other::Particle(candidates[k].1))
                } else {
                    ((k - np) / nw, Other::Wall((k - np) % nw))
                };
                Contact { i, other: o, delta: d[k], k: self.stiffness(i, o) }
            })
            .collect();
        if !nonlocal {
            // Hertz relaxation: Newton re-derives the overlaps with the nonlocal terms.
            self.contacts.clear();
        }
        self.x = x;
        (step, rel)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nonlocal::kernel::KernelKind;

    /// A small compressed cluster in a box with pair and wall contacts.
    fn cluster(kind: KernelKind) -> Nonlocal {
        let m = Material::hertz(1e4, 0.35).unwrap();
        let wm = Material::hertz(1e7, 0.3).unwrap();
        let pts = [
            [0.95, 1.0, 0.9],
            [2.75, 1.1, 1.0],
            [1.9, 2.6, 1.05],
            [1.85, 1.5, 2.55],
            [0.9, 2.8, 2.7],
            [2.9, 2.9, 2.8],
        ];
        let spheres: Vec<Sphere> = pts
            .iter()
            .enumerate()
            .map(|(k, p)| Sphere {
                id: k as u64 + 1,
                x: Vec3::from(*p),
                radius: 1.0 + 0.05 * k as f64,
                material: m,
            })
            .collect();
        let walls = vec![
            Wall { name: "a".into(), point: Vec3::zeros(), normal: Vec3::x() },
            Wall { name: "b".into(), point: Vec3::zeros(), normal: Vec3::z() },
            Wall { name: "c".into(), point: Vec3::new(3.8, 0.0, 0.0), normal: -Vec3::x() },
        ];
        let mut s = Nonlocal::new(&spheres, &walls, wm, Kernel::new(kind, 1.0).unwrap(), Settings::default())
            .unwrap();
        s.update_active_set();
        for (k, c) in s.contacts.iter_mut().enumerate() {
            c.delta = c.delta * 0.7 + 1e-3 * k as f64;
        }
        s
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        jacobian_check(KernelKind::Boussinesq);
    }

    #[test]
    fn jacobian_matches_finite_differences_with_the_sphere_kernel() {
        jacobian_check(KernelKind::Sphere);
    }

    fn jacobian_check(kind: KernelKind) {
        let s = cluster(kind);
        let nc = s.contacts.len();
        assert!(nc >= 8, "cluster has only {nc} contacts");
        let n = s.x.len();
        let dim = 3 * n + nc;
        let adj = s.adjacency();
        let delta: Vec<f64> = s.contacts.iter().map(|c| c.delta).collect();
        let ev = s.evaluate(&s.x, &delta, &adj, true, 0.0);
        let mut dense = vec![vec![0.0; dim]; dim];
        for t in &ev.trip {
            dense[t.row][t.col] += t.val;
        }
        let h = 1e-7;
        for col in 0..dim {
            let (mut xp, mut xm) = (s.x.clone(), s.x.clone());
            let (mut dp, mut dm) = (delta.clone(), delta.clone());
            if col < 3 * n {
                xp[col / 3][col % 3] += h;
                xm[col / 3][col % 3] -= h;
            } else {
                dp[col - 3 * n] += h;
                dm[col - 3 * n] -= h;
            }
            let rp = s.evaluate(&xp, &dp, &adj, false, 0.0).res;
            let rm = s.evaluate(&xm, &dm, &adj, false, 0.0).res;
            for row in 0..dim {
                let fd = (rp[row] - rm[row]) / (2.0 * h);
                let an = dense[row][col];
                // The tether −ε·k_ref on the position diagonal is deliberately not in the residual.
                let tether = if row == col && row < 3 * n { 1e-6 } else { 0.0 };
                let tol = 1e-6 * (1.0 + fd.abs()) + tether;
                if (an - fd).abs() > tol {
                    panic!("J[{row}][{col}] = {an}, finite difference {fd}");
                }
            }
        }
    }

    /// Single hydrogel sphere (SPEC §4 die: E = 23.3 kPa, ν = 0.5, r = 1 mm, walls 50 MPa) in a
    /// rigid cubic die of side 2r, top plate pushed down by Δ in steps of 0.05 r. Returns, per step,
    /// (Δ/r, P_v, P_h, P_v Hertz) and checks convergence and the die's symmetry.
    fn die(kind: KernelKind) -> Vec<(f64, f64, f64, f64)> {
        let (e, nu, r) = (23.3e3, 0.5, 1e-3);
        let m = Material::hertz(e, nu).unwrap();
        let wm = Material::hertz(50e6, 0.5).unwrap();
        let l = 2.0 * r;
        let walls = Wall::rigid_box(l, l, l, "top");
        let sphere = Sphere { id: 1, x: Vec3::new(r, r, r), radius: r, material: m };
        let mut s =
            Nonlocal::new(&[sphere], &walls, wm, Kernel::new(kind, 1.0).unwrap(), Settings::default())
                .unwrap();
        let e_star = PairCoeffs::new(&m, &wm, 1.0, 0.0).unwrap().e_star;
        let steps = 6;
        let disp = 0.3 * r;
        let top0 = walls[5].point;
        let path = |t: f64| {
            let points = walls
                .iter()
                .enumerate()
                .map(|(k, wall)| if k == 5 { top0 - Vec3::z() * (t * disp) } else { wall.point })
                .collect();
            (points, 0.0)
        };
        let mut out = Vec::new();
        for k in 1..=steps {
            let st = s.advance(&path, (k - 1) as f64 / steps as f64, k as f64 / steps as f64).unwrap();
            assert!(st.residual <= 1e-9, "{kind} step {k}: residual {}", st.residual);
            let f: Vec<f64> = s.wall_forces().iter().zip(&walls).map(|(f, w)| -f.dot(&w.normal)).collect();
            let (pv, ph) = (f[5], f[0]);
            assert!(pv.is_finite() && ph.is_finite());
            assert!((f[4] - pv).abs() <= 1e-9 * pv, "{kind}: bottom {} top {pv}", f[4]);
            for fw in &f[1..4] {
                assert!((fw - ph).abs() <= 1e-9 * pv, "{kind}: side {fw} vs {ph}");
            }
            let dr = disp / r * k as f64 / steps as f64;
            let hertz = crate::physics::hertz::hertz_force(e_star, r, 0.5 * dr * r);
            // Independent reduced solve by symmetry (unknowns P_v, P_h), with the kernel's G at 90°
            // and 180°: P_v: Δ/2 = H(P_v) + G180 P_v + 4 G90 P_h; P_h: 0 = H(P_h) + 2 G90 P_v + (G180 + 2 G90) P_h.
            let kern = Kernel::new(kind, 1.0).unwrap();
            let (g90, g180) = (kern.compliance(0.0, e, nu, r).0, kern.compliance(-1.0, e, nu, r).0);
            let h = |p: f64| (3.0 * p.max(0.0) / (4.0 * e_star * r.sqrt())).powf(2.0 / 3.0);
            let res = |pv: f64, ph: f64| {
                (
                    0.5 * dr * r - h(pv) - g180 * pv - 4.0 * g90 * ph,
                    -h(ph) - 2.0 * g90 * pv - (g180 + 2.0 * g90) * ph,
                )
            };
            let (mut qv, mut qh) = (pv * 1.01, ph * 1.01 + 1e-9 * pv);
            for _ in 0..60 {
                let (f1, f2) = res(qv, qh);
                let (e1, e2) = (1e-7 * qv, 1e-7 * qv);
                let (a11, a21) = ((res(qv + e1, qh).0 - f1) / e1, (res(qv + e1, qh).1 - f2) / e1);
                let (a12, a22) = ((res(qv, qh + e2).0 - f1) / e2, (res(qv, qh + e2).1 - f2) / e2);
                let det = a11 * a22 - a12 * a21;
                qv -= (a22 * f1 - a12 * f2) / det;
                qh -= (-a21 * f1 + a11 * f2) / det;
            }
            assert!((pv - qv).abs() <= 1e-6 * qv, "{kind} dr {dr}: P_v {pv} vs reduced {qv}");
            assert!(
                (ph - qh).abs() <= 1e-6 * qh.abs().max(1e-3 * qv),
                "{kind} dr {dr}: P_h {ph} vs reduced {qh}"
            );
            out.push((dr, pv, ph, hertz));
        }
        out
    }

    #[test]
    fn die_with_the_sphere_kernel() {
        let sphere = die(KernelKind::Sphere);
        let bous = die(KernelKind::Boussinesq);
        println!("dr    P_v Hertz   P_v sphere  P_h sphere  P_v bouss.  P_h bouss.");
        for (a, b) in sphere.iter().zip(&bous) {
            println!("{:.2}  {:.4e}  {:.4e}  {:.3e}  {:.4e}  {:.3e}", a.0, a.3, a.1, a.2, b.1, b.2);
            // Converged, finite, stiffer than Hertz (the outward bulge at the far contacts), and a
            // side-wall force builds up.
            assert!(a.1 > a.3 && a.2 > 0.0, "dr {}: P_v {} Hertz {} P_h {}", a.0, a.1, a.3, a.2);
        }
    }

    /// FIRE's parallel force evaluation gives the serial pass's bits: a 6 × 6 × 6 packing (216
    /// particles, more than one block of kernel sums and of contacts) pressed in a box of walls,
    /// relaxed with the lagged nonlocal law on one and on two threads.
    #[test]
    fn fire_relaxation_does_not_depend_on_the_thread_count() {
        let m = Material::hertz(1e4, 0.5).unwrap();
        let wm = Material::hertz(1e7, 0.3).unwrap();
        let packing = || {
            let mut spheres = Vec::new();
            for k in 0..216usize {
                let (a, b, c) = ((k % 6) as f64, ((k / 6) % 6) as f64, (k / 36) as f64);
                // Spacing below the diameter, and an irregular offset so no contact is symmetric.
                let wobble = 0.04 * ((k * 7919) % 13) as f64 / 13.0;
                spheres.push(Sphere {
                    id: k as u64 + 1,
                    x: Vec3::new(
                        1.0 + 1.9 * a + wobble,
                        1.0 + 1.9 * b - wobble,
                        1.0 + 1.9 * c + 0.5 * wobble,
                    ),
                    radius: 1.0 + 0.02 * ((k * 31) % 5) as f64,
                    material: m,
                });
            }
            spheres
        };
        let relaxed = |threads: usize| {
            let spheres = packing();
            let walls = vec![
                Wall { name: "x0".into(), point: Vec3::new(0.05, 0.0, 0.0), normal: Vec3::x() },
                Wall { name: "x1".into(), point: Vec3::new(11.3, 0.0, 0.0), normal: -Vec3::x() },
                Wall { name: "y0".into(), point: Vec3::new(0.0, 0.05, 0.0), normal: Vec3::y() },
                Wall { name: "y1".into(), point: Vec3::new(0.0, 11.3, 0.0), normal: -Vec3::y() },
                Wall { name: "z0".into(), point: Vec3::new(0.0, 0.0, 0.05), normal: Vec3::z() },
                Wall { name: "z1".into(), point: Vec3::new(0.0, 0.0, 11.3), normal: -Vec3::z() },
            ];
            let mut s = Nonlocal::new(
                &spheres,
                &walls,
                wm,
                Kernel::new(KernelKind::Sphere, 1.0).unwrap(),
                Settings::default(),
            )
            .unwrap();
            s.update_active_set();
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (steps, rel) = pool.install(|| s.relax(400, 1e-12, true));
            (s.positions(), steps, rel, s.contacts.len())
        };
        let (x1, steps1, rel1, c1) = relaxed(1);
        let (x2, steps2, rel2, c2) = relaxed(2);
        assert!(c1 > 216, "the packing must be loaded: {c1} contacts");
        assert_eq!((steps1, rel1.to_bits(), c1), (steps2, rel2.to_bits(), c2));
        for (a, b) in x1.iter().zip(&x2) {
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
        }
        // The relaxation moved the particles (a run that did nothing would compare equal trivially).
        let moved = x1.iter().zip(packing()).map(|(a, b)| (a - b.x).norm()).fold(0.0, f64::max);
        assert!(moved > 1e-6, "largest move {moved}");
    }
}

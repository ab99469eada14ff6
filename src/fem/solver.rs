//! Quasi-static equilibrium: assembly, frictionless rigid-plane contact by an active set on the
//! nodes, and Newton's method with a line search and a sparse Cholesky (LU as fallback) solve.
//!
//! Equilibrium minimises the total strain energy Π(u) = Σ_e Π_e(u) subject to the symmetry
//! conditions (fixed displacement components) and the non-penetration of the rigid planes,
//! s (X_a + u_a − h) ≤ 0 per node for a plane normal to axis a at h (s = +1: the body lies below).
//! Frictionless contact constrains only that normal component. The active set holds the nodes on a
//! plane; a node enters when it penetrates and leaves when the plane would have to pull it
//! (s ∂Π/∂u_a > 0), the Karush-Kuhn-Tucker conditions of the minimisation.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Side};

use super::element::{self, Geometry, Law, Output, Volumetric};
use super::material::Lame;
use super::mesh::Mesh;
use super::surface::SurfacePair;

/// A rigid frictionless plane normal to `axis` at `pos`; `upper`: the body stays at x_axis ≤ pos.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    pub axis: usize,
    pub pos: f64,
    pub upper: bool,
}

/// The boundary-value problem.
#[derive(Clone, Debug)]
pub struct Problem {
    pub mesh: Mesh,
    pub law: Law,
    pub lame: Lame,
    pub vol: Volumetric,
    /// Prescribed displacement components (dof = 3 node + axis, value).
    pub fixed: Vec<(usize, f64)>,
    pub planes: Vec<Plane>,
    /// Frictionless contacts between bodies of the mesh (`surface`); empty for one body.
    pub pairs: Vec<SurfacePair>,
}

/// Solver settings.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Converged when the largest free residual is below `rtol` times the largest reaction force
    /// (or `atol` E L², L the mesh size, whichever is larger).
    pub rtol: f64,
    pub atol: f64,
    pub max_iter: usize,
    /// Proximal-point regularisation κ in units of E L (0: none). Each Newton solve then minimises
    /// Π(u) + κ |u − a|²/2 about an anchor a, which moves to the solution until the proximal force
    /// κ |u − a| is within the tolerance: the equilibrium found is Π's own, the problems on the
    /// way are well conditioned. For a body held only by frictionless contacts (a sphere's rigid
    /// rotations cost nothing while its patches are single nodes).
    pub proximal: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { rtol: 1e-9, atol: 1e-13, max_iter: 60, proximal: 0.0 }
    }
}

/// Displacements, the contact active set (one flag per node and plane) and the multipliers λ [Pa]
/// of the body–body contacts (one per slave node of each pair).
#[derive(Clone, Debug)]
pub struct State {
    pub u: Vec<f64>,
    pub active: Vec<Vec<bool>>,
    pub multiplier: Vec<Vec<f64>>,
}

/// What a converged solve reports.
#[derive(Clone, Debug)]
pub struct Equilibrium {
    /// Per plane, the force the body exerts on it along its outward normal (≥ 0: pushing).
    pub plane_force: Vec<f64>,
    /// Per plane, the number of nodes in contact.
    pub contact_nodes: Vec<usize>,
    /// Per body–body pair, the force on the slave body [N] and its number of slave nodes in contact.
    pub pair_force: Vec<[f64; 3]>,
    pub pair_nodes: Vec<usize>,
    /// Per pair, the largest penetration left [m] (≤ its gap tolerance).
    pub pair_penetration: Vec<f64>,
    pub iterations: usize,
    pub residual: f64,
}

/// Reusable assembly data: element geometries, the sparsity pattern and its Cholesky analysis.
pub struct Solver {
    geo: Vec<Geometry>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    llt: Option<SymbolicLlt<usize>>,
    vals: Vec<f64>,
    /// Characteristic length of the mesh (bounding-box diagonal).
    length: f64,
    modulus: f64,
}

fn gather(mesh: &Mesh, e: usize, u: &[f64]) -> [[f64; 3]; 8] {
    mesh.hex[e].map(|n| [u[3 * n], u[3 * n + 1], u[3 * n + 2]])
}

/// Current position of a node.
fn current(mesh: &Mesh, u: &[f64], n: usize) -> [f64; 3] {
    [mesh.x[n][0] + u[3 * n], mesh.x[n][1] + u[3 * n + 1], mesh.x[n][2] + u[3 * n + 2]]
}

impl Solver {
    pub fn new(p: &Problem) -> Result<Self, String> {
        let geo = p
            .mesh
            .hex
            .iter()
            .enumerate()
            .map(|(e, h)| {
                element::geometry(&h.map(|i| p.mesh.x[i])).map_err(|m| format!("mesh element {e}: {m}"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let n = 3 * p.mesh.x.len();
        let mut idx = Vec::with_capacity(p.mesh.hex.len() * 300 + n);
        for h in &p.mesh.hex {
            for r in 0..24 {
                for c in 0..24 {
                    let (gr, gc) = (3 * h[r / 3] + r % 3, 3 * h[c / 3] + c % 3);
                    if gr >= gc {
                        idx.push(Pair { row: gr, col: gc });
                    }
                }
            }
        }
        for pair in &p.pairs {
            for (i, cands) in pair.candidates.iter().enumerate() {
                for &m in cands {
                    let dofs = pair.dofs(i, m);
                    for &gr in &dofs {
                        for &gc in &dofs {
                            if gr >= gc {
                                idx.push(Pair { row: gr, col: gc });
                            }
                        }
                    }
                }
            }
        }
        for d in 0..n {
            idx.push(Pair { row: d, col: d });
        }
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &idx)
            .map_err(|e| format!("sparsity pattern: {e:?}"))?;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for x in &p.mesh.x {
            for k in 0..3 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        let length = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
        let modulus = p.lame.mu * (3.0 * p.lame.lambda + 2.0 * p.lame.mu) / (p.lame.lambda + p.lame.mu);
        Ok(Solver { geo, symbolic, argsort, llt: None, vals: Vec::with_capacity(idx.len()), length, modulus })
    }

    /// A state at rest with no contact.
    pub fn rest(&self, p: &Problem) -> State {
        State {
            u: vec![0.0; 3 * p.mesh.x.len()],
            active: vec![vec![false; p.mesh.x.len()]; p.planes.len()],
            multiplier: p.pairs.iter().map(|pair| vec![0.0; pair.slave.len()]).collect(),
        }
    }

    /// Total energy (strain energy plus the body–body contacts' augmented-Lagrangian terms under the
    /// multipliers `multiplier`), or `None` if an element is inverted.
    pub fn energy(&self, p: &Problem, u: &[f64], multiplier: &[Vec<f64>]) -> Option<f64> {
        let mut out = Output::default();
        let mut w = 0.0;
        for e in 0..p.mesh.hex.len() {
            element::evaluate(p.law, &p.lame, p.vol, &self.geo[e], &gather(&p.mesh, e, u), false, &mut out)
                .ok()?;
            w += out.energy;
        }
        let pos = |node: usize| current(&p.mesh, u, node);
        for (pair, lam) in p.pairs.iter().zip(multiplier) {
            for i in 0..pair.slave.len() {
                w += pair.energy(i, lam[i], pair.gap(i, &pos).g);
            }
        }
        Some(w)
    }

    /// Internal force ∂Π/∂u, or `None` if an element is inverted.
    pub fn residual(&self, p: &Problem, u: &[f64]) -> Option<Vec<f64>> {
        let mut out = Output::default();
        let mut r = vec![0.0; u.len()];
        for (e, h) in p.mesh.hex.iter().enumerate() {
            element::evaluate(p.law, &p.lame, p.vol, &self.geo[e], &gather(&p.mesh, e, u), false, &mut out)
                .ok()?;
            for k in 0..24 {
                r[3 * h[k / 3] + k % 3] += out.grad[k];
            }
        }
        Some(r)
    }

    /// Tangent ∂²Π/∂u² as a dense matrix (tests on small meshes only).
    pub fn dense_tangent(&self, p: &Problem, u: &[f64]) -> Option<Vec<Vec<f64>>> {
        let mut out = Output::default();
        let mut k = vec![vec![0.0; u.len()]; u.len()];
        for (e, h) in p.mesh.hex.iter().enumerate() {
            element::evaluate(p.law, &p.lame, p.vol, &self.geo[e], &gather(&p.mesh, e, u), true, &mut out)
                .ok()?;
            for r in 0..24 {
                for c in 0..24 {
                    k[3 * h[r / 3] + r % 3][3 * h[c / 3] + c % 3] += out.hess[r][c];
                }
            }
        }
        Some(k)
    }

    /// Targets of the constrained dofs: the prescribed components and the active contact nodes.
    fn targets(p: &Problem, s: &State, bc: &mut [Option<f64>]) {
        bc.iter_mut().for_each(|b| *b = None);
        for &(d, v) in &p.fixed {
            bc[d] = Some(v);
        }
        for (k, pl) in p.planes.iter().enumerate() {
            for (n, &on) in s.active[k].iter().enumerate() {
                if on {
                    bc[3 * n + pl.axis] = Some(pl.pos - p.mesh.x[n][pl.axis]);
                }
            }
        }
    }

    /// Assemble R and K at u and solve K Δu = −R for the free dofs with Δu = target − u on the
    /// constrained ones (their columns moved to the right-hand side). Returns R and Δu.
    fn newton_direction(
        &mut self,
        p: &Problem,
        u: &[f64],
        multiplier: &[Vec<f64>],
        bc: &[Option<f64>],
        prox: Option<(&[f64], f64)>,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        let n = u.len();
        let mut r = vec![0.0; n];
        let mut rhs = vec![0.0; n];
        let du_c: Vec<f64> = (0..n).map(|d| bc[d].map_or(0.0, |t| t - u[d])).collect();
        self.vals.clear();
        let mut out = Output::default();
        for (e, h) in p.mesh.hex.iter().enumerate() {
            element::evaluate(p.law, &p.lame, p.vol, &self.geo[e], &gather(&p.mesh, e, u), true, &mut out)
                .map_err(|_| format!("element {e} inverted at the start of a Newton iteration"))?;
            for a in 0..24 {
                let ga = 3 * h[a / 3] + a % 3;
                r[ga] += out.grad[a];
                for b in 0..24 {
                    let gb = 3 * h[b / 3] + b % 3;
                    let kab = out.hess[a][b];
                    if bc[ga].is_none() && bc[gb].is_some() {
                        rhs[ga] -= kab * du_c[gb];
                    }
                    if ga >= gb {
                        self.vals.push(if bc[ga].is_none() && bc[gb].is_none() { kab } else { 0.0 });
                    }
                }
            }
        }
        // Body–body contacts: gradient A p ∂g (with sign −), Gauss–Newton tangent A k ∂g ∂gᵀ on the
        // face the node lies against; the other candidate faces' pattern entries get zeros.
        let pos = |node: usize| current(&p.mesh, u, node);
        for (pair, lam) in p.pairs.iter().zip(multiplier) {
            for (i, cands) in pair.candidates.iter().enumerate() {
                let gap = pair.gap(i, &pos);
                let pressure = pair.pressure(lam[i], gap.g);
                let grad = SurfacePair::gap_gradient(&gap);
                let scale = pair.area[i] * pair.penalty;
                for &m in cands {
                    let dofs = pair.dofs(i, m);
                    if !(m == gap.face && pressure > 0.0) {
                        // Its pattern entries, in the order of `Solver::new`, hold zeros.
                        let entries = dofs.iter().flat_map(|&ga| dofs.iter().filter(move |&&gb| ga >= gb));
                        self.vals.extend(entries.map(|_| 0.0));
                        continue;
                    }
                    for a in 0..15 {
                        r[dofs[a]] -= pair.area[i] * pressure * grad[a];
                    }
                    for a in 0..15 {
                        let ga = dofs[a];
                        for b in 0..15 {
                            let gb = dofs[b];
                            let kab = scale * grad[a] * grad[b];
                            if bc[ga].is_none() && bc[gb].is_some() {
                                rhs[ga] -= kab * du_c[gb];
                            }
                            if ga >= gb {
                                self.vals.push(if bc[ga].is_none() && bc[gb].is_none() { kab } else { 0.0 });
                            }
                        }
                    }
                }
            }
        }
        let kappa = prox.map_or(0.0, |(_, k)| k);
        if let Some((anchor, k)) = prox {
            for d in (0..n).filter(|&d| bc[d].is_none()) {
                r[d] += k * (u[d] - anchor[d]);
            }
        }
        for d in 0..n {
            self.vals.push(if bc[d].is_some() { 1.0 } else { kappa });
            rhs[d] = if bc[d].is_some() { du_c[d] } else { rhs[d] - r[d] };
        }
        let k = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, &self.vals)
            .map_err(|e| format!("assembly: {e:?}"))?;
        if self.llt.is_none() {
            self.llt = Some(
                SymbolicLlt::try_new(k.symbolic(), Side::Lower)
                    .map_err(|e| format!("Cholesky analysis: {e:?}"))?,
            );
        }
        let mut x = Mat::<f64>::from_fn(n, 1, |i, _| rhs[i]);
        match Llt::try_new_with_symbolic(self.llt.clone().unwrap(), k.as_ref(), Side::Lower) {
            Ok(f) => f.solve_in_place(x.as_mut()),
            Err(_) => {
                // Not positive definite away from equilibrium: the full symmetric matrix by LU.
                let mut trip = Vec::new();
                for c in 0..n {
                    for (row, v) in k.as_ref().row_idx_of_col(c).zip(k.as_ref().val_of_col(c)) {
                        trip.push(faer::sparse::Triplet::new(row, c, *v));
                        if row != c {
                            trip.push(faer::sparse::Triplet::new(c, row, *v));
                        }
                    }
                }
                let full = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
                    .map_err(|e| format!("assembly: {e:?}"))?;
                let lu = Lu::try_new_with_symbolic(
                    faer::sparse::linalg::solvers::SymbolicLu::try_new(full.symbolic())
                        .map_err(|e| format!("LU: {e:?}"))?,
                    full.as_ref(),
                )
                .map_err(|e| format!("singular tangent: {e:?}"))?;
                lu.solve_in_place(x.as_mut());
            }
        }
        let du: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
        if du.iter().any(|v| !v.is_finite()) {
            return Err("linear solve gave non-finite increments (singular tangent: is the body free to move rigidly?)".into());
        }
        Ok((r, du))
    }

    /// Equilibrium at the current plane positions, starting from `s` (updated in place).
    pub fn solve(&mut self, p: &Problem, s: &mut State, set: &Settings) -> Result<Equilibrium, String> {
        let n = s.u.len();
        let mut bc = vec![None; n];
        let floor = set.atol * self.modulus * self.length * self.length;
        let kappa = set.proximal * self.modulus * self.length;
        let mut anchor = s.u.clone();
        let mut last = f64::NAN;
        for it in 0..set.max_iter {
            Self::targets(p, s, &mut bc);
            let prox = (kappa > 0.0).then_some((anchor.as_slice(), kappa));
            let (r, du) = self.newton_direction(p, &s.u, &s.multiplier, &bc, prox)?;
            let moving = (0..n).any(|d| bc[d].is_some_and(|t| t != s.u[d]));
            let reaction = (0..n).filter(|&d| bc[d].is_some()).map(|d| r[d].abs()).fold(0.0, f64::max);
            let res = (0..n).filter(|&d| bc[d].is_none()).map(|d| r[d].abs()).fold(0.0, f64::max);
            last = res;
            if std::env::var_os("MCDEM_FEM_TRACE").is_some() {
                let worst =
                    (0..n).filter(|&d| bc[d].is_none()).max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs()));
                eprintln!(
                    "newton {it}: free residual {res:.3e} N at dof {worst:?}, reaction {reaction:.3e} N, constrained dofs moving: {moving}"
                );
            }
            if !moving && res <= (set.rtol * reaction).max(floor) {
                // Converged for this active set: release nodes the plane would pull, admit any
                // node that penetrates; done when neither happens.
                let mut changed = false;
                for (k, pl) in p.planes.iter().enumerate() {
                    let sg = if pl.upper { 1.0 } else { -1.0 };
                    for node in 0..p.mesh.x.len() {
                        let d = 3 * node + pl.axis;
                        if s.active[k][node] && sg * r[d] > (set.rtol * reaction).max(floor) {
                            s.active[k][node] = false;
                            changed = true;
                        } else if !s.active[k][node]
                            && sg * (p.mesh.x[node][pl.axis] + s.u[d] - pl.pos) > 1e-12 * self.length
                        {
                            s.active[k][node] = true;
                            changed = true;
                        }
                    }
                }
                // Uzawa: the pressures become the multipliers until every contacting slave node
                // is within its pair's gap tolerance of the master surface.
                let pos = |node: usize| current(&p.mesh, &s.u, node);
                let mut pair_force = Vec::new();
                let mut pair_nodes = Vec::new();
                let mut pair_penetration = Vec::new();
                for (pair, lam) in p.pairs.iter().zip(s.multiplier.iter_mut()) {
                    let (mut force, mut nodes, mut deepest) = ([0.0; 3], 0, 0.0f64);
                    for i in 0..pair.slave.len() {
                        let gap = pair.gap(i, &pos);
                        let pr = pair.pressure(lam[i], gap.g);
                        if pr > 0.0 {
                            nodes += 1;
                            deepest = deepest.max(-gap.g);
                            for k in 0..3 {
                                force[k] += pair.area[i] * pr * gap.nu[k];
                            }
                        }
                        if pr != lam[i] && (gap.g.abs() > pair.gap_tolerance || pr == 0.0) {
                            lam[i] = pr;
                            changed = true;
                        }
                    }
                    pair_force.push(force);
                    pair_nodes.push(nodes);
                    pair_penetration.push(deepest);
                }
                // Proximal point: re-anchor until the regularisation carries no force.
                if kappa > 0.0 {
                    let pull = (0..n)
                        .filter(|&d| bc[d].is_none())
                        .map(|d| kappa * (s.u[d] - anchor[d]).abs())
                        .fold(0.0, f64::max);
                    if pull > (set.rtol * reaction).max(floor) {
                        anchor.copy_from_slice(&s.u);
                        changed = true;
                    }
                }
                if !changed {
                    let mut plane_force = Vec::new();
                    let mut contact_nodes = Vec::new();
                    for (k, pl) in p.planes.iter().enumerate() {
                        let sg = if pl.upper { 1.0 } else { -1.0 };
                        plane_force.push(
                            -(0..p.mesh.x.len())
                                .filter(|&m| s.active[k][m])
                                .map(|m| sg * r[3 * m + pl.axis])
                                .sum::<f64>(),
                        );
                        contact_nodes.push(s.active[k].iter().filter(|&&a| a).count());
                    }
                    return Ok(Equilibrium {
                        plane_force,
                        contact_nodes,
                        pair_force,
                        pair_nodes,
                        pair_penetration,
                        iterations: it,
                        residual: res,
                    });
                }
                continue;
            }
            // Line search: the full step unless it inverts an element or (once the constrained
            // dofs are on target) fails to lower the energy (Armijo, c = 1e-4).
            let proximal_energy = |u: &[f64]| {
                (0..n)
                    .filter(|&d| bc[d].is_none())
                    .map(|d| 0.5 * kappa * (u[d] - anchor[d]).powi(2))
                    .sum::<f64>()
            };
            let e0 = if moving {
                None
            } else {
                self.energy(p, &s.u, &s.multiplier).map(|e| e + proximal_energy(&s.u))
            };
            let slope: f64 = (0..n).map(|d| r[d] * du[d]).sum();
            let mut alpha = 1.0;
            let mut trial = vec![0.0; n];
            loop {
                for d in 0..n {
                    trial[d] = s.u[d] + alpha * du[d];
                }
                match (self.energy(p, &trial, &s.multiplier).map(|e| e + proximal_energy(&trial)), e0) {
                    (Some(_), None) => break,
                    // The energy is a sum over all elements: near convergence its round-off (~1e-11
                    // relative) exceeds the decrease a Newton step can make, which must not count as failure.
                    (Some(e1), Some(e0)) if e1 <= e0 + 1e-4 * alpha * slope + 1e-11 * e0.abs() => break,
                    _ => {}
                }
                alpha *= 0.5;
                if alpha < 1e-6 {
                    return Err(format!(
                        "line search failed at Newton iteration {it} (free residual {res:.3e} N)"
                    ));
                }
            }
            s.u.copy_from_slice(&trial);
            // Admit penetrating nodes right away (they become constrained in the next iteration).
            for (k, pl) in p.planes.iter().enumerate() {
                let sg = if pl.upper { 1.0 } else { -1.0 };
                for node in 0..p.mesh.x.len() {
                    if !s.active[k][node]
                        && sg * (p.mesh.x[node][pl.axis] + s.u[3 * node + pl.axis] - pl.pos)
                            > 1e-12 * self.length
                    {
                        s.active[k][node] = true;
                    }
                }
            }
        }
        Err(format!("Newton did not converge in {} iterations (free residual {last:.3e} N)", set.max_iter))
    }
}

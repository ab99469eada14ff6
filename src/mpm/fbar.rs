//! F-bar against volumetric locking (de Souza Neto, Perić, Dunne & Owen 1996, Int. J. Solids
//! Struct. 33, 3277–3296): the per-cell state at a trial displacement and the exact Hessian of the
//! F-bar energy (`Locking::FBar` of the implicit step). It reads the implicit step's state only
//! through its arguments, so the step's module uses this one and not the other way round.

use faer::sparse::Triplet;

use super::constitutive::{det, Mat, Tangent};
use super::grid::{incremental_gradient, Stencil};
use super::points::Points;

/// Per-point and per-cell quantities of F-bar at the trial displacement.
#[derive(Clone, Debug, Default)]
pub(super) struct FBarState<const D: usize> {
    /// Points sorted by cell, and the start of each cell's run in `order` (plus the end).
    pub(super) order: Vec<usize>,
    pub(super) start: Vec<usize>,
    /// Per cell: Σ V⁰, J̄, τ̄ = Σ V⁰τ / Σ V⁰.
    pub(super) vol0: Vec<f64>,
    pub(super) jbar: Vec<f64>,
    pub(super) taubar: Vec<f64>,
    /// Per point: F, F⁻ᵀ, J, s = (J̄/J)^{1/D}, F̄ = sF, P̄ = P(F̄), τ = P̄ : F̄ / D.
    pub(super) f: Vec<Mat<D>>,
    pub(super) finv_t: Vec<Mat<D>>,
    pub(super) j: Vec<f64>,
    pub(super) s: Vec<f64>,
    pub(super) fb: Vec<Mat<D>>,
    pub(super) pb: Vec<Mat<D>>,
    pub(super) tau: Vec<f64>,
}

impl<const D: usize> FBarState<D> {
    /// Groups the points by the cell that holds them (keyed by the cell's lowest corner node: with
    /// multilinear shape functions all points of a cell share its 2^D nodes).
    pub(super) fn group(&mut self, stencils: &[Stencil<D>]) {
        self.order.clear();
        self.order.extend(0..stencils.len());
        self.order.sort_by_key(|&p| stencils[p].nodes[0]);
        self.start.clear();
        for (k, &p) in self.order.iter().enumerate() {
            if k == 0 || stencils[self.order[k - 1]].nodes[0] != stencils[p].nodes[0] {
                self.start.push(k);
            }
        }
        self.start.push(stencils.len());
        let (np, nc) = (stencils.len(), self.start.len() - 1);
        for v in [&mut self.vol0, &mut self.jbar, &mut self.taubar] {
            v.clear();
            v.resize(nc, 0.0);
        }
        for v in [&mut self.j, &mut self.s, &mut self.tau] {
            v.clear();
            v.resize(np, 0.0);
        }
        for v in [&mut self.f, &mut self.finv_t, &mut self.fb, &mut self.pb] {
            v.clear();
            v.resize(np, Mat::<D>::identity());
        }
    }

    /// F, J of every point and J̄ of every cell at displacement u; the points' F̄. Returns the first
    /// inverted point (J ≤ 0) as an error.
    pub(super) fn kinematics(
        &mut self,
        pts: &Points<D>,
        stencils: &[Stencil<D>],
        dof_of: &[usize],
        u: &[f64],
    ) -> Result<(), (usize, f64)> {
        for c in 0..self.start.len() - 1 {
            let (mut v, mut vj) = (0.0, 0.0);
            for &p in &self.order[self.start[c]..self.start[c + 1]] {
                let f = incremental_gradient(&stencils[p], dof_of, u) * pts.f[p];
                let j = det(&f);
                if j <= 0.0 {
                    return Err((p, j));
                }
                self.f[p] = f;
                self.j[p] = j;
                v += pts.vol0[p];
                vj += pts.vol0[p] * j;
            }
            self.vol0[c] = v;
            self.jbar[c] = vj / v;
            for &p in &self.order[self.start[c]..self.start[c + 1]] {
                self.s[p] = (self.jbar[c] / self.j[p]).powf(1.0 / D as f64);
                self.fb[p] = self.f[p] * self.s[p];
            }
        }
        Ok(())
    }
}

/// Adds the F-bar stiffness (the exact Hessian of Σ_p V⁰_p W(F̄_p), de Souza Neto et al. 1996,
/// Section 4, written here as the directional derivative of P_eff) to `ws.trip`, one cell at a time:
/// all points of a cell share its 2^D nodes, so each column is one nodal direction δu = e_k at one
/// corner, δF_p = e_k ⊗ G_p (G_p = F_p(t)ᵀ ∇N), and with a = F⁻ᵀ : δF = δJ/J, ā = δJ̄/J̄:
/// δF̄ = s δF + F̄ (ā − a)/D, δP̄ = A(F̄) : δF̄, δτ = (δP̄ : F̄ + P̄ : δF̄)/D, δτ̄ = V⁰-mean of δτ,
/// δP_eff = δs P̄ + s δP̄ − F⁻ᵀ δFᵀ F⁻ᵀ c + F⁻ᵀ (δτ̄ J/J̄ + τ̄ (J/J̄)(a − ā) − δτ),
/// with δs = s (ā − a)/D and c = τ̄ J/J̄ − τ. `stencils`, `dof_of` and `tangent` (A = ∂P/∂F at F̄)
/// are the step's per point and per node data; rows for which `free_row` is false (bound or
/// prescribed dofs, identity rows) are skipped.
pub(super) fn fbar_stiffness<const D: usize>(
    pts: &Points<D>,
    fb: &FBarState<D>,
    stencils: &[Stencil<D>],
    dof_of: &[usize],
    tangent: &[Tangent<D>],
    free_row: impl Fn(usize) -> bool,
    trip: &mut Vec<Triplet<usize, usize, f64>>,
) {
    let n = Stencil::<D>::LEN;
    let dd = D as f64;
    let mut dfb: Vec<Mat<D>> = Vec::new();
    let mut dpb: Vec<Mat<D>> = Vec::new();
    let mut a_p: Vec<f64> = Vec::new();
    let mut dtau: Vec<f64> = Vec::new();
    for c in 0..fb.start.len() - 1 {
        let cell = &fb.order[fb.start[c]..fb.start[c + 1]];
        let (jbar, taubar, v0) = (fb.jbar[c], fb.taubar[c], fb.vol0[c]);
        let nodes = stencils[cell[0]].nodes;
        dfb.resize(cell.len(), Mat::<D>::zeros());
        dpb.resize(cell.len(), Mat::<D>::zeros());
        a_p.resize(cell.len(), 0.0);
        dtau.resize(cell.len(), 0.0);
        for cb in 0..n {
            let rb = dof_of[nodes[cb]];
            for k in 0..D {
                // δF_p = e_k ⊗ G_p: row k of δF is G_p.
                let df = |p: usize| {
                    let g = pts.f[p].transpose() * stencils[p].grad[cb];
                    let mut m = Mat::<D>::zeros();
                    for l in 0..D {
                        m[(k, l)] = g[l];
                    }
                    m
                };
                let mut abar = 0.0;
                for (q, &p) in cell.iter().enumerate() {
                    a_p[q] = fb.finv_t[p].dot(&df(p));
                    abar += pts.vol0[p] * fb.j[p] * a_p[q];
                }
                abar /= v0 * jbar;
                let mut dtaubar = 0.0;
                for (q, &p) in cell.iter().enumerate() {
                    let dfp = df(p);
                    dfb[q] = dfp * fb.s[p] + fb.fb[p] * ((abar - a_p[q]) / dd);
                    let a4 = &tangent[p];
                    dpb[q] = Mat::<D>::from_fn(|i, jj| {
                        let mut v = 0.0;
                        for kk in 0..D {
                            for ll in 0..D {
                                v += a4[i][jj][kk][ll] * dfb[q][(kk, ll)];
                            }
                        }
                        v
                    });
                    dtau[q] = (dpb[q].dot(&fb.fb[p]) + fb.pb[p].dot(&dfb[q])) / dd;
                    dtaubar += pts.vol0[p] * dtau[q];
                }
                dtaubar /= v0;
                for (q, &p) in cell.iter().enumerate() {
                    let dfp = df(p);
                    let (s, j, fit) = (fb.s[p], fb.j[p], fb.finv_t[p]);
                    let ds = s * (abar - a_p[q]) / dd;
                    let cc = taubar * j / jbar - fb.tau[p];
                    let dpe = fb.pb[p] * ds + dpb[q] * s - fit * dfp.transpose() * fit * cc
                        + fit * (dtaubar * j / jbar + taubar * (j / jbar) * (a_p[q] - abar) - dtau[q]);
                    let st = &stencils[p];
                    let ft = pts.f[p].transpose();
                    for ca in 0..n {
                        let ra = dof_of[nodes[ca]];
                        let f = dpe * (ft * st.grad[ca]) * pts.vol0[p];
                        for i in 0..D {
                            let row = ra * D + i;
                            if free_row(row) {
                                trip.push(Triplet::new(row, rb * D + k, f[i]));
                            }
                        }
                    }
                }
            }
        }
    }
}

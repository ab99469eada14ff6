//! Residual, incremental potential, tangent and its factorization for the implicit step
//! (Nezamabadi et al. 2019, Eqs. 4, 9, 12, 13, A.3, A.4).

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{Pair, SparseColMat, SymbolicSparseColMat, Triplet};
use faer::Mat as FMat;

use super::{DofState, Locking, Pattern, Workspace};
use crate::mpm::constitutive::{det, Constitutive, Law};
use crate::mpm::fbar::fbar_stiffness;
use crate::mpm::grid::{incremental_gradient, Stencil};
use crate::mpm::points::Points;

/// The largest force term of the residual (inertia, external, internal): the scale of its
/// round-off.
pub(super) fn force_scale<const D: usize>(pts: &Points<D>, law: &Law, ws: &Workspace<D>, dt: f64) -> f64 {
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
pub(super) fn potential<const D: usize>(
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
    if ws.pw.enabled {
        let (p, s) = super::point_walls::potential(ws, u);
        pi += p;
        scale += s;
    }
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

/// Stress and tangent at the trial displacement; residual R = f_ext + f_int − M a (Eq. A.4) with
/// a from Eq. 12.
pub(super) fn evaluate<const D: usize>(
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
                    fb.finv_t[p] = crate::mpm::constitutive::inverse(&fb.f[p]).transpose();
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
    if ws.pw.enabled {
        super::point_walls::add_residual(ws);
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
pub(super) fn assemble_and_solve<const D: usize>(
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
pub(in crate::mpm) fn compliance<const D: usize>(ws: &Workspace<D>, dofs: &[usize], out: &mut Vec<f64>) {
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
pub(in crate::mpm) fn factorize<const D: usize>(
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
        let free_row = |r: usize| ws.state[r] == DofState::Free;
        fbar_stiffness(pts, &ws.fbar, &ws.stencils, &ws.dof_of, &ws.tangent, free_row, &mut ws.trip);
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
    if ws.pw.enabled {
        super::point_walls::add_tangent(ws);
    }
    // The pattern (the triplets' positions, in order) stays the same over a step's Newton
    // iterations and re-solves, and often over steps: its sort, compressed structure and symbolic
    // LU are kept and reused while it does (bit for bit what building them again gives).
    let same = ws.pattern.as_ref().is_some_and(|c| {
        c.idx.len() == ws.trip.len()
            && c.idx.iter().zip(&ws.trip).all(|(p, t)| p.row == t.row && p.col == t.col)
    });
    if !same {
        if let Some(old) = ws.pattern.take() {
            ws.pattern_idx = old.idx;
        }
        let mut idx = std::mem::take(&mut ws.pattern_idx);
        idx.clear();
        idx.extend(ws.trip.iter().map(|t| Pair { row: t.row, col: t.col }));
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(ndof, ndof, &idx)
            .map_err(|e| format!("step {step}: cannot assemble the stiffness matrix: {e:?}"))?;
        let lu = SymbolicLu::try_new(symbolic.as_ref())
            .map_err(|e| format!("step {step}: sparse LU (symbolic) failed: {e:?}"))?;
        ws.pattern = Some(Pattern { idx, symbolic, argsort, lu });
    }
    let c = ws.pattern.as_ref().expect("set above");
    ws.vals.clear();
    ws.vals.extend(ws.trip.iter().map(|t| t.val));
    let k = SparseColMat::new_from_argsort(c.symbolic.clone(), &c.argsort, &ws.vals)
        .map_err(|e| format!("step {step}: cannot assemble the stiffness matrix: {e:?}"))?;
    let lu = Lu::try_new_with_symbolic(c.lu.clone(), k.as_ref())
        .map_err(|e| format!("step {step}: sparse LU failed: {e:?}"))?;
    ws.lu = Some(lu);
    Ok(())
}

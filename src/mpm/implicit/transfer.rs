//! Transfers between the material points and the grid for the implicit step: points to grid at the
//! start (shape functions, lumped mass, nodal velocity of Eq. 5, body force of Eq. 4, wall bounds)
//! and grid to points at the end (Eqs. 9, 13, FLIP/PIC velocity).

use super::walls::wall_bounds;
use super::{point_walls, Body, DofState, Fixed, Locking, StepOptions, Wall, WallsOn, Workspace};
use crate::mpm::constitutive::{det, Constitutive, Law};
use crate::mpm::grid::{incremental_gradient, Stencil, Vector};
use crate::mpm::points::Points;

/// First part of a step: shape functions, lumped mass, nodal velocity (Eq. 5), body force, wall
/// bounds and Dirichlet conditions of every grid dof. The contact forces are zero after it.
pub(in crate::mpm) fn prepare<const D: usize>(
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

    // Walls on the points: no nodal bounds, the corner constraints of `point_walls` instead.
    let on_points = opt.walls_on == WallsOn::Points && !walls.is_empty();
    wall_bounds(grid, if on_points { &[] } else { walls }, dt, step, ws)?;
    if on_points {
        point_walls::prepare(pts, &body.law, walls, dt, grid.h, ws);
    } else {
        ws.pw.enabled = false;
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

/// Moves the points with the converged grid motion: x += Σ N u, v by FLIP/PIC, F = ΔF F,
/// V = J V⁰ (Eq. 13), σ = P Fᵀ / J (Eq. 9).
pub(super) fn update_points<const D: usize>(
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

//! The walls of the implicit step as bounds on the nodal displacement (Moreau's velocity-Signorini
//! condition at grid nodes, Nezamabadi et al. 2019, Section 2.2, Fig. 2a) and the active set that
//! enforces them inside Newton: a bound dof is held at its wall, a free dof is projected onto it.

use super::{DofState, Wall, Workspace};
use crate::mpm::grid::Grid;

/// Bounds of every dof from the walls (tightest one wins): s (u − Δt v_wall) ≥ −max(d, 0) with d the
/// node's gap to the wall plane at the start of the step. A node pinched between two walls is an error.
pub(super) fn wall_bounds<const D: usize>(
    grid: &Grid<D>,
    walls: &[Wall],
    dt: f64,
    step: usize,
    ws: &mut Workspace<D>,
) -> Result<(), String> {
    let ndof = ws.active.len() * D;
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
    Ok(())
}

/// Projects dof k onto its wall bounds; true when it was on or past one (the bound becomes active).
pub(super) fn clamp<const D: usize>(ws: &mut Workspace<D>, k: usize) -> bool {
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

/// Projected Newton (Bertsekas): a free node resting on its wall (within `tol`) that the residual
/// pushes into the wall is bound for the solve; otherwise the projection of the line-search path
/// would drop part of the increment and what remains need not descend.
pub(super) fn bind_resting<const D: usize>(ws: &mut Workspace<D>, tol: f64) {
    for k in 0..ws.u.len() {
        if ws.state[k] == DofState::Free {
            let (lo, hi) = (ws.lo[k], ws.hi[k]);
            let (at_lo, at_hi) = (ws.u[k] <= lo.0 + tol, ws.u[k] >= hi.0 - tol);
            if (at_lo && ws.res[k] < 0.0) || (at_hi && ws.res[k] > 0.0) {
                ws.u[k] = if at_lo { lo.0 } else { hi.0 };
                ws.state[k] = DofState::Wall(if at_lo { lo.1 } else { hi.1 });
            }
        }
    }
}

/// After Newton converged for the active set: every free dof on or past its wall is put on it
/// (the bound becomes active); true when one was.
pub(super) fn clamp_free<const D: usize>(ws: &mut Workspace<D>) -> bool {
    let mut changed = false;
    for k in 0..ws.u.len() {
        if ws.state[k] == DofState::Free && clamp(ws, k) {
            changed = true;
        }
    }
    changed
}

/// Releases every bound dof whose wall would have to pull: the reaction is −R, and it counts as
/// pulling only beyond the residual's round-off (`fscale`, the force scale). True when one was.
pub(super) fn release_pulling<const D: usize>(ws: &mut Workspace<D>, walls: &[Wall], fscale: f64) -> bool {
    let mut changed = false;
    for k in 0..ws.u.len() {
        if let DofState::Wall(w) = ws.state[k] {
            // Reaction −R; released only when it pulls beyond the residual's round-off.
            if walls[w].side * -ws.res[k] < -1e-12 * fscale {
                ws.state[k] = DofState::Free;
                changed = true;
            }
        }
    }
    changed
}

/// Adds each wall's normal load on the body (the reactions −R of the dofs bound to it, positive
/// when it pushes) to `load`.
pub(super) fn add_wall_loads<const D: usize>(ws: &Workspace<D>, walls: &[Wall], load: &mut [f64]) {
    for k in 0..ws.u.len() {
        if let DofState::Wall(w) = ws.state[k] {
            load[w] += walls[w].side * -ws.res[k];
        }
    }
}

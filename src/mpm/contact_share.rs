//! Where a body–body contact acts on a body at a node that carries only a sliver of it.
//!
//! A contact node's displacement stands for the displacement of the body's material there only if
//! the node has a fair share of that material. A node touched by the edge of one point's support
//! has mass m_I = Σ_p m_p N_I(x_p) and stiffness both of order N_I(x_p) ≪ 1: a contact force on it
//! moves the node by cells while the material hardly moves, and the strongly distorted point next
//! to it makes the body's response to that force non-convex (the compaction's stop, docs/mpm.md:
//! a node of 3.6e-8 kg/m, 0.7 % of its body's largest nodal mass, snapped by 1.3 h between two
//! states of its body under a 1.9 N/m contact force, and the contact iterations never settled).
//! Dropping such a node from the contact is not a remedy: the bodies then pass through each other
//! there.
//!
//! At such a node the contact acts on the material near the node instead. The material's mean
//! displacement at node I is ū_I = Σ_p m_p N_I(x_p) u(x_p) / m_I = Σ_J w_IJ u_J with
//! w_IJ = Σ_p m_p N_I(x_p) N_J(x_p) / m_I: the row of the consistent mass matrix over the lumped
//! mass. The weights sum to one (a rigid motion of the body moves ū_I with it), and for a node
//! touched by a single point ū_I is that point's displacement. By virtual work the contact force r
//! conjugate to ū_I is the set of nodal forces w_IJ r: every point supporting I takes its share
//! m_p N_I(x_p)/m_I of r and spreads it with its own shape functions. The sliver node itself keeps
//! only the fraction w_II ≈ N_I(x_p) of the force, the rest going to its body's well-massed nodes
//! through the points that are really there; non-penetration is still imposed at that node, on
//! the material's displacement rather than on the node's.

use super::grid::Stencil;
use super::implicit::Workspace;

/// Below this fraction of its body's largest nodal mass, a contact node's contact acts through the
/// material's mean displacement (module doc). With 2 × 2 points per cell a node inside the body
/// carries 4 point masses, one on a flat face 2, one at a square corner 1; below 1/100 a node
/// carries less than 4 % of one point's mass (Σ_p N_I(x_p) < 0.04): only the far corner of some
/// points' supports reaches it. The compaction's stalling node carried 0.7 % of the largest mass.
/// Used only where the nodal contact has no fixed point (`contact::step_bodies`): applied at every
/// step it changes converged results, since a node newly reached by a point that has just crossed a
/// grid line is a sliver too and its contact then engages that point one cell early. Measured on
/// the head-on discs: at 1/16 the restitution fell from 0.7912 / 0.8499 / 0.8796 to 0.7369 /
/// 0.7852 / 0.8022 (Δt = 10 / 5 / 2.5 µs, h = 1 mm); at 1/100 those were unchanged but at
/// h = 0.5 mm it fell from 0.8778 to 0.8386 (594 sliver contact sides over the collision).
pub(super) const SLIVER: f64 = 1.0 / 100.0;

/// Whether grid node `node` carries less than `SLIVER` of its body's largest nodal mass.
pub(super) fn is_sliver<const D: usize>(ws: &Workspace<D>, node: usize, max_mass: f64) -> bool {
    ws.node_mass[node] < SLIVER * max_mass
}

/// Appends to `out` the (active node, weight) terms through which a contact at grid node `node`
/// acts on the body of workspace `ws` (point masses `mass`, largest nodal mass `max_mass`): the
/// node itself with weight 1, or, for a sliver node, the row w_IJ of the module doc (weights
/// summing to one). Returns the number of terms appended.
pub(super) fn contact_terms<const D: usize>(
    ws: &Workspace<D>,
    mass: &[f64],
    node: usize,
    max_mass: f64,
    out: &mut Vec<(usize, f64)>,
) -> usize {
    let start = out.len();
    if !is_sliver(ws, node, max_mass) {
        out.push((ws.dof_of[node], 1.0));
        return 1;
    }
    let mut total = 0.0;
    for (p, st) in ws.stencils.iter().enumerate() {
        let Some(c) = (0..Stencil::<D>::LEN).find(|&c| st.nodes[c] == node) else { continue };
        let share = mass[p] * st.n[c];
        if share <= 0.0 {
            continue;
        }
        total += share;
        for j in 0..Stencil::<D>::LEN {
            let w = share * st.n[j];
            let a = ws.dof_of[st.nodes[j]];
            if w <= 0.0 || a == usize::MAX {
                continue;
            }
            match out[start..].iter_mut().find(|t| t.0 == a) {
                Some(t) => t.1 += w,
                None => out.push((a, w)),
            }
        }
    }
    for t in out[start..].iter_mut() {
        t.1 /= total;
    }
    out.len() - start
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mpm::grid::{Grid, Vector};

    /// Two cells side by side (h = 1): a point near the far corner of the left cell's support and
    /// four points filling the right cell. Node (0, 0) is touched only by the first point, with
    /// N = 0.1 × 0.1: a sliver. Its contact acts through that point: the weights are the point's
    /// own shape functions (summing to one), so the node itself keeps 1 % of the force and the node
    /// (1, 1) next to the material 81 %. A node with a fair share of the mass acts alone.
    #[test]
    fn a_sliver_node_acts_through_the_point_that_touches_it() {
        let grid = Grid::new(Vector::<2>::zeros(), 1.0, [2, 1]).unwrap();
        let xs = [(0.9, 0.9), (1.25, 0.25), (1.75, 0.25), (1.25, 0.75), (1.75, 0.75)];
        let mut ws = Workspace::<2> {
            stencils: xs.iter().map(|&(x, y)| grid.stencil(&Vector::<2>::new(x, y)).unwrap()).collect(),
            ..Default::default()
        };
        let mass = vec![1.0; xs.len()];
        ws.node_mass = vec![0.0; grid.n_nodes()];
        for (p, st) in ws.stencils.iter().enumerate() {
            for c in 0..Stencil::<2>::LEN {
                ws.node_mass[st.nodes[c]] += mass[p] * st.n[c];
            }
        }
        // Every node carries mass here: active index = grid index.
        ws.dof_of = (0..grid.n_nodes()).collect();
        let max_mass = ws.node_mass.iter().fold(0.0f64, |m, &v| m.max(v));
        let corner = grid.node_index([0, 0]);
        assert!(is_sliver(&ws, corner, max_mass), "{} of {max_mass}", ws.node_mass[corner]);
        let mut terms = Vec::new();
        assert_eq!(contact_terms(&ws, &mass, corner, max_mass, &mut terms), 4);
        let weight =
            |ijk: [usize; 2]| terms.iter().find(|t| t.0 == grid.node_index(ijk)).map_or(0.0, |t| t.1);
        assert!((terms.iter().map(|t| t.1).sum::<f64>() - 1.0).abs() < 1e-15);
        for (ijk, n) in [([0, 0], 0.01), ([1, 0], 0.09), ([0, 1], 0.09), ([1, 1], 0.81)] {
            assert!((weight(ijk) - n).abs() < 1e-14, "{ijk:?}: {} against {n}", weight(ijk));
        }
        // The middle node (1, 0) carries a fair share: it acts alone, with weight 1.
        let middle = grid.node_index([1, 0]);
        assert!(!is_sliver(&ws, middle, max_mass));
        terms.clear();
        assert_eq!(contact_terms(&ws, &mass, middle, max_mass, &mut terms), 1);
        assert_eq!(terms[0], (middle, 1.0));
    }
}

//! Contact Dynamics between MPM bodies and with rigid walls, with Coulomb friction (Nezamabadi et
//! al. 2019, Section 2.2, Figs. 1–2, Eqs. 6–7).
//!
//! Multi-mesh scheme: every body keeps its proper grid (its own nodal masses, velocities and
//! implicit solve); the proper grids are windows of one common lattice (same h, origins on the
//! lattice), so a node of the common grid is the same point in every proper grid that holds it.
//! A node carrying mass of two bodies A and B is a potential contact node. There
//!
//! - the normal n points from A to B. With ∇m_I = Σ_p m_p ∇N_I(x_p) (the derivative of the nodal
//!   mass with respect to the node's position) a body's ∇m points out of it at its boundary
//!   nodes (moving a node away from the points lowers N_I there), so n = (∇m_A − ∇m_B)/|∇m_A − ∇m_B|;
//! - the force on B is r and on A −r (momentum is exchanged, never created);
//! - the step's relative displacement g = u_B − u_A (= Δt × the relative velocity at t + Δt, Eq. 10)
//!   obeys the velocity-Signorini condition g·n ≥ 0, r·n ≥ 0, (g·n)(r·n) = 0 (Fig. 2a) and Coulomb's
//!   law |r_t| ≤ μ r·n, with r_t = −|r_t| g_t/|g_t| when g_t ≠ 0 (Fig. 2b).
//!
//! A rigid wall is a partner of infinite mass. Its normal condition is the exact active set inside
//! each body's Newton solve (`implicit`); its friction acts on the tangential dofs of the nodes
//! bound to it, with the wall's nodal reaction as the normal force.
//!
//! The forces enter each body's momentum balance (Eq. 4) as external nodal forces and the body is
//! re-solved implicitly. Between solves the forces are updated on the linear model of the bodies
//! at their solution (`delassus`): Eqs. 6–7 write r = r⁰ − (m/Δt²) g with the nodal masses alone,
//! which is the node's true response only while c Δt ≲ h; the update here uses each body's
//! compliance (M/Δt² + K)⁻¹ at the contact nodes instead, and intersects the linear relation with
//! the Signorini and Coulomb graphs by projected Gauss–Seidel. The iteration stops when no force
//! update changes a nodal relative displacement by more than `tolerance` × h over the step.

use rayon::prelude::*;

use super::contact_law::ContactNode;
pub use super::contact_law::{signorini_coulomb, ContactOptions};
use super::contact_share::{contact_terms, is_sliver};
use super::delassus::Delassus;
use super::grid::{Grid, Vector};
use super::implicit::{
    add_point_wall_loads, finish, prepare, solve, Body, DofState, StepOptions, Wall, Workspace,
};

/// Iterations without a new low of the contact correction after which an attempt is taken as
/// cycling. Measured on 100-disc compactions (λ = 0, 3, 100 MPa; 662 steps traced): every step
/// that converges does so in at most 7 iterations, and its correction never goes more than one
/// iteration without a new low; the steps whose nodal contact has no fixed point repeat a cycle of
/// period 2 (or 4 in the quick compaction) exactly, and used to spend all of `max_iter` (500) on it
/// before the sliver-node attempt converged in 4.
const STALL: usize = 30;

/// What one multi-body step reports.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactReport {
    /// Contact iterations (each one re-solves every body).
    pub iterations: usize,
    /// Newton iterations summed over bodies and contact iterations.
    pub newton_iterations: usize,
    /// Normal force of each wall on all bodies, positive when it pushes (N, or N/m in 2-D).
    pub wall_load: Vec<f64>,
    /// Friction force of each wall on all bodies, per axis (the wall's own axis is 0).
    pub wall_friction: Vec<[f64; 3]>,
    /// Nodes carrying mass of two bodies, and how many of them push (r·n > 0).
    pub contact_nodes: usize,
    pub active_contacts: usize,
    /// Contact-node sides at a sliver node of their body, acting through the material near the
    /// node (`contact_share`): non-zero only in a step whose nodal contact did not converge and
    /// was solved again that way.
    pub sliver_sides: usize,
    /// Pairs of bodies with at least one pushing contact node (the contacts of the packing).
    pub touching_pairs: usize,
    /// Σ r·n over the body–body contact nodes (N, or N/m in 2-D).
    pub contact_normal_force: f64,
    /// The last iteration's largest change of a nodal relative displacement [m].
    pub correction: f64,
}

/// Buffers of the multi-body step, kept between steps.
#[derive(Clone, Debug, Default)]
pub struct ContactWorkspace<const D: usize> {
    pub bodies: Vec<Workspace<D>>,
    /// Per body, per grid node: ∇m = Σ_p m_p ∇N_I(x_p), pointing out of the body.
    mass_grad: Vec<Vec<Vector<D>>>,
    /// Per body, per dof: the wall friction force.
    wall_ft: Vec<Vec<f64>>,
    nodes: Vec<ContactNode<D>>,
    terms: Vec<(usize, f64)>,
    delassus: Delassus<D>,
}

/// Offset of a proper grid in the common lattice of the first body's grid.
fn lattice_offset<const D: usize>(g: &Grid<D>, g0: &Grid<D>) -> Result<[i64; D], String> {
    let mut off = [0i64; D];
    for d in 0..D {
        let x = (g.origin[d] - g0.origin[d]) / g0.h;
        off[d] = x.round() as i64;
        if (x - x.round()).abs() > 1e-6 || (g.h - g0.h).abs() > 1e-12 * g0.h {
            return Err(format!(
                "contact: the bodies' grids are not windows of one lattice (cell sizes {} and {}, origin offset {x} cells along axis {d})",
                g0.h, g.h
            ));
        }
    }
    Ok(off)
}

/// Advances all bodies by one implicit step with Contact Dynamics between them and with the walls
/// (module doc). Walls are given at time t; the caller moves them afterwards.
pub fn step_bodies<const D: usize>(
    bodies: &mut [Body<D>],
    walls: &[Wall],
    opt: &StepOptions,
    copt: &ContactOptions,
    step: usize,
    cws: &mut ContactWorkspace<D>,
) -> Result<ContactReport, String> {
    try_step(bodies, walls, opt, copt, step, cws).map_err(|f| f.message)
}

/// What a step that did not converge reports: its message, and whether the points had already
/// moved (a point inverted in the final update), after which the step cannot be taken again.
struct StepFailure {
    message: String,
    points_moved: bool,
}

impl From<String> for StepFailure {
    fn from(message: String) -> Self {
        Self { message, points_moved: false }
    }
}

/// One step of Δt with the walls moved to t + Δt after it, cut into two steps of Δt/2 (each cut
/// again, at most `cuts` times) where it does not converge: the usual remedy of implicit codes
/// when Newton or the contact iterations fail, since a shorter step raises every node's inertia
/// term M/Δt² against the stiffness and the contact forces, and shortens the motion the
/// linearisation must cover. A step that converges is exactly `step_bodies` followed by the wall
/// motion, so scenes that never fail give the same numbers with or without cuts. Returns the
/// report of the step's last sub-step, its iteration counts summed over the sub-steps, and the
/// number of sub-steps taken (1 when the step was not cut).
pub fn step_bodies_cut<const D: usize>(
    bodies: &mut [Body<D>],
    walls: &mut [Wall],
    opt: &StepOptions,
    copt: &ContactOptions,
    step: usize,
    cws: &mut ContactWorkspace<D>,
    cuts: u32,
) -> Result<(ContactReport, usize), String> {
    cut_step(bodies, walls, opt, copt, step, cws, cuts, 0)
}

/// `step_bodies_cut` at `depth` cuts below the whole step, with `cuts` more allowed.
#[allow(clippy::too_many_arguments)]
fn cut_step<const D: usize>(
    bodies: &mut [Body<D>],
    walls: &mut [Wall],
    opt: &StepOptions,
    copt: &ContactOptions,
    step: usize,
    cws: &mut ContactWorkspace<D>,
    cuts: u32,
    depth: u32,
) -> Result<(ContactReport, usize), String> {
    match try_step(bodies, walls, opt, copt, step, cws) {
        Ok(r) => {
            for w in walls.iter_mut() {
                w.position += w.velocity * opt.dt;
            }
            Ok((r, 1))
        }
        Err(f) if cuts > 0 && !f.points_moved => {
            // The points are as they were before the step (a failed attempt moves none), so the
            // step can be taken again in two halves. Allocates only on this rare path.
            let start: Vec<f64> = walls.iter().map(|w| w.position).collect();
            let half = StepOptions { dt: 0.5 * opt.dt, ..*opt };
            let (r1, n1) = cut_step(bodies, walls, &half, copt, step, cws, cuts - 1, depth + 1)?;
            let (mut r2, n2) = cut_step(bodies, walls, &half, copt, step, cws, cuts - 1, depth + 1)?;
            // The walls end where an uncut step would have put them, to the last bit.
            for (w, s) in walls.iter_mut().zip(start) {
                w.position = s + w.velocity * opt.dt;
            }
            r2.iterations += r1.iterations;
            r2.newton_iterations += r1.newton_iterations;
            r2.sliver_sides += r1.sliver_sides;
            Ok((r2, n1 + n2))
        }
        Err(f) if depth == 0 => Err(f.message),
        // Name the sub-step that failed (the step number is that of the whole step).
        Err(f) => Err(format!(
            "{} (in a sub-step of Δt = {:.3e} s, the step cut in halves {depth} times)",
            f.message, opt.dt
        )),
    }
}

fn try_step<const D: usize>(
    bodies: &mut [Body<D>],
    walls: &[Wall],
    opt: &StepOptions,
    copt: &ContactOptions,
    step: usize,
    cws: &mut ContactWorkspace<D>,
) -> Result<ContactReport, StepFailure> {
    let nb = bodies.len();
    let h = bodies.first().ok_or_else(|| String::from("contact: no body"))?.grid.h;
    cws.bodies.resize_with(nb, Workspace::default);
    cws.mass_grad.resize_with(nb, Vec::new);
    cws.wall_ft.resize_with(nb, Vec::new);
    // Proper grids follow their bodies (one cell of room for the step's motion).
    for body in bodies.iter_mut() {
        let (mut lo, mut hi) = (Vector::<D>::repeat(f64::INFINITY), Vector::<D>::repeat(f64::NEG_INFINITY));
        for x in &body.points.x {
            lo = lo.inf(x);
            hi = hi.sup(x);
        }
        body.grid.follow(&lo, &hi, 1);
    }
    // The bodies' own work runs in parallel (Section 5: each particle's MPM solve is independent
    // given the contact forces); the results do not depend on the number of threads.
    bodies
        .par_iter()
        .zip(cws.bodies.par_iter_mut())
        .try_for_each(|(body, ws)| prepare(body, walls, &[], opt, step, ws))?;
    for (b, body) in bodies.iter().enumerate() {
        let ws = &mut cws.bodies[b];
        let mg = &mut cws.mass_grad[b];
        mg.clear();
        mg.resize(body.grid.n_nodes(), Vector::<D>::zeros());
        for (p, st) in ws.stencils.iter().enumerate() {
            for c in 0..super::grid::Stencil::<D>::LEN {
                mg[st.nodes[c]] += st.grad[c] * body.points.mass[p];
            }
        }
        let ft = &mut cws.wall_ft[b];
        ft.clear();
        ft.resize(ws.u.len(), 0.0);
    }

    // Potential contact nodes: common-lattice nodes with mass of two bodies.
    cws.nodes.clear();
    cws.terms.clear();
    let max_mass: Vec<f64> =
        cws.bodies.iter().map(|w| w.node_mass.iter().fold(0.0, |m: f64, &v| m.max(v))).collect();
    for a in 0..nb {
        let off_a = lattice_offset(&bodies[a].grid, &bodies[0].grid)?;
        for b in a + 1..nb {
            let off_b = lattice_offset(&bodies[b].grid, &bodies[0].grid)?;
            let (ga, gb) = (&bodies[a].grid, &bodies[b].grid);
            let npa_b = gb.nodes_per_axis();
            for &ia in cws.bodies[a].active.iter() {
                let ijk = ga.node_ijk(ia);
                let mut local = [0usize; D];
                let mut inside = true;
                for d in 0..D {
                    let g = ijk[d] as i64 + off_a[d] - off_b[d];
                    if g < 0 || g >= npa_b[d] as i64 {
                        inside = false;
                        break;
                    }
                    local[d] = g as usize;
                }
                if !inside {
                    continue;
                }
                let ib = gb.node_index(local);
                // Both bodies must carry mass there (a massless active node has no inertia to
                // exchange momentum with).
                if cws.bodies[b].dof_of[ib] == usize::MAX
                    || cws.bodies[b].node_mass[ib] <= 0.0
                    || cws.bodies[a].node_mass[ia] <= 0.0
                {
                    continue;
                }
                let n = cws.mass_grad[a][ia] - cws.mass_grad[b][ib];
                // Equal and opposite gradients cannot happen between two bodies on opposite
                // sides; a zero sum (a node deep inside both, i.e. overlap) has no normal.
                if n.norm() == 0.0 {
                    return Err(format!(
                        "step {step}: bodies {a} and {b} overlap at grid node {ia} of body {a} (no contact normal)"
                    ).into());
                }
                let start = cws.terms.len();
                cws.terms.push((cws.bodies[a].dof_of[ia], 1.0));
                cws.terms.push((cws.bodies[b].dof_of[ib], 1.0));
                cws.nodes.push(ContactNode {
                    a,
                    b,
                    ta: (start, 1),
                    tb: (start + 1, 1),
                    ia,
                    ib,
                    n: n.normalize(),
                    r: Vector::<D>::zeros(),
                });
            }
        }
    }

    let mut report = ContactReport {
        wall_load: vec![0.0; walls.len()],
        wall_friction: vec![[0.0; 3]; walls.len()],
        contact_nodes: cws.nodes.len(),
        ..Default::default()
    };
    let limit = copt.tolerance * h;
    let (mut converged, mut stalled) = (false, false);
    // First every contact acts on its node. Where that has no fixed point the iterations cycle
    // (a sliver node snapping between two states of its body, `contact_share`): the step is then
    // solved again from the start with the contacts of the sliver nodes acting through the
    // material near them.
    for attempt in 0..2 {
        if attempt == 1 {
            cws.terms.clear();
            for c in cws.nodes.iter_mut() {
                c.r = Vector::<D>::zeros();
                for (side, body, node) in [(&mut c.ta, c.a, c.ia), (&mut c.tb, c.b, c.ib)] {
                    let start = cws.terms.len();
                    let len = contact_terms(
                        &cws.bodies[body],
                        &bodies[body].points.mass,
                        node,
                        max_mass[body],
                        &mut cws.terms,
                    );
                    report.sliver_sides += usize::from(is_sliver(&cws.bodies[body], node, max_mass[body]));
                    *side = (start, len);
                }
            }
            if report.sliver_sides == 0 {
                break;
            }
            for ft in cws.wall_ft.iter_mut() {
                ft.fill(0.0);
            }
        }
        // A correction that has not found a new low in STALL iterations is cycling (the nodal
        // attempt without a fixed point): stop the attempt there rather than at `max_iter`.
        let (mut best, mut since_best) = (f64::INFINITY, 0);
        stalled = false;
        for it in 1..=copt.max_iter {
            report.iterations += 1;
            // Contact forces into Eq. 4 as external nodal forces, then each body's implicit solve.
            for b in 0..nb {
                let ws = &mut cws.bodies[b];
                for k in 0..ws.fext.len() {
                    ws.fext[k] = ws.fbody[k] + cws.wall_ft[b][k];
                }
            }
            for c in &cws.nodes {
                for &(j, w) in &cws.terms[c.ta.0..c.ta.0 + c.ta.1] {
                    for d in 0..D {
                        cws.bodies[c.a].fext[j * D + d] -= w * c.r[d];
                    }
                }
                for &(j, w) in &cws.terms[c.tb.0..c.tb.0 + c.tb.1] {
                    for d in 0..D {
                        cws.bodies[c.b].fext[j * D + d] += w * c.r[d];
                    }
                }
            }
            report.newton_iterations += bodies
                .par_iter()
                .zip(cws.bodies.par_iter_mut())
                .map(|(body, ws)| solve(body, walls, opt, step, ws, it > 1).map(|r| r.iterations))
                .collect::<Result<Vec<_>, String>>()?
                .iter()
                .sum::<usize>();
            let corr = cws.delassus.update(
                bodies,
                walls,
                opt,
                copt,
                step,
                &mut cws.bodies,
                &mut cws.nodes,
                &cws.terms,
                &mut cws.wall_ft,
            )?;
            report.correction = corr;
            if corr <= limit {
                converged = true;
                break;
            }
            if corr < best {
                (best, since_best) = (corr, 0);
            } else {
                since_best += 1;
                if since_best >= STALL {
                    stalled = true;
                    break;
                }
            }
        }
        if converged {
            break;
        }
    }
    if !converged {
        return Err(format!(
            "step {step}: contact iterations did not converge {} (also with the sliver nodes' contacts on their material): a force update still moves a node by {:.3e} m (criterion {:.1e} × h = {limit:.3e} m); reduce Δt",
            if stalled { format!("(no new low of the correction in {STALL} iterations)") } else { format!("in {} iterations", copt.max_iter) },
            report.correction, copt.tolerance
        ).into());
    }
    // The last solve is within the tolerance of the final forces: report its loads, move points.
    for b in 0..nb {
        let ws = &cws.bodies[b];
        for a in 0..ws.active.len() {
            for ax in 0..D {
                if let DofState::Wall(w) = ws.state[a * D + ax] {
                    report.wall_load[w] += walls[w].side * -ws.res[a * D + ax];
                    for d in 0..D {
                        if d != ax {
                            report.wall_friction[w][d] += cws.wall_ft[b][a * D + d];
                        }
                    }
                }
            }
        }
    }
    for ws in &cws.bodies {
        add_point_wall_loads(ws, &mut report.wall_load);
    }
    // The nodes of one pair are consecutive (built pair by pair above).
    let mut last_pair = None;
    for c in &cws.nodes {
        let rn = c.r.dot(&c.n);
        if rn > 0.0 {
            report.active_contacts += 1;
            report.contact_normal_force += rn;
            if last_pair != Some((c.a, c.b)) {
                report.touching_pairs += 1;
                last_pair = Some((c.a, c.b));
            }
        }
    }
    bodies
        .par_iter_mut()
        .zip(cws.bodies.par_iter())
        .try_for_each(|(body, ws)| finish(body, opt, step, ws))
        .map_err(|message| StepFailure { message, points_moved: true })?;
    Ok(report)
}

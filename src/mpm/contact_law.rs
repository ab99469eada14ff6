//! The contact law at one node of Contact Dynamics (Nezamabadi et al. 2019, Section 2.2, Fig. 2,
//! Eqs. 6–7): the velocity-Signorini condition and Coulomb's law, the node record and the options
//! of the contact iterations. Used by the iterations (`contact`) and the force update on the
//! bodies' compliances (`delassus`).

use super::grid::Vector;

/// Friction coefficients and the stop rule of the contact iterations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactOptions {
    /// Coulomb coefficient between a body and a wall (≥ 0).
    pub wall_friction: f64,
    /// Coulomb coefficient between two bodies (≥ 0).
    pub body_friction: f64,
    /// Converged when the largest change of a nodal relative displacement over the step caused by
    /// a force update is below `tolerance` × h.
    pub tolerance: f64,
    pub max_iter: usize,
}

impl Default for ContactOptions {
    fn default() -> Self {
        // 1e-7 of a cell per step is far below the contact's own discretisation error (one cell,
        // Section 2.2); with the bodies' compliances it is reached in 5–15 re-solves (measured on
        // colliding discs and on a block sliding under friction).
        Self { wall_friction: 0.0, body_friction: 0.0, tolerance: 1e-7, max_iter: 500 }
    }
}

impl ContactOptions {
    pub fn validate(&self) -> Result<(), String> {
        for (name, mu) in [("wall_friction", self.wall_friction), ("body_friction", self.body_friction)] {
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(format!("contact: {name} must be a finite friction coefficient ≥ 0, got {mu}"));
            }
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) || self.max_iter == 0 {
            return Err(format!(
                "contact: tolerance must be positive and max_iter at least 1 (got {}, {})",
                self.tolerance, self.max_iter
            ));
        }
        Ok(())
    }
}

/// A node of the common grid carrying mass of bodies `a` and `b` (a < b).
#[derive(Clone, Copy, Debug)]
pub(super) struct ContactNode<const D: usize> {
    pub(super) a: usize,
    pub(super) b: usize,
    /// Where the contact acts on each body: a range of `ContactWorkspace::terms`, (active node,
    /// weight) pairs; the node itself with weight 1, or the material near a sliver node
    /// (`contact_share`).
    pub(super) ta: (usize, usize),
    pub(super) tb: (usize, usize),
    /// The node's index in each body's grid.
    pub(super) ia: usize,
    pub(super) ib: usize,
    /// Unit normal from A to B.
    pub(super) n: Vector<D>,
    /// Force on B (−r on A).
    pub(super) r: Vector<D>,
}

/// Eqs. 6–7 intersected with the Signorini and Coulomb graphs (Nezamabadi et al. 2019, Section
/// 2.2, Fig. 2) at one node: from the force r⁰ on B and the step's relative displacement g = u_B − u_A
/// obtained with it, the linear relation r = r⁰ − k g with k = m_red/Δt² gives the force that
/// would stop the relative motion; its normal part is kept if it pushes (else the node opens,
/// r = 0), its tangential part is projected onto the Coulomb disc |r_t| ≤ μ r_n. At a fixed point
/// r_n > 0 ⇒ g_n = 0 and r_n = 0 ⇒ g_n ≥ 0 (Signorini); |r_t| < μ r_n ⇒ g_t = 0 (stick), else g_t
/// is opposite to r_t (sliding resisted).
pub fn signorini_coulomb<const D: usize>(
    r0: Vector<D>,
    g: Vector<D>,
    n: Vector<D>,
    k: f64,
    mu: f64,
) -> Vector<D> {
    let trial = r0 - g * k;
    let rn = trial.dot(&n);
    if rn <= 0.0 {
        return Vector::<D>::zeros();
    }
    let rt = trial - n * rn;
    n * rn + project_disc(rt, mu * rn)
}

/// The vector v scaled back onto the ball of the given radius when it lies outside.
pub(super) fn project_disc<const D: usize>(v: Vector<D>, radius: f64) -> Vector<D> {
    let l = v.norm();
    if l > radius {
        if radius > 0.0 {
            v * (radius / l)
        } else {
            Vector::<D>::zeros()
        }
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fixed points of the node update are the Signorini–Coulomb solutions.
    #[test]
    fn node_update_satisfies_signorini_and_coulomb() {
        let n = Vector::<2>::new(0.6, 0.8);
        let t = Vector::<2>::new(-0.8, 0.6);
        let k = 2.0;
        // Approaching and sliding fast: pushes, friction at the cone's edge, opposite to the slip.
        let r = signorini_coulomb(Vector::<2>::zeros(), -n * 1.0 + t * 3.0, n, k, 0.5);
        assert!((r.dot(&n) - 2.0).abs() < 1e-14);
        assert!((r.dot(&t) + 1.0).abs() < 1e-14);
        // Approaching, slow slip: sticks (the whole slip is cancelled).
        let r = signorini_coulomb(Vector::<2>::zeros(), -n * 1.0 + t * 0.1, n, k, 0.5);
        assert!((r.dot(&t) + 0.2).abs() < 1e-14);
        // Separating: no force.
        assert_eq!(signorini_coulomb(n * 0.3, n * 1.0, n, k, 0.5), Vector::<2>::zeros());
        // μ = 0: no tangential force at all.
        let r = signorini_coulomb(Vector::<2>::zeros(), -n + t, n, k, 0.0);
        assert!(r.dot(&t).abs() < 1e-15);
    }
}

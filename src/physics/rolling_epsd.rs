//! LIGGGHTS 3.8 `pair_style gran ... rolling_friction epsd` and `epsd2` (rolling_model_epsd.h,
//! rolling_model_epsd2.h): the elastic–plastic spring–dashpot rolling resistance of Iwashita & Oda
//! (1998, J. Eng. Mech. 124, 285) in the form of Ai et al. (2011, Powder Technol. 206, 269,
//! model C, Eqs. 13–17).
//!
//! A rolling spring torque M_k is built incrementally from the relative rolling rotation,
//!
//! M_k ← M_k + k_r Δt ω_t,  capped at |M_k| ≤ μ_r R |F_n|,
//!
//! with ω_t the relative angular velocity without its part along the contact normal (torsion is
//! not rolling), μ_r the type pair's `coefficientRollingFriction`, R the rolling lever (R* =
//! r_i r_j/(r_i + r_j) for a pair, the particle radius for a wall) and F_n the normal sub-model's
//! force (elastic plus damping, plus the cohesion under `tangential_reduce on`: LIGGGHTS' `Fn`).
//! The capped spring is the contact's history (three numbers). The torque on particle i is −M,
//! on a partner particle +M, where
//!
//! - `epsd`: k_r = 2.25 k_n μ_r² R² (Ai et al. Eq. 15, k_n the normal law's stiffness) and, while
//!   the spring is below the cap, M = M_k + C_r ω_t with C_r = η_r 2 √(I_r k_r) (Eq. 16, η_r the
//!   pair's `coefficientRollingViscousDamping`, I_r the rolling inertia of [`pair_inertia`] or
//!   [`wall_inertia`]); at the cap the damping is off (Eq. 17, "full mobilisation"): M = M_k;
//! - `epsd2`: k_r = k_t R² (k_t the normal law's tangential stiffness) and no damping: M = M_k.
//!
//! The history is neither rotated nor projected when the contact turns (LIGGGHTS accumulates it
//! as it is) and is zero for a new contact and once the surfaces part.

use super::Vec3;

/// Which spring–dashpot, with what only it reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Epsd {
    /// `epsd`: k_r from k_n, and the viscous damping ratio η_r ≥ 0 of the dashpot.
    Epsd { damping: f64 },
    /// `epsd2`: k_r from k_t, no dashpot.
    Epsd2,
}

/// One contact as the rolling model reads it.
#[derive(Debug, Clone, Copy)]
pub struct Rolling {
    /// μ_r [-].
    pub mu_r: f64,
    /// Lever R [m] (see the module doc).
    pub reff: f64,
    /// Normal and tangential stiffness of the normal law at this overlap [N/m].
    pub kn: f64,
    pub kt: f64,
    /// Normal force F_n of the normal sub-model [N] (its magnitude is read).
    pub fnorm: f64,
    /// Rolling inertia I_r [kg m²] (read by `epsd`'s dashpot only).
    pub inertia: f64,
    /// Relative rolling angular velocity (LIGGGHTS' `wr`: ω_i − ω_j for a pair; see
    /// [`super::pair`] for a wall) [rad/s], and the unit contact normal.
    pub wr: Vec3,
    pub en: Vec3,
}

/// The rolling torque on particle i (a partner particle gets its negative), from the spring
/// `spring` of the last step, which is advanced over `dt` and capped in place (the caller keeps it
/// on a time step). Same operations in the same order as LIGGGHTS' `calcRollTorque`.
#[inline]
pub fn torque(model: Epsd, r: &Rolling, dt: f64, spring: &mut Vec3) -> Vec3 {
    let (w, en) = (r.wr, r.en);
    let wn = w.x * en.x + w.y * en.y + w.z * en.z;
    let wt = Vec3::new(w.x - en.x * wn, w.y - en.y * wn, w.z - en.z * wn);
    let kr = stiffness(model, r);
    let mut m = *spring + wt * (dt * kr);
    let mag = (m.x * m.x + m.y * m.y + m.z * m.z).sqrt();
    let max = r.fnorm.abs() * r.reff * r.mu_r;
    if mag > max {
        m *= max / mag;
        *spring = m;
    } else {
        *spring = m;
        if let Epsd::Epsd { damping } = model {
            let c = damping * 2.0 * (r.inertia * kr).sqrt();
            m += wt * c;
        }
    }
    -m
}

/// The rolling stiffness k_r [N m/rad]: `epsd` 2.25 k_n μ_r² R² (Ai et al. 2011 Eq. 15), `epsd2`
/// k_t R² (LIGGGHTS rolling_model_epsd2.h).
#[inline]
pub fn stiffness(model: Epsd, r: &Rolling) -> f64 {
    match model {
        Epsd::Epsd { .. } => 2.25 * r.kn * r.mu_r * r.mu_r * r.reff * r.reff,
        Epsd::Epsd2 => r.kt * r.reff * r.reff,
    }
}

/// Rolling inertia of a pair as `epsd` takes it (rolling_model_epsd.h, 3D): 1.4 I_i I_j/(I_i + I_j)
/// with I = m r² of each particle (the moment of inertia about the contact point of a sphere
/// rolling on a fixed partner, (2/5 + 1) m r², in series).
#[inline]
pub fn pair_inertia(mi: f64, ri: f64, mj: f64, rj: f64) -> f64 {
    let (a, b) = (mi * ri * ri, mj * rj * rj);
    1.4 * a * b / (a + b)
}

/// Rolling inertia of a particle on a wall (rolling_model_epsd.h, 3D): 1.4 m r².
#[inline]
pub fn wall_inertia(m: f64, r: f64) -> f64 {
    1.4 * m * r * r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contact(w: Vec3) -> Rolling {
        Rolling {
            mu_r: 0.1,
            reff: 1e-3,
            kn: 1e4,
            kt: 2e4,
            fnorm: 0.5,
            inertia: 1e-9,
            wr: w,
            en: Vec3::new(0.0, 0.0, 1.0),
        }
    }

    /// Below the cap the spring grows by k_r Δt ω_t (torsion left out) and epsd2 returns −M_k.
    #[test]
    fn spring_grows_with_the_rolling_rotation() {
        let r = contact(Vec3::new(2.0, 0.0, 5.0));
        let mut s = Vec3::zeros();
        let t = torque(Epsd::Epsd2, &r, 1e-6, &mut s);
        let kr = stiffness(Epsd::Epsd2, &r);
        assert!((kr - 2e4 * 1e-6).abs() < 1e-18);
        assert_eq!(s, Vec3::new(2.0 * (1e-6 * kr), 0.0, 0.0));
        assert_eq!(t, -s);
    }

    /// At the cap |M_k| = μ_r R |F_n| and epsd adds no damping; below it, it does.
    #[test]
    fn cap_and_damping() {
        let r = contact(Vec3::new(0.0, 3.0, 0.0));
        let max = 0.5 * 1e-3 * 0.1;
        let mut s = Vec3::new(0.0, 2.0 * max, 0.0);
        let t = torque(Epsd::Epsd { damping: 0.3 }, &r, 1e-6, &mut s);
        assert!((s.norm() - max).abs() < 1e-18 && t == -s);
        let mut s = Vec3::zeros();
        let t = torque(Epsd::Epsd { damping: 0.3 }, &r, 1e-6, &mut s);
        let kr = stiffness(Epsd::Epsd { damping: 0.3 }, &r);
        let c = 0.3 * 2.0 * (1e-9 * kr).sqrt();
        assert!((t.y + s.y + 3.0 * c).abs() < 1e-12 * c);
    }
}

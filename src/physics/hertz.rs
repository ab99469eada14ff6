//! Hertz normal force with viscous damping and the history tangential force with Coulomb
//! truncation: Ghods et al. (2022) Eqs. 5–6 and App. C, identical to LIGGGHTS
//! `pair_style gran model hertz tangential history` (docs/spec.md §1).
//!
//! Two sub-models in the LAMMPS GRANULAR manner: [`normal`] gives the normal force and the
//! stiffness/damping coefficients that [`tangential_history`] then reads.

use super::material::PairCoeffs;
// The tangential sub-model is a choice stored with the pair coefficients, so it lives with them
// in `material`; re-exported here beside the two functions it selects. `material` imports nothing
// from this file: the dependency points one way.
pub use super::material::Tangential;
use super::Vec3;

/// √(5/6), the constant of Eqs. C.2 and C.7.
/// The correctly rounded double of √(5/6), the value LIGGGHTS uses: the 16-digit literal
/// 0.9128709291752768 is one ulp lower and breaks bit-parity with LIGGGHTS `hertz` whenever damping acts.
const SQRT_FIVE_SIXTHS: f64 = 0.912_870_929_175_276_9;

/// Output of the normal sub-model for one contact.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NormalForce {
    /// Total normal force F_n = k_n δ − γ_n v_n [N]; positive pushes the bodies apart. It can be
    /// negative at the end of a fast separation (viscous pull), exactly as in LIGGGHTS without `limitForce`.
    pub force: f64,
    /// Elastic part k_n δ [N].
    pub elastic: f64,
    /// k_n = (4/3) E* √(R δ) [N/m] (Eq. C.1 times √(Rδ), Eq. 5).
    pub kn: f64,
    /// k_t = 8 G* √(R δ) [N/m] (Eq. C.6 times √(Rδ)).
    pub kt: f64,
    /// γ_n = −2 √(5/6) β √(S_n m_eff) [kg/s] (Eq. C.2; ≥ 0 because β ≤ 0).
    pub gamma_n: f64,
    /// γ_t = −2 √(5/6) β √(S_t m_eff) [kg/s] (Eq. C.7).
    pub gamma_t: f64,
}

/// Effective radius R* = r_i r_j/(r_i + r_j) (Eq. 5) and effective mass m* = m_i m_j/(m_i + m_j) of
/// a particle pair, from one division (the pair loop's hot path has few enough that one more
/// shows). A rigid wall is the limit r_j, m_j → ∞: R* = r_i, m* = m_i.
#[inline(always)]
pub fn effective_radius_and_mass(ri: f64, rj: f64, mi: f64, mj: f64) -> (f64, f64) {
    let (rs, ms) = (ri + rj, mi + mj);
    let inv = 1.0 / (rs * ms);
    (ri * rj * ms * inv, mi * mj * rs * inv)
}

/// Normal sub-model (Eq. 5, App. C). `delta` is the overlap [m] (already including the
/// multi-contact radius changes), `vn = (v_i − v_j)·n` the normal relative velocity [m/s]
/// (negative when approaching). A non-positive overlap gives no force: with the multi-contact
/// radius changes the effective overlap can turn non-positive while the bodies still touch
/// geometrically, and the right answer then is "no contact", not an abort.
#[inline(always)]
pub fn normal(c: &PairCoeffs, delta: f64, reff: f64, meff: f64, vn: f64) -> NormalForce {
    if delta <= 0.0 {
        return NormalForce::default();
    }
    let sqrtval = (reff * delta).sqrt();
    let sn = 2.0 * c.e_star * sqrtval;
    let st = 8.0 * c.g_star * sqrtval;
    let kn = 4.0 / 3.0 * c.e_star * sqrtval;
    let gamma_n = -2.0 * SQRT_FIVE_SIXTHS * c.beta * (sn * meff).sqrt();
    // −2√(5/6) β √(S_t m*) = γ_n √(S_t/S_n), and S_t/S_n = 4G*/E* is fixed per material pair.
    let gamma_t = gamma_n * c.damping_ratio_t_n;
    let elastic = kn * delta;
    NormalForce { force: elastic - gamma_n * vn, elastic, kn, kt: st, gamma_n, gamma_t }
}

/// Closed-form Hertz force of an undamped contact, F = (4/3) E* √R δ^{3/2}: the analytic limit
/// tests and the static reference compare against.
#[inline]
pub fn hertz_force(e_star: f64, reff: f64, delta: f64) -> f64 {
    if delta <= 0.0 {
        0.0
    } else {
        4.0 / 3.0 * e_star * reff.sqrt() * delta.powf(1.5)
    }
}

/// Inverse of [`hertz_force`]: the overlap that carries force `f` ≥ 0.
#[inline]
pub fn hertz_overlap(e_star: f64, reff: f64, f: f64) -> f64 {
    if f <= 0.0 {
        0.0
    } else {
        (3.0 * f / (4.0 * e_star * reff.sqrt())).powf(2.0 / 3.0)
    }
}

/// History tangential sub-model (Eq. 6, App. C; LIGGGHTS `tangential history`).
///
/// `shear` is the contact's elastic tangential displacement ξ [m], updated in place: ξ += v_t,rel dt,
/// projected on the tangent plane of `en`; F_t = −k_t ξ; if |F_t| > μ|F_n| it is scaled to μ|F_n|
/// and ξ = −F_t/k_t, otherwise the damping −γ_t v_t,rel is added. Returns F_t on body i [N].
/// With μ = 0 the result is exactly zero and ξ is reset, so callers may skip the call entirely.
// Always inlined into the pair force (see `pair::forces`): an out-of-line call costs more than its body.
#[inline(always)]
pub fn tangential_history(
    shear: &mut Vec3,
    vtr: &Vec3,
    en: &Vec3,
    dt: f64,
    normal: &NormalForce,
    friction: f64,
) -> Vec3 {
    *shear += vtr * dt;
    let rsht = shear.dot(en);
    *shear -= en * rsht;
    let kt = normal.kt;
    let mut ft = -kt * *shear;
    let ft_friction = friction * normal.force.abs();
    // Compare squares: the square root is needed only when the contact slides. Sliding implies
    // |ξ| > 0 (the limit μ|F_n| is ≥ 0), so the division below is safe.
    let shrmag_sq = shear.norm_squared();
    if kt * kt * shrmag_sq > ft_friction * ft_friction {
        let ft_shear = kt * shrmag_sq.sqrt();
        ft *= ft_friction / ft_shear;
        *shear = -ft / kt;
    } else {
        ft -= normal.gamma_t * vtr;
    }
    ft
}

/// Tangential force without history (LIGGGHTS `tangential no_history`): F_t = −γ v_t,rel with
/// γ = min(γ_t, μ|F_n| / |v_t,rel|), so |F_t| never exceeds the Coulomb limit. No state.
#[inline]
pub fn tangential_no_history(vtr: &Vec3, normal: &NormalForce, friction: f64) -> Vec3 {
    let vrel = vtr.norm();
    let ft_friction = friction * normal.force.abs();
    let gamma = if ft_friction < normal.gamma_t * vrel { ft_friction / vrel } else { normal.gamma_t };
    -gamma * vtr
}

#[cfg(test)]
mod constant_tests {
    #[test]
    fn sqrt_five_sixths_is_the_correctly_rounded_double() {
        assert_eq!(super::SQRT_FIVE_SIXTHS, (5.0f64 / 6.0).sqrt());
    }
}

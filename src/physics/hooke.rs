//! LIGGGHTS 3.8 `gran model hooke` (normal_model_hooke.h): a linear spring-dashpot whose
//! stiffness is fitted to Hertz at a characteristic impact velocity V
//! (`fix property/global characteristicVelocity scalar V`).
//!
//! With Y* the effective Young's modulus (as for Hertz), R* = r_i r_j/(r_i + r_j) (r_i for a
//! wall), m* = m_i m_j/(m_i + m_j) (m_i for a wall) and e the pair's coefficient of restitution:
//!
//! - k_n = 16/15 √R* Y* (15 m* V² / (16 √R* Y*))^{1/5}, independent of the overlap;
//! - k_t = k_n (`ktToKnUser on`: k_t = 0.285714286 k_n, the literal LIGGGHTS uses for 2/7);
//! - γ_n = √(4 m* k_n / (1 + (π / ln e)²));
//! - γ_t = γ_n (`tangential_damping on`, the default), 0 when off;
//! - F_n = k_n δ − γ_n v_n, with v_n = (v_i − v_j)·n negative on approach; `limitForce on`
//!   sets a negative F_n to 0 (default off).
//!
//! The tangential force is the same `tangential history` (or `no_history`) sub-model as for
//! Hertz ([`super::hertz::tangential_history`]): it reads k_t, γ_t and F_n from [`NormalForce`].
//! The `viscous` option (a Stokes-number dependent restitution) is not modelled.

pub use super::hertz::NormalForce;
pub use super::material::Hooke;

/// The literal LIGGGHTS multiplies k_n by under `ktToKnUser on` (2/7 to nine digits).
const KT_TO_KN_USER: f64 = 0.285714286;

/// Normal sub-model of `model hooke`: `e_star` = Y* [Pa], `delta` the overlap [m], `reff`, `meff`
/// as above, `vn` the normal relative velocity [m/s]. No force for a non-positive overlap (as
/// [`super::hertz::normal`]). Same operations in the same order as LIGGGHTS.
#[inline]
pub fn normal(e_star: f64, h: &Hooke, delta: f64, reff: f64, meff: f64, vn: f64) -> NormalForce {
    if delta <= 0.0 {
        return NormalForce::default();
    }
    let sqrtval = reff.sqrt();
    let v = h.char_vel;
    let kn = 16.0 / 15.0 * sqrtval * e_star * (15.0 * meff * v * v / (16.0 * sqrtval * e_star)).powf(0.2);
    let kt = if h.kt_to_kn { kn * KT_TO_KN_USER } else { kn };
    let p = std::f64::consts::PI / h.ln_e;
    let gamma_n = (4.0 * meff * kn / (1.0 + p * p)).sqrt();
    let gamma_t = if h.tangential_damping { gamma_n } else { 0.0 };
    let elastic = kn * delta;
    let mut force = -gamma_n * vn + elastic;
    if h.limit_force && force < 0.0 {
        force = 0.0;
    }
    NormalForce { force, elastic, kn, kt, gamma_n, gamma_t }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(e: f64) -> Hooke {
        Hooke {
            char_vel: 2.0,
            ln_e: f64::ln(e),
            tangential_damping: true,
            limit_force: false,
            kt_to_kn: false,
        }
    }

    /// Two glass-like spheres of the LIGGGHTS tutorial `hysteresis/in.noHysteresis`: Y = 5 MPa,
    /// ν = 0.45, r = 1.5 mm, ρ = 2500 kg/m³, e = 0.9, V = 2 m/s. By hand:
    /// Y* = Y / (2 (1 − ν²)) = 3 134 796.238 Pa, R* = 0.75 mm, m* = m/2 = 1.767 146e-5 kg,
    /// k_n = (16/15)^{4/5} Y*^{4/5} R*^{2/5} m*^{1/5} V^{2/5} = 1378.10217 N/m,
    /// γ_n = √(4 m* k_n / (1 + (π/ln 0.9)²)) = 0.0104614244 kg/s.
    #[test]
    fn stiffness_and_damping_match_a_hand_calculation() {
        let y = 1.0 / (2.0 * (1.0 - 0.45 * 0.45) / 5e6);
        let m = 2500.0 * 4.0 / 3.0 * std::f64::consts::PI * 0.0015f64.powi(3);
        let (reff, meff) = (0.00075, m / 2.0);
        let h = params(0.9);
        let n = normal(y, &h, 1e-5, reff, meff, -0.2);
        let rel = |a: f64, b: f64| ((a - b) / b).abs();
        assert!(rel(n.kn, 1378.1021680337856) < 1e-13, "kn {}", n.kn);
        assert!(rel(n.gamma_n, 0.010461424354276775) < 1e-13, "gamma_n {}", n.gamma_n);
        assert_eq!(n.kt, n.kn);
        assert_eq!(n.gamma_t, n.gamma_n);
        assert!(rel(n.elastic, 1378.1021680337856e-5) < 1e-13);
        // Approaching (v_n < 0): the damping adds to the repulsion.
        assert!(rel(n.force, n.elastic + 0.2 * n.gamma_n) < 1e-15);
        // The closed form independent of the grouping of the factors.
        let closed =
            (16.0f64 / 15.0).powf(0.8) * y.powf(0.8) * reff.powf(0.4) * meff.powf(0.2) * 2f64.powf(0.4);
        assert!(rel(n.kn, closed) < 1e-13);
    }

    #[test]
    fn options_and_limits() {
        let h = Hooke { tangential_damping: false, limit_force: true, kt_to_kn: true, ..params(0.5) };
        // Fast separation: the viscous pull would make F_n negative; limitForce clips it.
        let n = normal(1e7, &h, 1e-6, 1e-3, 1e-4, 100.0);
        assert_eq!(n.force, 0.0);
        assert_eq!(n.gamma_t, 0.0);
        assert_eq!(n.kt, n.kn * KT_TO_KN_USER);
        // e = 1: ln e = 0, no damping.
        let n = normal(1e7, &params(1.0), 1e-6, 1e-3, 1e-4, 100.0);
        assert_eq!(n.gamma_n, 0.0);
        assert_eq!(n.force, n.elastic);
        // No overlap, no force.
        assert_eq!(normal(1e7, &params(0.9), 0.0, 1e-3, 1e-4, -1.0), NormalForce::default());
    }
}

//! LIGGGHTS 3.8 `gran model hooke/hysteresis` (normal_model_hooke_hysteresis.h): a
//! Walton–Braun-type hysteretic linear spring with adhesion (Walton & Braun 1986, J. Rheol. 30,
//! 949; the adhesive branch as in Luding 2008, Granular Matter 10, 235, Eqs. 4–6).
//!
//! k_n, k_t, γ_n and γ_t are those of `model hooke` ([`super::hooke`], fitted to Hertz at the
//! characteristic velocity); k_t = k_n and γ_t = γ_n (or 0 with `tangential_damping off`). Three
//! per-type-pair ratios set the loop:
//!
//! - `coefficientMaxElasticStiffness` φ₂ = k₂,max / k_n (> 1): the stiffest unloading slope;
//! - `coefficientAdhesionStiffness` φ_c = k_c / k_n (≥ 0): the slope of the adhesive branch −k_c δ;
//! - `coefficientPlasticityDepth` φ_f (≥ 0): the maximum overlap δ_lim = φ₂/(φ₂ − 1) φ_f 2R*
//!   beyond which the unloading slope stays k₂,max.
//!
//! The contact keeps one history value, the largest overlap δ_max seen so far (reset when the
//! surfaces part). With k₂ = k_n + (k₂,max − k_n) δ_max/δ_lim (k₂,max once δ_max ≥ δ_lim):
//! loading follows k_n δ; unloading and reloading follow k₂ (δ − δ₀), δ₀ the plastic overlap where
//! that line crosses zero, down to the adhesive branch −k_c δ; on the adhesive branch δ_max moves
//! so that the unloading line meets −k_c δ at the current overlap. The normal force is that
//! elastic-plastic-adhesive part plus the damping −γ_n v_n. LIGGGHTS 3.8 ignores `limitForce`
//! and `ktToKnUser` for this model (the deck parser refuses them rather than ignore them).

pub use super::hertz::NormalForce;
use super::material::{Hooke, Hysteresis};

/// Normal sub-model of `model hooke/hysteresis`: `e_star` = Y* [Pa], the hooke parameters and
/// the loop's ratios, `delta` the overlap [m],
/// `reff`, `meff` as in [`super::hooke::normal`], `vn` the normal relative velocity [m/s],
/// `delta_max` the contact's history (largest overlap so far, updated in place; the caller keeps
/// it only on a time step). No force and no change of history for a non-positive overlap.
/// Same operations in the same order as LIGGGHTS.
#[inline]
pub fn normal(
    e_star: f64,
    (h, hy): (&Hooke, &Hysteresis),
    delta: f64,
    reff: f64,
    meff: f64,
    vn: f64,
    delta_max: &mut f64,
) -> NormalForce {
    if delta <= 0.0 {
        return NormalForce::default();
    }
    let sqrtval = reff.sqrt();
    let v = h.char_vel;
    let kn = 16.0 / 15.0 * sqrtval * e_star * (15.0 * meff * v * v / (16.0 * sqrtval * e_star)).powf(0.2);
    let kt = kn;
    let p = std::f64::consts::PI / h.ln_e;
    let gamma_n = (4.0 * meff * kn / (1.0 + p * p)).sqrt();
    let gamma_t = if h.tangential_damping { gamma_n } else { 0.0 };
    let k2_max = kn * hy.max_stiffness;
    let kc = kn * hy.adhesion_stiffness;
    if delta > *delta_max {
        *delta_max = delta;
    }
    let dmax = *delta_max;
    let dlim = (k2_max / (k2_max - kn)) * hy.plasticity_depth * 2.0 * reff;
    // On the adhesive branch the loop's history moves: the δ_max whose unloading line meets −k_c δ
    // at this overlap (root of δ_max² − δ δ_max − (k_n + k_c) δ δ_lim/(k₂,max − k_n) = 0).
    let adhesive_dmax =
        || 0.5 * (delta + (delta * delta + 4.0 * ((kn + kc) * delta * dlim / (k2_max - kn))).sqrt());
    let hys = if dmax >= dlim {
        // Beyond the plasticity depth: the unloading slope is k₂,max, anchored at δ_lim.
        let line = k2_max * (delta - dlim) + kn * dlim;
        if line >= -kc * delta {
            line
        } else {
            *delta_max = adhesive_dmax();
            -kc * delta
        }
    } else {
        let k2 = kn + (k2_max - kn) * dmax / dlim;
        let line = k2 * (delta - dmax) + kn * dmax;
        if line >= kn * delta {
            kn * delta
        } else if line > -kc * delta {
            line
        } else {
            *delta_max = adhesive_dmax();
            -kc * delta
        }
    };
    let force = hys + -gamma_n * vn;
    NormalForce { force, elastic: hys, kn, kt, gamma_n, gamma_t }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> (Hooke, Hysteresis) {
        (
            Hooke {
                char_vel: 2.0,
                ln_e: 1.0f64.ln(),
                tangential_damping: true,
                limit_force: false,
                kt_to_kn: false,
            },
            Hysteresis { max_stiffness: 2.0, adhesion_stiffness: 0.2, plasticity_depth: 0.05 },
        )
    }

    /// A quasi-static loop (v_n = 0, so no damping): load to δ₁ < δ_lim along k_n δ, unload along
    /// k₂ (δ − δ₀) to the adhesive branch, then follow −k_c δ to separation. The work lost is the
    /// area of the triangle between the loading and unloading lines above zero force, plus the
    /// adhesive part: by hand ½ k_n δ₁ (δ₁ − δ₀) + the work of the attractive branch.
    #[test]
    fn quasi_static_loop_dissipates_the_loop_area() {
        let (h, hy) = params();
        let (y, reff, meff) = (3.0e6, 7.5e-4, 1.8e-5);
        let kn = normal(y, (&h, &hy), 1e-9, reff, meff, 0.0, &mut 0.0).kn;
        let k2max = 2.0 * kn;
        let dlim = 2.0 * 0.05 * 2.0 * reff;
        let d1 = 0.3 * dlim;
        let n = 200_000;
        let mut dmax = 0.0;
        let mut work_in = 0.0;
        let mut last = 0.0;
        // Loading: trapezoidal work of the force along the path.
        for s in 1..=n {
            let d = d1 * s as f64 / n as f64;
            let f = normal(y, (&h, &hy), d, reff, meff, 0.0, &mut dmax).force;
            work_in += 0.5 * (f + last) * (d1 / n as f64);
            last = f;
        }
        assert!((last - kn * d1).abs() < 1e-12 * kn * d1);
        assert_eq!(dmax, d1);
        // Unloading to zero overlap.
        let mut work_out = 0.0;
        for s in (0..n).rev() {
            let d = d1 * s as f64 / n as f64;
            let f = if d > 0.0 { normal(y, (&h, &hy), d, reff, meff, 0.0, &mut dmax).force } else { 0.0 };
            work_out += 0.5 * (f + last) * (d1 / n as f64);
            last = f;
        }
        let k2 = kn + (k2max - kn) * d1 / dlim;
        let d0 = d1 - kn * d1 / k2; // where the unloading line crosses zero
                                    // The unloading line meets −k_c δ at δ_c = (k₂ − k_n) δ₁ / (k₂ + k_c).
        let kc = 0.2 * kn;
        let dc = (k2 - kn) * d1 / (k2 + kc);
        let lost_by_hand = 0.5 * kn * d1 * d1 - 0.5 * kn * d1 * (d1 - d0) // loading minus elastic return
            + 0.5 * (d0 - dc) * kc * dc // below zero along the unloading line
            + 0.5 * kc * dc * dc; // the adhesive branch to separation
        let lost = work_in - work_out;
        assert!(((lost - lost_by_hand) / lost_by_hand).abs() < 1e-6, "lost {lost} by hand {lost_by_hand}");
    }

    /// Beyond the plasticity depth the unloading slope is k₂,max and loading continues along it.
    #[test]
    fn beyond_the_plasticity_depth_the_slope_is_k2max() {
        let (h, hy) = params();
        let h = Hooke { ln_e: 0.9f64.ln(), ..h };
        let (y, reff, meff) = (3.0e6, 7.5e-4, 1.8e-5);
        let dlim = 2.0 * 0.05 * 2.0 * reff;
        let mut dmax = 0.0;
        let f1 = normal(y, (&h, &hy), 1.2 * dlim, reff, meff, 0.0, &mut dmax);
        let f2 = normal(y, (&h, &hy), 1.1 * dlim, reff, meff, 0.0, &mut dmax);
        let slope = (f1.force - f2.force) / (0.1 * dlim);
        assert!((slope / (2.0 * f1.kn) - 1.0).abs() < 1e-9, "slope {slope} kn {}", f1.kn);
        // Damping acts as for hooke.
        let mut d = dmax;
        let fd = normal(y, (&h, &hy), 1.1 * dlim, reff, meff, -0.1, &mut d);
        assert!(fd.gamma_n > 0.0);
        assert!((fd.force - f2.force - 0.1 * fd.gamma_n).abs() < 1e-12 * fd.force);
    }
}

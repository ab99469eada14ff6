//! Time-step estimates of a granular assembly: the Rayleigh time and the Hertz collision time.
//!
//! Source: LIGGGHTS 3.8 `fix check/timestep/gran` (`fix_check_timestep_gran.cpp`), which compares
//! the time step with both. The Rayleigh time is the time a Rayleigh surface wave takes to cross a
//! particle, with the usual approximation of the Rayleigh wave speed
//! c_R ≈ (0.1631 ν + 0.8766) √(G/ρ), G = E / (2 (1 + ν)):
//!
//! t_R = π r √(ρ / G) / (0.1631 ν + 0.8766).
//!
//! The Hertz time is the duration of an elastic Hertz collision at impact speed v,
//! t_H = 2.87 (m_eff² / (r_eff E_eff² v))^(1/5); LIGGGHTS evaluates it for a particle hitting its
//! own copy but with m_eff = m (the particle's full mass, not m/2), r_eff = r/2 and
//! E_eff = 1 / ((1 − ν_i²)/E_i + (1 − ν_j²)/E_j) of its type with itself. These functions take
//! those quantities as LIGGGHTS forms them, so callers reproduce its numbers.

/// Rayleigh time t_R = π r √(ρ/G) / (0.1631 ν + 0.8766) with G = E / (2(1 + ν)) [s].
pub fn rayleigh_time(radius: f64, density: f64, youngs_modulus: f64, poisson_ratio: f64) -> f64 {
    let shear_modulus = youngs_modulus / (2.0 * (poisson_ratio + 1.0));
    std::f64::consts::PI * radius * (density / shear_modulus).sqrt() / (0.1631 * poisson_ratio + 0.8766)
}

/// Hertz collision time t_H = 2.87 (m_eff² / (r_eff E_eff² v))^(1/5) [s]; infinite at v = 0.
pub fn hertz_time(m_eff: f64, r_eff: f64, e_eff: f64, speed: f64) -> f64 {
    2.87 * (m_eff * m_eff / (r_eff * e_eff * e_eff * speed)).powf(0.2)
}

/// E_eff = 1 / ((1 − ν_i²)/E_i + (1 − ν_j²)/E_j) of two materials [Pa].
pub fn effective_modulus(e_i: f64, nu_i: f64, e_j: f64, nu_j: f64) -> f64 {
    1.0 / ((1.0 - nu_i * nu_i) / e_i + (1.0 - nu_j * nu_j) / e_j)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand calculation: glass-like sphere r = 1 mm, ρ = 2500 kg/m³, E = 5e6 Pa, ν = 0.45.
    /// G = 5e6 / 2.9 = 1 724 137.93 Pa; √(ρ/G) = √(1.45e-3) = 0.038078866 s/m;
    /// 0.1631·0.45 + 0.8766 = 0.949995; t_R = π·1e-3·0.038078866 / 0.949995 = 1.2592517e-4 s.
    /// m = 4/3 π (1e-3)³ 2500 = 1.0471976e-5 kg, r_eff = 5e-4 m, E_eff = 5e6 / (2·0.7975)
    /// = 3 134 796.24 Pa, v = 2 m/s: m²/(r E² v) = 1.0966227e-10 / (5e-4 · 9.826947e12 · 2)
    /// = 1.1159342e-20; its fifth root 1.0221808e-4; t_H = 2.87 × that = 2.9336589e-4 s.
    #[test]
    fn rayleigh_and_hertz_times_match_a_hand_calculation() {
        let tr = rayleigh_time(1e-3, 2500.0, 5e6, 0.45);
        assert!((tr / 1.2592517e-4 - 1.0).abs() < 1e-6, "{tr:e}");
        let m = 4.0 / 3.0 * std::f64::consts::PI * 1e-9 * 2500.0;
        let e = effective_modulus(5e6, 0.45, 5e6, 0.45);
        assert!((e / 3_134_796.24 - 1.0).abs() < 1e-9, "{e}");
        let th = hertz_time(m, 0.5e-3, e, 2.0);
        assert!((th / 2.9336589e-4 - 1.0).abs() < 1e-6, "{th:e}");
        assert!(hertz_time(m, 0.5e-3, e, 0.0).is_infinite());
    }
}

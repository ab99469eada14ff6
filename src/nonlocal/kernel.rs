//! Compliance kernels G_i(c, k) of the nonlocal contact relation (SPEC §4, §4.1): the inward
//! displacement of particle i's surface at contact c per unit compressive force at its contact k.
//!
//! A kernel is a function of the angle between the two contact directions only (contacts sit on
//! the undeformed sphere), so it is written in terms of μ = cos α = e_c·e_k, the cosine between the
//! unit vectors from the centre toward the two contacts. The solver needs G and dG/dμ: the
//! directions of particle–particle contacts move with the centres, and the Newton Jacobian is
//! exact only with that derivative.

use std::fmt;
use std::str::FromStr;

use crate::physics::brodu2015::{bracket_on_sphere, compliance_prefactor};

/// Two contacts whose half-angle sine s = sin(α/2) is below this are treated as one point: the
/// half-space kernel is singular (∝ 1/s) there and the local Hertz term already carries the load.
/// Same role as [`crate::physics::brodu2015::MIN_CHORD`] for a unit sphere.
pub const MIN_HALF_ANGLE_SINE: f64 = 1e-6;

/// Which kernel G to use (SPEC §4.1 **[option `kernel`]**).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KernelKind {
    /// Exact finite elastic sphere (Legendre series). Not implemented yet: selecting it is an error.
    Sphere,
    /// Boussinesq half-space, the Eq. 2 kernel with γ = 1 (the parity partner of standard MC).
    Boussinesq,
    /// No nonlocal term: every contact is pure Hertz.
    None,
}

impl KernelKind {
    /// Name as written in scene files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            KernelKind::Sphere => "sphere",
            KernelKind::Boussinesq => "boussinesq",
            KernelKind::None => "none",
        }
    }
}

impl fmt::Display for KernelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for KernelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "sphere" => Ok(KernelKind::Sphere),
            "boussinesq" => Ok(KernelKind::Boussinesq),
            "none" => Ok(KernelKind::None),
            other => Err(format!("unknown kernel '{other}': expected sphere, boussinesq or none")),
        }
    }
}

/// A kernel ready for evaluation: the variant and a dimensionless prefactor `scale` (the γ of
/// "kernel γ·G", SPEC §4 consequence (b); 1 for the reference solution).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kernel {
    kind: KernelKind,
    scale: f64,
}

impl Kernel {
    /// Builds a kernel. `scale` must be finite and ≥ 0. The `sphere` kernel is refused with an
    /// explanation: its series solution has not been implemented and verified against the SPEC §4.1
    /// orientation values, and an unverified compliance would silently bias every reference curve.
    pub fn new(kind: KernelKind, scale: f64) -> Result<Self, String> {
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("invalid kernel_scale = {scale}: must be finite and >= 0"));
        }
        if kind == KernelKind::Sphere {
            return Err("kernel 'sphere' (finite elastic sphere, SPEC §4.1) is not available in this \
                        version: use 'boussinesq' or 'none'"
                .to_string());
        }
        Ok(Self { kind, scale })
    }

    pub fn kind(&self) -> KernelKind {
        self.kind
    }

    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// True when the kernel contributes nothing (pure Hertz): the solver then skips the O(Z²) loop.
    pub fn is_zero(&self) -> bool {
        self.kind == KernelKind::None || self.scale == 0.0
    }

    /// Compliance G(μ) [m/N] and dG/dμ of a sphere of Young's modulus `e`, Poisson ratio `nu` and
    /// radius `r`, for two contacts with direction cosine `mu`.
    ///
    /// Boussinesq (SPEC §4): G = (1+ν) B(s) / (4π E r s), s = sin(α/2) = √((1−μ)/2), B the Eq. 2
    /// bracket on a sphere. It is written as −[`compliance_prefactor`](γ=1) · B(s) / d with the chord
    /// d = 2 r s, i.e. exactly minus the Eq. 2 displacement per unit force (Eq. 2 returns the radius
    /// growth; G is the inward displacement). dG/dμ = dG/ds · ds/dμ with ds/dμ = −1/(4s) and
    /// dB/ds = 2(1−2ν) − 2(7−8ν)s (derivative of SPEC §2's B(s)).
    #[inline]
    pub fn compliance(&self, mu: f64, e: f64, nu: f64, r: f64) -> (f64, f64) {
        match self.kind {
            KernelKind::None | KernelKind::Sphere => (0.0, 0.0),
            KernelKind::Boussinesq => {
                let s = (0.5 * (1.0 - mu)).clamp(0.0, 1.0).sqrt();
                if s < MIN_HALF_ANGLE_SINE {
                    return (0.0, 0.0);
                }
                let c = -self.scale * compliance_prefactor(1.0, e, nu) / (2.0 * r);
                let b = bracket_on_sphere(s, nu);
                let db = 2.0 * (1.0 - 2.0 * nu) - 2.0 * (7.0 - 8.0 * nu) * s;
                let g = c * b / s;
                let dg_ds = c * (db * s - b) / (s * s);
                (g, dg_ds * (-0.25 / s))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::brodu2015::displacement;
    use crate::physics::Vec3;

    #[test]
    fn boussinesq_is_minus_eq2_per_unit_force() {
        let (e, nu, r) = (23.3e3, 0.3, 1e-3);
        let k = Kernel::new(KernelKind::Boussinesq, 1.0).unwrap();
        for alpha_deg in [10.0_f64, 45.0, 90.0, 120.0, 179.0, 180.0] {
            let a = alpha_deg.to_radians();
            let pc = Vec3::new(0.0, 0.0, r);
            let pk = Vec3::new(r * a.sin(), 0.0, r * a.cos());
            let disp = displacement(&pk, &pc, 1.0, 1.0, e, nu);
            let (g, _) = k.compliance(a.cos(), e, nu, r);
            assert!((g + disp).abs() <= 1e-12 * disp.abs().max(1e-30), "alpha {alpha_deg}: {g} vs {disp}");
        }
    }

    #[test]
    fn boussinesq_derivative_matches_finite_difference() {
        let k = Kernel::new(KernelKind::Boussinesq, 0.8).unwrap();
        for mu in [-0.999, -0.5, 0.0, 0.3, 0.9] {
            let h = 1e-6;
            let (_, d) = k.compliance(mu, 1.0, 0.4, 1.0);
            let fd =
                (k.compliance(mu + h, 1.0, 0.4, 1.0).0 - k.compliance(mu - h, 1.0, 0.4, 1.0).0) / (2.0 * h);
            assert!((d - fd).abs() < 1e-6 * fd.abs().max(1.0), "mu {mu}: {d} vs {fd}");
        }
    }

    #[test]
    fn spec_orientation_values_of_boussinesq() {
        // SPEC §4.1: a diametric pair of unit loads gives −0.098, −0.169 (θ = 90°, ν = 0.3, 0.5) and
        // −0.028, −0.113 (θ = 60°) in units P/(E R) with the Boussinesq kernel.
        let k = Kernel::new(KernelKind::Boussinesq, 1.0).unwrap();
        let pair = |theta: f64, nu: f64| {
            let t = theta.to_radians();
            k.compliance(t.cos(), 1.0, nu, 1.0).0
                + k.compliance((std::f64::consts::PI - t).cos(), 1.0, nu, 1.0).0
        };
        for (theta, nu, want) in
            [(90.0, 0.3, -0.098), (90.0, 0.5, -0.169), (60.0, 0.3, -0.028), (60.0, 0.5, -0.113)]
        {
            let got = pair(theta, nu);
            assert!((got - want).abs() < 1.5e-3, "theta {theta} nu {nu}: {got} vs {want}");
        }
    }

    #[test]
    fn sphere_kernel_is_refused_and_bad_scale_rejected() {
        assert!(Kernel::new(KernelKind::Sphere, 1.0).unwrap_err().contains("not available"));
        assert!(Kernel::new(KernelKind::Boussinesq, f64::NAN).is_err());
        assert!("halfspace".parse::<KernelKind>().is_err());
        assert_eq!("none".parse::<KernelKind>().unwrap(), KernelKind::None);
    }
}

//! Compliance kernels G_i(c, k) of the nonlocal contact relation (docs/spec.md §4, §4.1): the inward
//! displacement of particle i's surface at contact c per unit compressive force at its contact k.
//!
//! A kernel is a function of the angle between the two contact directions only (contacts sit on
//! the undeformed sphere), so it is written in terms of μ = cos α = e_c·e_k, the cosine between the
//! unit vectors from the centre toward the two contacts. The solver needs G and dG/dμ: the
//! directions of particle–particle contacts move with the centres, and the Newton Jacobian is
//! exact only with that derivative.
//!
//! # The `sphere` kernel (finite elastic sphere, docs/spec.md §4.1)
//!
//! **Legendre series.** A normal surface traction σ_rr = −p_n P_n(cos θ), σ_rθ = 0 on a solid
//! sphere of radius R (n ≠ 1) is carried by the two regular axisymmetric displacement families
//! u = ∇φ_n and u = (n+5−4ν) r²∇φ_n − [(1−2ν)(4n+2)+2n] x φ_n, φ_n = rⁿ P_n (Lamé/Love). Solving
//! the two traction conditions gives the inward surface displacement (p_n R / E) w_n P_n with
//!
//! ```text
//!     w_n = (1+ν) [2(1−ν) n² + ν n + 2ν − 1] / ((n−1) (n² + (2ν+1) n + ν + 1))
//! ```
//!
//! (w_0 = 1−2ν is Lamé's uniform pressure; a test re-solves the two traction conditions
//! numerically for each n). A unit inward point force at the pole has p_n = (2n+1)/(4πR²),
//! so its inward displacement in units P/(E R) is g(μ) = Σ d_n P_n(μ), d_n = (2n+1) w_n / (4π).
//! The n = 1 term carries the net force and has no solution on its own: the load is balanced by
//! its own n = 1 component (the normal traction −3P cos θ/(4πR²)), which leaves the centre fixed
//! and no n = 1 deformation; what remains free is a rigid translation along the load axis,
//! u_r = d_1 cos θ, fixed below. A diametric pair of unit loads (the docs/spec.md §4.1 verification case)
//! is exactly w(θ) = g(cos θ) + g(−cos θ): the odd terms, d_1 included, cancel and the even ones
//! double.
//!
//! **Summation.** d_n → (1−ν²)/π, so the series diverges at the pole and converges only
//! conditionally elsewhere (its partial sums oscillate with amplitude ∝ n^−½). The asymptotic
//! expansion d_n = a + b/n + c/(n(n+1)) + e/(n(n+1)(n+2)) + O(n⁻⁴) with
//! a = (1−ν²)/π, b = (1+ν)(1−2ν)²/(2π), c = −(1+ν)(16ν³−12ν²−5ν+2)/(4π),
//! e = (1+ν)(32ν⁴−32ν³−10ν²+13ν+1)/(4π) is subtracted and summed in closed form
//! (s = sin(θ/2), μ = 1 − 2s²): Σ_{n≥0} P_n = 1/(2s) (the Boussinesq 1/chord term: a/(2s) per
//! P/(E R) is exactly (1−ν²)P/(πEρ)), Σ_{n≥1} P_n/n = −ln(s(1+s)),
//! Σ_{n≥1} P_n/(n(n+1)) = 1 − 2 ln(1+s), Σ_{n≥1} P_n/(n(n+1)(n+2)) = s² ln s − (1+s²) ln(1+s) + s + ¼.
//! The remainder, with O(n⁻⁴) coefficients, is summed to [`SPHERE_TERMS`] terms (truncation
//! < 1e−10) with its derivative, once per ν, on a uniform grid of [`SPHERE_GRID`] intervals in s,
//! and evaluated by cubic Hermite interpolation (C¹); the singular part (1/s, ln s) is evaluated
//! analytically.
//! Tables are built lazily, cached per ν (bit pattern) for the life of the process, with a
//! per-thread last-used entry in front. The smooth closed forms (in ln(1 + s)) are tabulated with
//! the remainder, so an evaluation is a lookup, one cubic and one logarithm (ln s), with no
//! allocation.
//!
//! **Kernel.** G(μ) = γ g(μ) / (E R): the field of the load at k alone, not of k's diametric
//! pair. For a particle in equilibrium (Σ_k P_k e_k = 0) the n = 1 reactions of all its loads
//! cancel, so the superposition Σ_k g(μ_ck) P_k is the exact displacement of the sphere, with the
//! centre fixed (the d_1 translations cancel too). Charging every contact with its whole pair
//! instead would count each load twice away from its antipode (a contact on the equator of a
//! sphere pressed by two plates would see twice the plates' bulge). This is also how the Boussinesq kernel is used: docs/spec.md §4.1
//! compares its two-load sum with the sphere's pair values. Consequences:
//! - θ → 0 (coincident contacts): g has the Boussinesq 1/chord singularity (a/(2s) is exactly
//!   (1−ν²)P/(πEρ)) and, for ν < ½, a logarithmic one (−b ln s, from the tangential part of the
//!   point-load field on a curved surface). As for the Boussinesq kernel, the load's own contact is
//!   the local Hertz term: contacts closer than [`MIN_HALF_ANGLE_SINE`] contribute nothing.
//! - The self term. The exact approach at c also contains the regular part of c's own field at
//!   c, g_reg = lim_{s→0} [g − a/(2s) + b ln s] (times P_c), for which the relation of docs/spec.md §4 has no
//!   term. The translation d_1 is chosen as −g_reg (d_1 = 0.3170 for ν = ½, 0.5034 for ν = 0.3),
//!   i.e. g_reg = 0: for an equilibrated particle Σ_{k≠c} d_1 μ_ck P_k = −d_1 P_c, so the relation
//!   without a self term then equals the exact superposition, self term included. (For ν = ½ this
//!   is unambiguous; for ν < ½ the scale inside the logarithm is a convention, ln s = ln(ρ/2R).)
//! - θ → π (c opposite k): g is smooth and finite. With g⁰, g⁰_reg the values for d_1 = 0,
//!   G(π) = g⁰(π) − d_1 = g⁰(π) + g⁰_reg: the diametric pair's field at the antipode with the
//!   antipodal point load's singular (Hertz) part removed, so a sphere loaded at two opposite
//!   contacts gets its exact pair solution.
//!
//! **Verification** (units P/(E R), diametric pair, accurate to < 1e−9): θ = 90°: −0.16168
//! (ν = 0.3), −0.20721 (ν = 0.5); θ = 60° or 120°: −0.07919 (ν = 0.3), −0.12488 (ν = 0.5).
//! docs/spec.md §4.1 prints −0.158, −0.204, −0.084, −0.129: these are the same series (same d_n) summed
//! without acceleration and cut at n_max ≈ 3000–4000 with n_max ≡ 4 (mod 12), e.g. 3400, where
//! the oscillating partial sums are still 3–5e−3 off the limit (both are tests below).

use std::cell::Cell;
use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;
use std::sync::Mutex;

use crate::physics::brodu2015::{bracket_on_sphere, compliance_prefactor};

/// Two contacts whose half-angle sine s = sin(α/2) is below this are treated as one point: the
/// half-space kernel is singular (∝ 1/s) there and the local Hertz term already carries the load.
/// Same role as [`crate::physics::brodu2015::MIN_CHORD`] for a unit sphere.
pub const MIN_HALF_ANGLE_SINE: f64 = 1e-6;

/// Which kernel G to use (docs/spec.md §4.1 **[option `kernel`]**).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KernelKind {
    /// Exact finite elastic sphere (Legendre series, see the module documentation).
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
/// "kernel γ·G", docs/spec.md §4 consequence (b); 1 for the reference solution).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kernel {
    kind: KernelKind,
    scale: f64,
}

impl Kernel {
    /// Builds a kernel. `scale` must be finite and ≥ 0.
    pub fn new(kind: KernelKind, scale: f64) -> Result<Self, String> {
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("invalid kernel_scale = {scale}: must be finite and >= 0"));
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
    /// Boussinesq (docs/spec.md §4): G = (1+ν) B(s) / (4π E r s), s = sin(α/2) = √((1−μ)/2), B the Eq. 2
    /// bracket on a sphere. It is written as −[`compliance_prefactor`](γ=1) · B(s) / d with the chord
    /// d = 2 r s, i.e. exactly minus the Eq. 2 displacement per unit force (Eq. 2 returns the radius
    /// growth; G is the inward displacement). dG/dμ = dG/ds · ds/dμ with ds/dμ = −1/(4s) and
    /// dB/ds = 2(1−2ν) − 2(7−8ν)s (derivative of docs/spec.md §2's B(s)).
    ///
    /// Sphere (docs/spec.md §4.1): G = g(μ) / (E r), g the finite-sphere displacement of the module
    /// documentation ([`sphere_unit_displacement`]).
    #[inline]
    pub fn compliance(&self, mu: f64, e: f64, nu: f64, r: f64) -> (f64, f64) {
        match self.kind {
            KernelKind::None => (0.0, 0.0),
            KernelKind::Sphere => {
                let (g, dg) = sphere_unit_displacement(mu, nu);
                let c = self.scale / (e * r);
                (c * g, c * dg)
            }
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

/// A kernel bound to one particle's E, ν and r: the prefactor and, for `sphere`, the table are
/// looked up once ([`Kernel::bind`]) instead of at every evaluation. Gives bit for bit the values
/// of [`Kernel::compliance`].
#[derive(Clone, Copy)]
pub struct BoundKernel {
    kind: KernelKind,
    /// γ/(E r) (sphere) or −γ·prefactor/(2r) (Boussinesq).
    c: f64,
    nu: f64,
    table: Option<&'static SphereTable>,
    /// A lower bound of G over all μ (≤ 0), see [`BoundKernel::lower_bound`].
    lower: f64,
}

impl fmt::Debug for BoundKernel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("BoundKernel")
            .field("kind", &self.kind)
            .field("c", &self.c)
            .field("nu", &self.nu)
            .finish()
    }
}

impl Kernel {
    /// This kernel for a sphere of Young's modulus `e`, Poisson ratio `nu` and radius `r`.
    pub fn bind(&self, e: f64, nu: f64, r: f64) -> BoundKernel {
        let (c, table) = match self.kind {
            KernelKind::None => (0.0, None),
            KernelKind::Sphere => (self.scale / (e * r), Some(sphere_table(nu))),
            KernelKind::Boussinesq => (-self.scale * compliance_prefactor(1.0, e, nu) / (2.0 * r), None),
        };
        let mut b = BoundKernel { kind: self.kind, c, nu, table, lower: 0.0 };
        if self.kind != KernelKind::None {
            // G → +∞ as the two contacts meet (1/chord) and is smooth elsewhere; its minimum sampled
            // on a fine grid in s, lowered by 1 % (the sampling error is orders of magnitude less).
            let m = 1 << 13;
            let min = (1..=m)
                .map(|j| {
                    let s = j as f64 / m as f64;
                    b.value(1.0 - 2.0 * s * s)
                })
                .fold(f64::INFINITY, f64::min);
            b.lower = (min - 0.01 * min.abs()).min(0.0);
        }
        b
    }
}

impl BoundKernel {
    /// G(μ) and dG/dμ, as [`Kernel::compliance`].
    #[inline]
    pub fn eval(&self, mu: f64) -> (f64, f64) {
        match self.kind {
            KernelKind::None => (0.0, 0.0),
            KernelKind::Sphere => {
                let s = (0.5 * (1.0 - mu)).clamp(0.0, 1.0).sqrt();
                if s < MIN_HALF_ANGLE_SINE {
                    return (0.0, 0.0);
                }
                let (g, dg_ds) = self.sphere().eval(s);
                let dg = dg_ds * (-0.25 / s);
                (self.c * g, self.c * dg)
            }
            KernelKind::Boussinesq => {
                let s = (0.5 * (1.0 - mu)).clamp(0.0, 1.0).sqrt();
                if s < MIN_HALF_ANGLE_SINE {
                    return (0.0, 0.0);
                }
                let (c, nu) = (self.c, self.nu);
                let b = bracket_on_sphere(s, nu);
                let db = 2.0 * (1.0 - 2.0 * nu) - 2.0 * (7.0 - 8.0 * nu) * s;
                let g = c * b / s;
                let dg_ds = c * (db * s - b) / (s * s);
                (g, dg_ds * (-0.25 / s))
            }
        }
    }

    /// G(μ) alone (the same value as `eval(mu).0`, without the derivative's work).
    #[inline]
    pub fn value(&self, mu: f64) -> f64 {
        match self.kind {
            KernelKind::None => 0.0,
            KernelKind::Sphere => {
                let s = (0.5 * (1.0 - mu)).clamp(0.0, 1.0).sqrt();
                if s < MIN_HALF_ANGLE_SINE {
                    return 0.0;
                }
                self.c * self.sphere().value(s)
            }
            KernelKind::Boussinesq => {
                let s = (0.5 * (1.0 - mu)).clamp(0.0, 1.0).sqrt();
                if s < MIN_HALF_ANGLE_SINE {
                    return 0.0;
                }
                self.c * bracket_on_sphere(s, self.nu) / s
            }
        }
    }

    /// A lower bound of G(μ) over μ ∈ [−1, 1], ≤ 0: Σ_k G(μ_k) P_k ≥ lower_bound · Σ_k P_k for
    /// non-negative loads (used to skip contacts that cannot close).
    pub fn lower_bound(&self) -> f64 {
        self.lower
    }

    #[inline]
    fn sphere(&self) -> &'static SphereTable {
        match self.table {
            Some(t) => t,
            None => sphere_table(self.nu),
        }
    }
}

/// Legendre terms summed for the smooth remainder of the sphere kernel (coefficients O(n⁻⁴):
/// truncation below 1e−10 in g).
pub const SPHERE_TERMS: usize = 3000;

/// Intervals of the uniform grid in s = sin(θ/2) ∈ [0, 1] on which the remainder is tabulated.
pub const SPHERE_GRID: usize = 1024;

/// Coefficient d_n of the Legendre series of the sphere kernel: the inward surface displacement,
/// in units P/(E R), of a unit inward point force at the pole is g = Σ d_n P_n(cos θ). d_1 is the
/// rigid translation that makes the regular self term vanish (module documentation).
pub fn sphere_coefficient(n: usize, nu: f64) -> f64 {
    if n == 1 {
        sphere_table(nu).d1
    } else {
        sphere_formula(n, nu)
    }
}

/// d_n = (2n+1) w_n / (4π) for n ≠ 1 (0 for n = 1).
fn sphere_formula(n: usize, nu: f64) -> f64 {
    if n == 1 {
        return 0.0;
    }
    let x = n as f64;
    let w = (1.0 + nu) * (2.0 * (1.0 - nu) * x * x + nu * x + 2.0 * nu - 1.0)
        / ((x - 1.0) * (x * x + (2.0 * nu + 1.0) * x + nu + 1.0));
    (2.0 * x + 1.0) * w / (4.0 * PI)
}

/// Asymptotic coefficients (a, b, c, e) of d_n = a + b/n + c/(n(n+1)) + e/(n(n+1)(n+2)) + O(n⁻⁴).
fn sphere_asymptotics(nu: f64) -> [f64; 4] {
    let q = 1.0 + nu;
    [
        (1.0 - nu * nu) / PI,
        q * (1.0 - 2.0 * nu).powi(2) / (2.0 * PI),
        -q * (((16.0 * nu - 12.0) * nu - 5.0) * nu + 2.0) / (4.0 * PI),
        q * ((((32.0 * nu - 32.0) * nu - 10.0) * nu + 13.0) * nu + 1.0) / (4.0 * PI),
    ]
}

/// Closed-form sums of the subtracted asymptotic series at s = sin(θ/2) > 0, and their
/// s-derivatives: Σ P_n = 1/(2s), Σ P_n/n, Σ P_n/(n(n+1)), Σ P_n/(n(n+1)(n+2)) (sums from n = 1
/// except the first). The kernel evaluates them split in two ([`sphere_singular`],
/// [`sphere_smooth`]); this whole form is the check of that split.
#[cfg(test)]
fn sphere_closed_forms(s: f64) -> ([f64; 4], [f64; 4]) {
    let l1 = s.ln_1p();
    let ls = s.ln();
    let v = [0.5 / s, -(ls + l1), 1.0 - 2.0 * l1, s * s * ls - (1.0 + s * s) * l1 + s + 0.25];
    let d = [
        -0.5 / (s * s),
        -1.0 / s - 1.0 / (1.0 + s),
        -2.0 / (1.0 + s),
        2.0 * s * ls + s - 2.0 * s * l1 - (1.0 + s * s) / (1.0 + s) + 1.0,
    ];
    (v, d)
}

/// The singular part of Σ_k asym_k · (closed form k) at s > 0, and its s-derivative: the terms
/// in 1/s and ln s, evaluated analytically (one logarithm).
#[inline(always)]
fn sphere_singular([a, b, _, e]: [f64; 4], s: f64) -> (f64, f64) {
    let ls = s.ln();
    (a * (0.5 / s) - b * ls + e * (s * s * ls), -a * (0.5 / (s * s)) - b / s + e * (2.0 * s * ls + s))
}

/// The rest of the closed forms, smooth on [0, 1] (polynomials and ln(1 + s)), and its
/// s-derivative: tabulated with the series remainder, so that an evaluation takes one logarithm
/// instead of two (`ln_1p` was a tenth of the nonlocal `sphere` run).
fn sphere_smooth([_, b, c, e]: [f64; 4], s: f64) -> (f64, f64) {
    let l1 = s.ln_1p();
    let v = -b * l1 + c * (1.0 - 2.0 * l1) + e * (-(1.0 + s * s) * l1 + s + 0.25);
    let d = -b / (1.0 + s) - 2.0 * c / (1.0 + s) + e * (-2.0 * s * l1 - (1.0 + s * s) / (1.0 + s) + 1.0);
    (v, d)
}

/// The tabulated smooth remainder of the sphere kernel for one ν.
struct SphereTable {
    asym: [f64; 4],
    /// The n = 1 coefficient (rigid translation) that makes the regular self term vanish.
    d1: f64,
    /// Remainder Σ ρ_n P_n(1 − 2s²) plus the smooth closed forms ([`sphere_smooth`]), and its
    /// s-derivative, at s_j = j / SPHERE_GRID.
    val: Box<[f64]>,
    der: Box<[f64]>,
}

impl SphereTable {
    /// Asymptotic coefficients, d_1, and the remainder coefficients ρ_n, n < [`SPHERE_TERMS`].
    fn coefficients(nu: f64) -> ([f64; 4], f64, Vec<f64>) {
        let asym = sphere_asymptotics(nu);
        let [a, b, c, e] = asym;
        let mut rho: Vec<f64> = (0..SPHERE_TERMS)
            .map(|n| {
                let x = n as f64;
                match n {
                    0 => sphere_formula(0, nu) - a,
                    1 => -a - b - c / 2.0 - e / 6.0,
                    _ => {
                        sphere_formula(n, nu)
                            - a
                            - b / x
                            - c / (x * (x + 1.0))
                            - e / (x * (x + 1.0) * (x + 2.0))
                    }
                }
            })
            .collect();
        // Regular self term with d_1 = 0 at s = 0 (P_n(1) = 1; the b and e parts of the closed forms
        // tend to −b ln s and e/4, the c part to c), then d_1 = −g_reg.
        let g_reg: f64 = c + 0.25 * e + rho.iter().rev().sum::<f64>();
        let d1 = -g_reg;
        rho[1] += d1;
        (asym, d1, rho)
    }

    fn build(nu: f64) -> Self {
        let (asym, d1, rho) = Self::coefficients(nu);
        let mut val = vec![0.0; SPHERE_GRID + 1];
        let mut der = vec![0.0; SPHERE_GRID + 1];
        for j in 0..=SPHERE_GRID {
            let s = j as f64 / SPHERE_GRID as f64;
            let mu = 1.0 - 2.0 * s * s;
            // P_n and P_n' by the three-term recurrences; P'_{n+1} = P'_{n−1} + (2n+1) P_n.
            let (mut p0, mut p1) = (1.0, mu);
            let (mut d0, mut d1) = (0.0, 1.0);
            let (mut sv, mut sd) = (rho[0], 0.0);
            for (n, &r) in rho.iter().enumerate().skip(1) {
                sv += r * p1;
                sd += r * d1;
                let x = n as f64;
                let p2 = ((2.0 * x + 1.0) * mu * p1 - x * p0) / (x + 1.0);
                let d2 = d0 + (2.0 * x + 1.0) * p1;
                (p0, p1, d0, d1) = (p1, p2, d1, d2);
            }
            // The smooth closed forms join the remainder (a cubic interpolates ln(1 + s) on this
            // grid to ~1e-14: its fourth derivative is at most 6).
            let (mv, md) = sphere_smooth(asym, s);
            val[j] = sv + mv;
            der[j] = sd * (-4.0 * s) + md;
        }
        Self { asym, d1, val: val.into_boxed_slice(), der: der.into_boxed_slice() }
    }

    /// The table cell holding s: local coordinate t ∈ [0, 1), the end values and the end slopes
    /// scaled to the cell.
    #[inline]
    fn cell(&self, s: f64) -> (f64, [f64; 4]) {
        let m = SPHERE_GRID as f64;
        let u = s * m;
        let j = (u as usize).min(SPHERE_GRID - 1);
        let t = u - j as f64;
        let h = 1.0 / m;
        (t, [self.val[j], self.val[j + 1], self.der[j] * h, self.der[j + 1] * h])
    }

    /// Cubic Hermite interpolant of the series remainder on a cell.
    #[inline]
    fn hermite(t: f64, [v0, v1, m0, m1]: [f64; 4]) -> f64 {
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * v0
            + (t3 - 2.0 * t2 + t) * m0
            + (-2.0 * t3 + 3.0 * t2) * v1
            + (t3 - t2) * m1
    }

    /// g and dg/ds at s ∈ (0, 1].
    #[inline]
    fn eval(&self, s: f64) -> (f64, f64) {
        let (t, c) = self.cell(s);
        let [v0, v1, m0, m1] = c;
        let t2 = t * t;
        let rem = Self::hermite(t, c);
        let drem =
            ((6.0 * t2 - 6.0 * t) * (v0 - v1) + (3.0 * t2 - 4.0 * t + 1.0) * m0 + (3.0 * t2 - 2.0 * t) * m1)
                * SPHERE_GRID as f64;
        let (sg, dsg) = sphere_singular(self.asym, s);
        (rem + sg, drem + dsg)
    }

    /// g alone at s ∈ (0, 1] (the same value as `eval(s).0`).
    #[inline]
    fn value(&self, s: f64) -> f64 {
        let (t, c) = self.cell(s);
        // The derivative's arithmetic is unused here and drops out once this is inlined.
        Self::hermite(t, c) + sphere_singular(self.asym, s).0
    }
}

static SPHERE_TABLES: Mutex<Vec<(u64, &'static SphereTable)>> = Mutex::new(Vec::new());

thread_local! {
    static LAST_SPHERE_TABLE: Cell<Option<(u64, &'static SphereTable)>> = const { Cell::new(None) };
}

/// The table for `nu`, built on first use and kept for the life of the process (a few distinct
/// Poisson ratios per run, 16 KiB each).
fn sphere_table(nu: f64) -> &'static SphereTable {
    let key = nu.to_bits();
    if let Some((k, t)) = LAST_SPHERE_TABLE.with(Cell::get) {
        if k == key {
            return t;
        }
    }
    let t = {
        let mut tables = SPHERE_TABLES.lock().unwrap_or_else(|e| e.into_inner());
        match tables.iter().find(|(k, _)| *k == key) {
            Some(&(_, t)) => t,
            None => {
                let t: &'static SphereTable = Box::leak(Box::new(SphereTable::build(nu)));
                tables.push((key, t));
                t
            }
        }
    };
    LAST_SPHERE_TABLE.with(|c| c.set(Some((key, t))));
    t
}

/// Inward surface displacement g(μ) of the finite sphere, in units P/(E R), at direction cosine
/// `mu` from a unit inward point force (module documentation), and dg/dμ. Returns (0, 0) for
/// coincident points (s = sin(θ/2) < [`MIN_HALF_ANGLE_SINE`]), as the Boussinesq kernel does.
#[inline]
pub fn sphere_unit_displacement(mu: f64, nu: f64) -> (f64, f64) {
    let s = (0.5 * (1.0 - mu)).clamp(0.0, 1.0).sqrt();
    if s < MIN_HALF_ANGLE_SINE {
        return (0.0, 0.0);
    }
    let (g, dg_ds) = sphere_table(nu).eval(s);
    (g, dg_ds * (-0.25 / s))
}

/// Inward surface displacement at polar angle `theta` (radians) of a sphere loaded by a diametric pair
/// of unit compressive point forces at the poles, in units P/(E R) (the docs/spec.md §4.1 orientation case):
/// g(cos θ) + g(−cos θ).
pub fn sphere_pair_displacement(theta: f64, nu: f64) -> f64 {
    let mu = theta.cos();
    sphere_unit_displacement(mu, nu).0 + sphere_unit_displacement(-mu, nu).0
}

#[cfg(test)]
#[path = "kernel_tests.rs"]
mod tests;

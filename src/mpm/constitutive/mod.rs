//! Constitutive laws of the MPM particles: first Piola–Kirchhoff stress P(F) and its consistent
//! tangent A = ∂P/∂F, behind one interface ([`Constitutive`]).
//!
//! Nezamabadi et al. 2019, Eq. 8 writes the law as Π = 𝓕(F) with Π the first Piola–Kirchhoff
//! stress; Eq. 9 gives the Cauchy stress σ = Π Fᵀ / J. The Newton iterations of the implicit step
//! (App. A, Eq. A.3) need the derivative of Π with respect to F, which each law supplies in closed
//! form (checked against finite differences in the tests).
//!
//! In 2-D (D = 2) every law is the plane-strain restriction: F₃₃ = 1, so J = det of the in-plane
//! 2×2 block and the in-plane components of C⁻¹, γ and S are those of the 2×2 block.

mod hooke;
mod neohookean;
mod svk;

pub use hooke::Hooke;
pub use neohookean::NeoHookean;
pub use svk::SaintVenantKirchhoff;

use nalgebra::SMatrix;

/// A D×D matrix (deformation gradient, stress).
pub type Mat<const D: usize> = SMatrix<f64, D, D>;

/// Fourth-order tangent A\[i\]\[J\]\[k\]\[L\] = ∂P_iJ / ∂F_kL.
pub type Tangent<const D: usize> = [[[[f64; D]; D]; D]; D];

/// The deformation gradient has J = det F ≤ 0 (an inverted or collapsed material point), where the
/// hyperelastic laws are undefined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inverted {
    pub det: f64,
}

/// Stress and consistent tangent from the deformation gradient.
pub trait Constitutive<const D: usize> {
    /// First Piola–Kirchhoff stress P(F) (Nezamabadi et al. 2019, Eq. 8).
    fn pk1(&self, f: &Mat<D>) -> Result<Mat<D>, Inverted>;
    /// Strain energy per unit initial volume W(F), with P = ∂W/∂F.
    fn energy(&self, f: &Mat<D>) -> Result<f64, Inverted>;
    /// P(F) and A = ∂P/∂F together (the Newton tangent of App. A).
    fn pk1_tangent(&self, f: &Mat<D>) -> Result<(Mat<D>, Tangent<D>), Inverted>;
}

/// The laws of the paper, chosen at run time from the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    Hooke(Hooke),
    SaintVenantKirchhoff(SaintVenantKirchhoff),
    NeoHookean(NeoHookean),
}

impl Law {
    /// Lamé constants (λ, μ) of the law.
    pub fn lame(&self) -> (f64, f64) {
        match self {
            Law::Hooke(m) => (m.lambda, m.mu),
            Law::SaintVenantKirchhoff(m) => (m.lambda, m.mu),
            Law::NeoHookean(m) => (m.lambda, m.mu),
        }
    }
}

impl<const D: usize> Constitutive<D> for Law {
    fn pk1(&self, f: &Mat<D>) -> Result<Mat<D>, Inverted> {
        match self {
            Law::Hooke(m) => m.pk1(f),
            Law::SaintVenantKirchhoff(m) => m.pk1(f),
            Law::NeoHookean(m) => m.pk1(f),
        }
    }
    fn energy(&self, f: &Mat<D>) -> Result<f64, Inverted> {
        match self {
            Law::Hooke(m) => m.energy(f),
            Law::SaintVenantKirchhoff(m) => m.energy(f),
            Law::NeoHookean(m) => m.energy(f),
        }
    }
    fn pk1_tangent(&self, f: &Mat<D>) -> Result<(Mat<D>, Tangent<D>), Inverted> {
        match self {
            Law::Hooke(m) => m.pk1_tangent(f),
            Law::SaintVenantKirchhoff(m) => m.pk1_tangent(f),
            Law::NeoHookean(m) => m.pk1_tangent(f),
        }
    }
}

/// Determinant of a 2×2 or 3×3 matrix (the only dimensions of the solver).
pub fn det<const D: usize>(a: &Mat<D>) -> f64 {
    const { assert!(D == 2 || D == 3, "the MPM is written for D = 2 or 3") };
    if D == 2 {
        a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)]
    } else {
        a[(0, 0)] * (a[(1, 1)] * a[(2, 2)] - a[(1, 2)] * a[(2, 1)])
            - a[(0, 1)] * (a[(1, 0)] * a[(2, 2)] - a[(1, 2)] * a[(2, 0)])
            + a[(0, 2)] * (a[(1, 0)] * a[(2, 1)] - a[(1, 1)] * a[(2, 0)])
    }
}

/// Inverse by the adjugate; the caller has checked det ≠ 0.
pub fn inverse<const D: usize>(a: &Mat<D>) -> Mat<D> {
    let d = det(a);
    let mut out = Mat::<D>::zeros();
    if D == 2 {
        out[(0, 0)] = a[(1, 1)] / d;
        out[(0, 1)] = -a[(0, 1)] / d;
        out[(1, 0)] = -a[(1, 0)] / d;
        out[(1, 1)] = a[(0, 0)] / d;
    } else {
        for i in 0..3 {
            for j in 0..3 {
                // Cofactor of a_ji (transposed adjugate), cyclic indices avoid sign bookkeeping.
                let (r0, r1) = ((j + 1) % 3, (j + 2) % 3);
                let (c0, c1) = ((i + 1) % 3, (i + 2) % 3);
                out[(i, j)] = (a[(r0, c0)] * a[(r1, c1)] - a[(r0, c1)] * a[(r1, c0)]) / d;
            }
        }
    }
    out
}

/// A zero tangent, to be filled.
pub fn zero_tangent<const D: usize>() -> Tangent<D> {
    [[[[0.0; D]; D]; D]; D]
}

/// Validates Lamé constants: μ > 0 and the bulk modulus λ + 2μ/D ≥ 0 (λ = 0 is the paper's fully
/// compressible case), all finite.
pub fn check_lame(lambda: f64, mu: f64) -> Result<(), String> {
    if !lambda.is_finite() || !mu.is_finite() {
        return Err(format!("Lamé constants must be finite (λ = {lambda}, μ = {mu})"));
    }
    if mu <= 0.0 {
        return Err(format!("shear modulus μ must be positive, got {mu} Pa"));
    }
    if lambda < 0.0 {
        return Err(format!("Lamé constant λ must be non-negative, got {lambda} Pa"));
    }
    Ok(())
}

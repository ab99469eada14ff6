//! Saint-Venant–Kirchhoff law, Nezamabadi et al. 2019, Eq. 17: S = λ tr(γ) I + 2μ γ with the
//! Green–Lagrange strain γ = (C − I)/2, C = FᵀF, and P = F S.
//!
//! Eq. 17 as printed reads "+ μ γ"; the factor 2 is restored here because only with it does the
//! law reduce to Hooke's σ = λ tr ε I + 2μ ε at small strain, which the paper's Fig. 7 (Hooke and
//! SVK curves on top of each other) requires.

use super::{check_lame, det, Constitutive, Inverted, Mat, Tangent};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SaintVenantKirchhoff {
    pub lambda: f64,
    pub mu: f64,
}

impl SaintVenantKirchhoff {
    pub fn new(lambda: f64, mu: f64) -> Result<Self, String> {
        check_lame(lambda, mu)?;
        Ok(Self { lambda, mu })
    }

    /// Second Piola–Kirchhoff stress S (Eq. 17).
    pub fn pk2<const D: usize>(&self, f: &Mat<D>) -> Mat<D> {
        let gamma = (f.transpose() * f - Mat::<D>::identity()) * 0.5;
        Mat::<D>::identity() * (self.lambda * gamma.trace()) + gamma * (2.0 * self.mu)
    }
}

impl<const D: usize> Constitutive<D> for SaintVenantKirchhoff {
    fn pk1(&self, f: &Mat<D>) -> Result<Mat<D>, Inverted> {
        // The law itself is defined for any F, but an inverted point (J ≤ 0) is a failed step.
        let j = det(f);
        if j <= 0.0 {
            return Err(Inverted { det: j });
        }
        Ok(f * self.pk2(f))
    }

    /// W = λ/2 (tr γ)² + μ γ:γ.
    fn energy(&self, f: &Mat<D>) -> Result<f64, Inverted> {
        let j = det(f);
        if j <= 0.0 {
            return Err(Inverted { det: j });
        }
        let gamma = (f.transpose() * f - Mat::<D>::identity()) * 0.5;
        Ok(0.5 * self.lambda * gamma.trace().powi(2) + self.mu * gamma.norm_squared())
    }

    /// ∂P_iJ/∂F_kL = δ_ik S_LJ + λ F_iJ F_kL + μ (F_iL F_kJ + (F Fᵀ)_ik δ_JL), from P = F S and
    /// ∂S_MJ/∂F_kL = λ δ_MJ F_kL + μ (δ_ML F_kJ + F_kM δ_JL).
    fn pk1_tangent(&self, f: &Mat<D>) -> Result<(Mat<D>, Tangent<D>), Inverted> {
        let p = self.pk1(f)?;
        let s = self.pk2(f);
        let b = f * f.transpose();
        let mut a = super::zero_tangent::<D>();
        for (i, ai) in a.iter_mut().enumerate() {
            for (j, aij) in ai.iter_mut().enumerate() {
                for (k, aijk) in aij.iter_mut().enumerate() {
                    for (l, v) in aijk.iter_mut().enumerate() {
                        let mut t = self.lambda * f[(i, j)] * f[(k, l)] + self.mu * f[(i, l)] * f[(k, j)];
                        if i == k {
                            t += s[(l, j)];
                        }
                        if j == l {
                            t += self.mu * b[(i, k)];
                        }
                        *v = t;
                    }
                }
            }
        }
        Ok((p, a))
    }
}

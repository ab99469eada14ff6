//! Compressible Neo-Hookean law, Nezamabadi et al. 2019, Eq. 18: S = (λ ln J − μ) C⁻¹ + μ I, so
//! P = F S = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ.

use super::{check_lame, det, inverse, Constitutive, Inverted, Mat, Tangent};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeoHookean {
    pub lambda: f64,
    pub mu: f64,
}

impl NeoHookean {
    pub fn new(lambda: f64, mu: f64) -> Result<Self, String> {
        check_lame(lambda, mu)?;
        Ok(Self { lambda, mu })
    }
}

impl<const D: usize> Constitutive<D> for NeoHookean {
    fn pk1(&self, f: &Mat<D>) -> Result<Mat<D>, Inverted> {
        let j = det(f);
        if j <= 0.0 {
            return Err(Inverted { det: j });
        }
        let f_it = inverse(f).transpose();
        Ok((f - f_it) * self.mu + f_it * (self.lambda * j.ln()))
    }

    /// W = μ/2 (tr C − 3) − μ ln J + λ/2 (ln J)², with tr C − 3 = tr C₂ₓ₂ − 2 in plane strain.
    fn energy(&self, f: &Mat<D>) -> Result<f64, Inverted> {
        let j = det(f);
        if j <= 0.0 {
            return Err(Inverted { det: j });
        }
        let lnj = j.ln();
        Ok(0.5 * self.mu * (f.norm_squared() - D as f64) - self.mu * lnj + 0.5 * self.lambda * lnj * lnj)
    }

    /// With ∂(F⁻ᵀ)_iJ/∂F_kL = −F⁻¹_Jk F⁻¹_Li and ∂ln J/∂F_kL = F⁻¹_Lk:
    /// ∂P_iJ/∂F_kL = μ δ_ik δ_JL + (μ − λ ln J) F⁻¹_Jk F⁻¹_Li + λ F⁻¹_Ji F⁻¹_Lk.
    fn pk1_tangent(&self, f: &Mat<D>) -> Result<(Mat<D>, Tangent<D>), Inverted> {
        let p = self.pk1(f)?;
        let fi = inverse(f);
        let c = self.mu - self.lambda * det(f).ln();
        let mut a = super::zero_tangent::<D>();
        for (i, ai) in a.iter_mut().enumerate() {
            for (j, aij) in ai.iter_mut().enumerate() {
                for (k, aijk) in aij.iter_mut().enumerate() {
                    for (l, v) in aijk.iter_mut().enumerate() {
                        let mut t = c * fi[(j, k)] * fi[(l, i)] + self.lambda * fi[(j, i)] * fi[(l, k)];
                        if i == k && j == l {
                            t += self.mu;
                        }
                        *v = t;
                    }
                }
            }
        }
        Ok((p, a))
    }
}

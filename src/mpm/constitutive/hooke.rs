//! Linear (small-strain) Hooke law, the infinitesimal-strain reference of Nezamabadi et al. 2019,
//! Fig. 7: σ = λ tr(ε) I + 2μ ε with ε = sym(F) − I, taken as the first Piola–Kirchhoff stress
//! (the small-strain theory does not tell the stress measures apart). It is not frame-indifferent:
//! a rigid rotation produces stress, which is why the paper moves to the finite-strain laws.

use super::{check_lame, zero_tangent, Constitutive, Inverted, Mat, Tangent};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hooke {
    pub lambda: f64,
    pub mu: f64,
}

impl Hooke {
    pub fn new(lambda: f64, mu: f64) -> Result<Self, String> {
        check_lame(lambda, mu)?;
        Ok(Self { lambda, mu })
    }
}

impl<const D: usize> Constitutive<D> for Hooke {
    fn pk1(&self, f: &Mat<D>) -> Result<Mat<D>, Inverted> {
        let eps = (f + f.transpose()) * 0.5 - Mat::<D>::identity();
        Ok(Mat::<D>::identity() * (self.lambda * eps.trace()) + eps * (2.0 * self.mu))
    }

    /// W = λ/2 (tr ε)² + μ ε:ε.
    fn energy(&self, f: &Mat<D>) -> Result<f64, Inverted> {
        let eps = (f + f.transpose()) * 0.5 - Mat::<D>::identity();
        Ok(0.5 * self.lambda * eps.trace().powi(2) + self.mu * eps.norm_squared())
    }

    fn pk1_tangent(&self, f: &Mat<D>) -> Result<(Mat<D>, Tangent<D>), Inverted> {
        let mut a = zero_tangent::<D>();
        for (i, ai) in a.iter_mut().enumerate() {
            for (j, aij) in ai.iter_mut().enumerate() {
                for (k, aijk) in aij.iter_mut().enumerate() {
                    for (l, v) in aijk.iter_mut().enumerate() {
                        let d = |x: usize, y: usize| if x == y { 1.0 } else { 0.0 };
                        *v = self.lambda * d(i, j) * d(k, l)
                            + self.mu * (d(i, k) * d(j, l) + d(i, l) * d(j, k));
                    }
                }
            }
        }
        Ok((self.pk1(f)?, a))
    }
}

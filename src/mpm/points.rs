//! Material points of one body: constant mass, volume, deformation gradient F, Cauchy stress,
//! velocity and position (Nezamabadi et al. 2019, Section 2: the body is divided into N_p points
//! of constant mass, so Eq. 1 holds by construction).

use super::constitutive::Mat;
use super::grid::Vector;

#[derive(Clone, Debug, Default)]
pub struct Points<const D: usize> {
    pub mass: Vec<f64>,
    /// Initial volume V_p⁰ (per unit thickness in 2-D).
    pub vol0: Vec<f64>,
    /// Current volume V_p = J_p V_p⁰ (Eq. 13).
    pub vol: Vec<f64>,
    pub x: Vec<Vector<D>>,
    pub v: Vec<Vector<D>>,
    /// Deformation gradient from the initial configuration, ⁰ₜF.
    pub f: Vec<Mat<D>>,
    /// Cauchy stress σ = P Fᵀ / J (Eq. 9).
    pub sigma: Vec<Mat<D>>,
}

impl<const D: usize> Points<D> {
    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    pub fn push(&mut self, x: Vector<D>, vol: f64, density: f64) {
        self.mass.push(vol * density);
        self.vol0.push(vol);
        self.vol.push(vol);
        self.x.push(x);
        self.v.push(Vector::<D>::zeros());
        self.f.push(Mat::<D>::identity());
        self.sigma.push(Mat::<D>::zeros());
    }

    /// Points on the lattice of spacing h/n (n per cell and axis, at sub-cell centres) anchored at
    /// `anchor` (a grid node), kept where `inside` holds; each carries the volume (h/n)^D.
    pub fn seed(
        lo: Vector<D>,
        hi: Vector<D>,
        anchor: Vector<D>,
        h: f64,
        n: usize,
        density: f64,
        inside: impl Fn(&Vector<D>) -> bool,
    ) -> Self {
        let s = h / n as f64;
        let first: [i64; D] = std::array::from_fn(|d| ((lo[d] - anchor[d]) / s).floor() as i64);
        let last: [i64; D] = std::array::from_fn(|d| ((hi[d] - anchor[d]) / s).ceil() as i64);
        let counts: [usize; D] = std::array::from_fn(|d| (last[d] - first[d]).max(0) as usize);
        let total: usize = counts.iter().product();
        let mut pts = Self::default();
        for lin in 0..total {
            let mut rest = lin;
            let mut x = Vector::<D>::zeros();
            for d in 0..D {
                let k = first[d] + (rest % counts[d]) as i64;
                rest /= counts[d];
                x[d] = anchor[d] + (k as f64 + 0.5) * s;
            }
            if inside(&x) {
                pts.push(x, s.powi(D as i32), density);
            }
        }
        pts
    }

    /// Total linear momentum Σ m_p v_p.
    pub fn momentum(&self) -> Vector<D> {
        self.mass.iter().zip(&self.v).fold(Vector::<D>::zeros(), |acc, (m, v)| acc + v * *m)
    }

    /// Kinetic energy Σ ½ m_p |v_p|².
    pub fn kinetic_energy(&self) -> f64 {
        self.mass.iter().zip(&self.v).map(|(m, v)| 0.5 * m * v.norm_squared()).sum()
    }
}

//! What a compaction of many bodies in a box reports (Nezamabadi et al. 2019, Section 6.2, Figs.
//! 10–15): packing fraction Φ, cumulative vertical strain ε, particle volume change ln(V_S/V_Si),
//! mean coordination number Z, the top wall's stress σ, and the standard deviation and excess
//! kurtosis of the equivalent strain γ_eq (Eq. 24) and of J over the material points.

use std::fmt::Write;

use super::constitutive::{det, Mat};
use super::contact::ContactReport;
use super::implicit::{Body, Wall};

/// The first pair of walls across `axis`: the index of the wall on its low side (side +1, the
/// bodies above it) and of the one on its high side (side −1); `None` unless both exist.
pub fn wall_pair(walls: &[Wall], axis: usize) -> Option<(usize, usize)> {
    let lo = walls.iter().position(|w| w.axis == axis && w.side > 0.0)?;
    let hi = walls.iter().position(|w| w.axis == axis && w.side < 0.0)?;
    Some((lo, hi))
}

/// The walls bounding a box: a [`wall_pair`] across every axis, `None` unless every axis has one.
pub fn box_walls<const D: usize>(walls: &[Wall]) -> Option<[(usize, usize); D]> {
    let mut out = [(0, 0); D];
    for (d, o) in out.iter_mut().enumerate() {
        *o = wall_pair(walls, d)?;
    }
    Some(out)
}

/// Equivalent von Mises strain of Eq. 24, γ_eq = √(2/3 γᵈ:γᵈ), with γ = (FᵀF − I)/2 the
/// Green–Lagrange strain (in 2-D the plane-strain tensor, γ₃₃ = 0, enters the deviator).
pub fn equivalent_strain<const D: usize>(f: &Mat<D>) -> f64 {
    let g: Mat<D> = (f.transpose() * f - Mat::<D>::identity()) * 0.5;
    let tr = g.trace() / 3.0;
    let mut dd = 0.0;
    for i in 0..D {
        for j in 0..D {
            let v = g[(i, j)] - if i == j { tr } else { 0.0 };
            dd += v * v;
        }
    }
    if D == 2 {
        dd += tr * tr; // γᵈ₃₃ = 0 − tr/3
    }
    (2.0 / 3.0 * dd).sqrt()
}

/// Standard deviation and excess kurtosis of a sample (population moments).
pub fn sd_excess_kurtosis(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let (mut m2, mut m4) = (0.0, 0.0);
    for v in x {
        let d = v - m;
        m2 += d * d;
        m4 += d * d * d * d;
    }
    m2 /= n;
    m4 /= n;
    let kurt = if m2 > 0.0 { m4 / (m2 * m2) - 3.0 } else { 0.0 };
    (m2.sqrt(), kurt)
}

/// Rows of `packing.csv`, one per output step.
pub struct CompactionLog<const D: usize> {
    walls: [(usize, usize); D],
    vs0: f64,
    height0: f64,
    pub csv: String,
    gammas: Vec<f64>,
    js: Vec<f64>,
}

impl<const D: usize> CompactionLog<D> {
    pub fn new(walls: [(usize, usize); D], w: &[Wall], bodies: &[Body<D>]) -> Self {
        let a = D - 1;
        Self {
            walls,
            vs0: solid_volume(bodies),
            height0: w[walls[a].1].position - w[walls[a].0].position,
            csv: "step,time,phi,epsilon,ln_vs_over_vsi,Z,touching_pairs,sigma_top_pa,sd_gamma_eq,exkurt_gamma_eq,sd_J,exkurt_J\n"
                .into(),
            gammas: Vec::new(),
            js: Vec::new(),
        }
    }

    /// One row at the end of a step (walls already moved to the step's end).
    /// Φ: the bodies' solid volume over the box's (area in 2-D).
    pub fn phi(&self, bodies: &[Body<D>], walls: &[Wall]) -> f64 {
        let extent = |d: usize| walls[self.walls[d].1].position - walls[self.walls[d].0].position;
        solid_volume(bodies) / (0..D).map(extent).product::<f64>()
    }

    pub fn record(
        &mut self,
        step: usize,
        time: f64,
        bodies: &[Body<D>],
        walls: &[Wall],
        rep: &ContactReport,
    ) {
        let a = D - 1;
        let extent = |d: usize| walls[self.walls[d].1].position - walls[self.walls[d].0].position;
        let volume: f64 = (0..D).map(extent).product();
        let vs = solid_volume(bodies);
        // Top wall force over its area (2-D: per unit depth, over the box width).
        let area: f64 = (0..a).map(extent).product();
        let sigma = rep.wall_load[self.walls[a].1] / area;
        self.gammas.clear();
        self.js.clear();
        for b in bodies {
            for f in &b.points.f {
                self.gammas.push(equivalent_strain(f));
                self.js.push(det(f));
            }
        }
        let (sg, kg) = sd_excess_kurtosis(&self.gammas);
        let (sj, kj) = sd_excess_kurtosis(&self.js);
        let z = 2.0 * rep.touching_pairs as f64 / bodies.len() as f64;
        let _ = writeln!(
            self.csv,
            "{step},{time:.9e},{:.9e},{:.9e},{:.9e},{z:.6},{},{sigma:.9e},{sg:.9e},{kg:.9e},{sj:.9e},{kj:.9e}",
            vs / volume,
            (self.height0 / extent(a)).ln(),
            (vs / self.vs0).ln(),
            rep.touching_pairs,
        );
    }
}

/// Σ_p J_p V⁰_p over all bodies: the particles' current solid volume (area in 2-D).
/// How far each material point's domain reaches past a wall: the domain is the point's reference
/// sub-cell (side l = (V⁰)^{1/D}) mapped by its F, a parallelogram (parallelepiped) whose extent
/// along the wall's axis a is (l/2) Σ_j |F_aj| on each side of the point. Returns the largest
/// penetration over the points and walls [m] (≤ 0 when every domain is on its body's side) and the
/// volume of solid past the wall planes, each point's current volume times the fraction of that
/// extent beyond a plane (a slab estimate, exact for an axis-aligned domain).
pub fn domains_past_walls<const D: usize>(bodies: &[Body<D>], walls: &[Wall]) -> (f64, f64) {
    let (mut worst, mut volume) = (f64::NEG_INFINITY, 0.0);
    for b in bodies {
        let pts = &b.points;
        for p in 0..pts.len() {
            let l = pts.vol0[p].powf(1.0 / D as f64);
            for w in walls {
                let a = w.axis;
                let e = 0.5 * l * (0..D).map(|j| pts.f[p][(a, j)].abs()).sum::<f64>();
                // Signed distance of the point from the plane, positive on the body's side.
                let d = w.side * (pts.x[p][a] - w.position);
                worst = worst.max(e - d);
                volume += pts.vol[p] * ((e - d) / (2.0 * e)).clamp(0.0, 1.0);
            }
        }
    }
    (worst, volume)
}

/// Σ_p J_p V⁰_p over every body.
pub fn solid_volume<const D: usize>(bodies: &[Body<D>]) -> f64 {
    bodies.iter().flat_map(|b| b.points.f.iter().zip(&b.points.vol0)).map(|(f, v)| det(f) * v).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 24 on closed forms: zero for a rigid rotation, and for plane-strain uniaxial stretch
    /// F = diag(s, 1) with e = (s² − 1)/2 the deviator (2e/3, −e/3, −e/3) gives γ_eq = √(2/3 · 6e²/9).
    #[test]
    fn equivalent_strain_closed_forms() {
        let (c, s) = (0.6f64, 0.8f64);
        let rot = Mat::<2>::new(c, -s, s, c);
        assert!(equivalent_strain(&rot) < 1e-15);
        let st = 1.2f64;
        let e = 0.5 * (st * st - 1.0);
        let expect = (2.0 / 3.0 * (6.0 * e * e / 9.0)).sqrt();
        let got = equivalent_strain(&Mat::<2>::new(st, 0.0, 0.0, 1.0));
        assert!((got - expect).abs() < 1e-15, "{got} vs {expect}");
    }

    /// Moments of a symmetric two-point sample: SD 1, excess kurtosis 1 − 3 = −2.
    #[test]
    fn moments_of_a_two_point_sample() {
        let (sd, k) = sd_excess_kurtosis(&[-1.0, 1.0, -1.0, 1.0]);
        assert!((sd - 1.0).abs() < 1e-15 && (k + 2.0).abs() < 1e-15);
    }
}

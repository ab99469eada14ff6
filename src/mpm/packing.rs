//! Polydisperse disc (sphere) packings for the compaction scenes (Nezamabadi et al. 2019,
//! Section 6.2: diameters uniform by volume fraction in [d_min, d_max], no overlap, in a box).
//!
//! "Uniform by volume fraction" means each diameter class holds the same solid volume, so the
//! number density of diameters is ∝ d^−D (2-D: area ∝ d²). Sampled by inverting its distribution
//! function. Placement is random sequential addition, largest discs first, with a clearance of
//! `gap` between surfaces and from the box walls, so no grid node is shared at the start: the
//! packing starts loose (Φ ≈ 0.4–0.5 in 2-D) and the compaction itself brings it to jamming.
//! With `"compress"` the loose packing is then compressed by a frictionless DEM to jamming
//! (`packing_dem`), as the paper prepares its initial configuration, and the scene's top wall
//! starts where the DEM left it.

use serde::Deserialize;

use crate::rng::SplitMix64;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PackingSpec {
    /// Number of particles.
    pub count: usize,
    /// [d_min, d_max] [m].
    pub diameter: [f64; 2],
    /// The box the particles are placed in (its walls are given in "walls").
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    /// Clearance between surfaces and to the box [m] (default: none; give at least 2h so no grid
    /// node carries two bodies at the start).
    #[serde(default)]
    pub gap: f64,
    #[serde(default = "seed")]
    pub seed: u64,
    /// Compress the loose packing to jamming by DEM before the run (absent: start loose).
    #[serde(default)]
    pub compress: Option<CompressSpec>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompressSpec {
    /// Top wall pressure at which the DEM packing counts as jammed, in units of the contact
    /// stiffness over the largest diameter: the padded discs' overlaps are about this fraction of
    /// the largest diameter, and must stay below `gap` (default 1e-3).
    #[serde(default = "pressure")]
    pub pressure: f64,
}

fn pressure() -> f64 {
    1e-3
}

/// A generated packing: the particles, and where the top wall starts when the DEM compressed it.
#[derive(Clone, Debug)]
pub struct Packed {
    /// Centre [m] and radius [m] of each particle.
    pub discs: Vec<(Vec<f64>, f64)>,
    /// The DEM preparation, if any (its top wall position, overlaps and steps).
    pub compressed: Option<super::packing_dem::Compressed>,
}

fn seed() -> u64 {
    1
}

/// Tries per particle before the box is declared too small.
const TRIES: usize = 200_000;

impl PackingSpec {
    /// The particles, placed loose and, with `compress`, compressed to jamming by DEM; or an error
    /// naming what cannot be met.
    pub fn packed<const D: usize>(&self) -> Result<Packed, String> {
        let mut discs = self.discs(D)?;
        let compressed = match &self.compress {
            None => None,
            Some(c) => {
                let out =
                    super::packing_dem::compress::<D>(&discs, &self.lo, &self.hi, self.gap, c.pressure)?;
                for (d, x) in discs.iter_mut().zip(&out.centres) {
                    d.0.clone_from(x);
                }
                Some(out)
            }
        };
        Ok(Packed { discs, compressed })
    }

    /// The particles' centres and radii placed loose, or an error naming what cannot be met.
    pub fn discs(&self, dim: usize) -> Result<Vec<(Vec<f64>, f64)>, String> {
        let [d0, d1] = self.diameter;
        if !(d0.is_finite() && d0 > 0.0 && d1 >= d0) {
            return Err(format!(
                "packing: diameter must be [d_min, d_max] with 0 < d_min ≤ d_max, got {:?}",
                self.diameter
            ));
        }
        if self.count == 0 {
            return Err("packing: count must be at least 1".into());
        }
        if self.lo.len() != dim
            || self.hi.len() != dim
            || (0..dim)
                .any(|d| self.hi[d] <= self.lo[d] || !self.hi[d].is_finite() || !self.lo[d].is_finite())
        {
            return Err(format!(
                "packing: lo and hi need {dim} coordinates with hi > lo, got {:?}, {:?}",
                self.lo, self.hi
            ));
        }
        if !(self.gap.is_finite() && self.gap >= 0.0) {
            return Err(format!("packing: gap must be ≥ 0, got {}", self.gap));
        }
        let mut rng = SplitMix64(self.seed);
        let mut diam: Vec<f64> = (0..self.count).map(|_| diameter(rng.uniform(), d0, d1, dim)).collect();
        diam.sort_by(|a, b| b.total_cmp(a));
        let mut placed: Vec<(Vec<f64>, f64)> = Vec::with_capacity(self.count);
        for (i, &d) in diam.iter().enumerate() {
            let r = 0.5 * d;
            let mut ok = None;
            for _ in 0..TRIES {
                let c: Vec<f64> = (0..dim)
                    .map(|k| {
                        let (a, b) = (self.lo[k] + r + self.gap, self.hi[k] - r - self.gap);
                        a + rng.uniform() * (b - a).max(0.0)
                    })
                    .collect();
                let free = placed.iter().all(|(q, rq)| {
                    let dist2: f64 = c.iter().zip(q).map(|(x, y)| (x - y) * (x - y)).sum();
                    dist2 >= (r + rq + self.gap).powi(2)
                });
                if free {
                    ok = Some(c);
                    break;
                }
            }
            let c = ok.ok_or_else(|| {
                format!(
                    "packing: particle {i} (d = {d:.3e} m) does not fit after {TRIES} tries; enlarge the box or lower count"
                )
            })?;
            placed.push((c, r));
        }
        Ok(placed)
    }
}

/// The diameter at quantile u ∈ [0, 1) of the number density p(d) ∝ d^−D on [d0, d1] (inverse
/// of its distribution function), which gives every diameter class the same solid volume.
fn diameter(u: f64, d0: f64, d1: f64, dim: usize) -> f64 {
    let e = 1.0 - dim as f64;
    (d0.powf(e) + u * (d1.powf(e) - d0.powf(e))).powf(1.0 / e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal solid volume per diameter class: in 2-D (area ∝ d²) and 3-D (volume ∝ d³) the
    /// discs with d in the lower half of the range hold half the solid, the lowest quarter a
    /// quarter, to sampling error (20000 draws: under 1 %, asserted 2 %); the packing places them.
    #[test]
    fn diameters_are_uniform_by_volume_fraction() {
        let (d0, d1) = (2e-3f64, 4e-3f64);
        for dim in [2, 3] {
            let mut rng = SplitMix64(7);
            let (mut half, mut quarter, mut total) = (0.0, 0.0, 0.0);
            for _ in 0..20000 {
                let d = diameter(rng.uniform(), d0, d1, dim);
                assert!((d0..=d1).contains(&d), "{d}");
                let v = d.powi(dim as i32);
                total += v;
                if d < 3e-3 {
                    half += v;
                }
                if d < 2.5e-3 {
                    quarter += v;
                }
            }
            assert!((half / total - 0.5).abs() < 0.02, "dim {dim}: {}", half / total);
            assert!((quarter / total - 0.25).abs() < 0.02, "dim {dim}: {}", quarter / total);
        }
        let p = PackingSpec {
            count: 1,
            diameter: [d0, d1],
            lo: vec![0.0, 0.0],
            hi: vec![1.0, 1.0],
            gap: 0.0,
            seed: 7,
            compress: None,
        };
        assert_eq!(p.discs(2).unwrap().len(), 1);
    }
}

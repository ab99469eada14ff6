//! φ_c(μ) from the grid's rate data, one quasi-static set per μ, and Eq. 8 refitted with that φ_c.
//!
//! Ghods et al. (2022), Section 4.2: below φ_c the flow is inertial (Bagnold, p̂ ∝ γ̂²), above it
//! quasi-static (p̂ independent of γ̂), with an intermediate regime between them at finite rate. The
//! local rate exponent n(φ) = d ln p̂ / d ln γ̂ therefore falls from 2 (or the intermediate 1) to 0
//! across jamming. Two routes to φ_c, both from the recorded runs only:
//!
//! - (a) **rate exponent**: n between the two slowest rates, averaged over ν, crosses
//!   [`N_CROSS`] = 0.5 (linear interpolation in φ between grid points). 0.5 is the middle of the
//!   intermediate value 1 and the quasi-static 0, and the same threshold as the quasi-static test
//!   (`surface::quasi_static`), so the loosest quasi-static φ and this φ_c are defined alike. At
//!   finite rate the crossover lies above the γ̂ → 0 jamming point (it moves up when n is taken
//!   between faster rates), so the shift of the crossing from the slow to the fast rate pair is
//!   part of its error bar.
//! - (b) **p̂ → 0 extrapolation**: per ν, the exponent β for which p̂^(1/β) is most nearly linear
//!   in φ over the quasi-static points (least 1 − R²), and φ_c where that line reaches 0 (the usual
//!   way of extrapolating a pressure to zero without fixing β, e.g. O'Hern et al., Phys. Rev. E 68,
//!   011306 (2003)); mean and standard deviation over ν.

use std::collections::BTreeMap;

use serde::Serialize;

use super::protocol::RunResult;
use crate::study::fit;

/// The rate exponent that separates the inertial (2, intermediate 1) and quasi-static (0) branches.
pub const N_CROSS: f64 = 0.5;

/// One run reduced to what the φ_c routes read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RatePoint {
    pub mu: f64,
    pub nu: f64,
    pub phi: f64,
    pub gamma_hat: f64,
    pub p_hat: f64,
}

impl RatePoint {
    pub fn of(r: &RunResult) -> Self {
        RatePoint {
            mu: r.spec.mu,
            nu: r.spec.nu,
            phi: r.spec.phi,
            gamma_hat: r.spec.gamma_hat,
            p_hat: r.p_hat,
        }
    }
}

pub(super) fn key3(x: f64) -> i64 {
    (x * 1000.0).round() as i64
}

/// The runs of one μ grouped by (ν, φ), each group sorted by rate (slowest first).
fn groups(points: &[RatePoint], mu: f64) -> BTreeMap<(i64, i64), Vec<RatePoint>> {
    let mut g: BTreeMap<(i64, i64), Vec<RatePoint>> = BTreeMap::new();
    for p in points.iter().filter(|p| key3(p.mu) == key3(mu)) {
        g.entry((key3(p.nu), key3(p.phi))).or_default().push(*p);
    }
    for v in g.values_mut() {
        v.sort_by(|a, b| a.gamma_hat.total_cmp(&b.gamma_hat));
    }
    g
}

/// d ln p̂ / d ln γ̂ between rate `k` and rate `k + 1` of one (μ, ν, φ) group sorted by rate.
pub fn rate_exponent(sorted: &[RatePoint], k: usize) -> Option<f64> {
    let (a, b) = (sorted.get(k)?, sorted.get(k + 1)?);
    let n = (b.p_hat / a.p_hat).ln() / (b.gamma_hat / a.gamma_hat).ln();
    n.is_finite().then_some(n)
}

/// The quasi-static test of one (μ, ν, φ) group sorted by rate: n < [`N_CROSS`] between the two
/// slowest rates; with one rate, the inertial-number test p̂/γ̂² = p/(ρ d² γ̇²) > 10³.
pub fn passes(sorted: &[RatePoint]) -> bool {
    let Some(slow) = sorted.first() else { return false };
    let qs = match rate_exponent(sorted, 0) {
        Some(n) => n < N_CROSS,
        None => slow.p_hat / slow.gamma_hat.powi(2) > 1e3,
    };
    qs && slow.p_hat > 0.0
}

/// The quasi-static φ of one μ, the same for every ν: a φ enters when it passes the test for
/// more than half of the ν that ran there (the median ν's verdict). One ν alone would let the
/// scatter of a borderline point (n = 0.50–0.53 at μ = 0, φ = 0.65 in the full grid) decide for
/// that ν only; requiring all ν would let one noisy ν drop a point for every ν.
pub fn qs_phis(points: &[RatePoint], mu: f64) -> Vec<f64> {
    let mut votes: BTreeMap<i64, (f64, usize, usize)> = BTreeMap::new();
    for ((_, phi), g) in groups(points, mu) {
        let e = votes.entry(phi).or_insert((g[0].phi, 0, 0));
        e.1 += 1;
        e.2 += usize::from(passes(&g));
    }
    votes.values().filter(|(_, n, yes)| 2 * yes > *n).map(|v| v.0).collect()
}

/// Per ν of one μ: (ν, the quasi-static points (φ, p̂ at the slowest rate)) over the common set.
pub fn qs_sets(points: &[RatePoint], mu: f64) -> Vec<(f64, Vec<(f64, f64)>)> {
    let phis: Vec<i64> = qs_phis(points, mu).iter().map(|p| key3(*p)).collect();
    let mut by_nu: BTreeMap<i64, (f64, Vec<(f64, f64)>)> = BTreeMap::new();
    for ((nu, phi), g) in groups(points, mu) {
        let e = by_nu.entry(nu).or_insert((g[0].nu, Vec::new()));
        if phis.contains(&phi) && g[0].p_hat > 0.0 {
            e.1.push((g[0].phi, g[0].p_hat));
        }
    }
    by_nu.into_values().collect()
}

/// Where a curve n(φ) (sorted by φ) crosses a level going to denser packings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Crossing {
    /// Crosses at this φ (linear interpolation between the two grid φ around it).
    At(f64),
    /// Already below the level at the loosest φ: φ_c lies below it.
    Below(f64),
    /// Never below the level: φ_c lies above the densest φ.
    Above(f64),
}

impl Crossing {
    pub fn at(self) -> Option<f64> {
        match self {
            Crossing::At(x) => Some(x),
            _ => None,
        }
    }
}

/// The first crossing of `level` by n(φ) from above, scanning from the loosest φ, interpolating n
/// linearly in φ between the two grid φ around it.
pub fn crossing(curve: &[(f64, f64)], level: f64) -> Option<Crossing> {
    crossing_by(curve, level, false)
}

/// As [`crossing`], with `log`: ln n interpolated linearly instead of n (linear when n ≤ 0 at
/// the denser point). Where n falls steeply between two grid φ (2 → 0.05),
/// the two interpolations differ by a good part of the grid step: that difference measures how
/// far the grid resolves the crossing.
fn crossing_by(curve: &[(f64, f64)], level: f64, log: bool) -> Option<Crossing> {
    let first = curve.first()?;
    if first.1 < level {
        return Some(Crossing::Below(first.0));
    }
    for w in curve.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if y1 < level {
            let t = if log && y1 > 0.0 {
                (y0.ln() - level.ln()) / (y0.ln() - y1.ln())
            } else {
                (y0 - level) / (y0 - y1)
            };
            return Some(Crossing::At(x0 + (x1 - x0) * t));
        }
    }
    Some(Crossing::Above(curve[curve.len() - 1].0))
}

/// n(φ) of one μ between rates `k` and `k + 1`: (φ, mean over ν, standard deviation over ν).
pub fn rate_curve(points: &[RatePoint], mu: f64, k: usize) -> Vec<(f64, f64, f64)> {
    let mut by_phi: BTreeMap<i64, (f64, Vec<f64>)> = BTreeMap::new();
    for ((_, phi), g) in groups(points, mu) {
        if let Some(n) = rate_exponent(&g, k) {
            by_phi.entry(phi).or_insert((g[0].phi, Vec::new())).1.push(n);
        }
    }
    by_phi
        .into_values()
        .map(|(phi, ns)| {
            let (m, s) = mean_sd(&ns);
            (phi, m, s)
        })
        .collect()
}

pub(super) fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let s =
        if v.len() > 1 { (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() } else { 0.0 };
    (m, s)
}

/// Route (b) for one ν: the β in [0.25, 6] for which p̂^(1/β) is most nearly linear in φ
/// (least 1 − R² of the straight-line fit), and the φ where that line reaches 0: (φ_c, β). None
/// with fewer than three points, a best β at the edge of the scan (no power law fits better than
/// its limits) or a line that does not rise with φ.
pub fn linearised_phi_c(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    if points.len() < 3 || points.iter().any(|p| p.1 <= 0.0) {
        return None;
    }
    let line = |beta: f64| -> (f64, f64, f64) {
        let n = points.len() as f64;
        let z: Vec<f64> = points.iter().map(|p| p.1.powf(1.0 / beta)).collect();
        let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
        let mz = z.iter().sum::<f64>() / n;
        let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxz: f64 = points.iter().zip(&z).map(|(p, z)| (p.0 - mx) * (z - mz)).sum();
        let szz: f64 = z.iter().map(|z| (z - mz).powi(2)).sum();
        let slope = sxz / sxx;
        // 1 − R² of z on φ.
        let bad = 1.0 - sxz * sxz / (sxx * szz);
        (bad, slope, mz - slope * mx)
    };
    const LO: f64 = 0.25;
    const HI: f64 = 6.0;
    const STEPS: usize = 5750;
    let (mut best_k, mut best) = (0, f64::INFINITY);
    for k in 0..=STEPS {
        let b = LO + (HI - LO) * k as f64 / STEPS as f64;
        let (bad, _, _) = line(b);
        if bad < best {
            best = bad;
            best_k = k;
        }
    }
    if best_k == 0 || best_k == STEPS {
        return None;
    }
    let beta = LO + (HI - LO) * best_k as f64 / STEPS as f64;
    let (_, slope, icept) = line(beta);
    (slope > 0.0).then(|| (-icept / slope, beta))
}

/// φ_c of one μ by both routes, and the value the data-derived fit uses.
#[derive(Debug, Clone, Serialize)]
pub struct Jamming {
    pub mu: f64,
    /// Route (a): n̄ between the two slowest rates crosses [`N_CROSS`].
    pub rate: Option<Crossing>,
    /// The crossings of n̄ − sd and n̄ + sd (the ν spread), when both lie inside the grid.
    pub rate_spread: Option<(f64, f64)>,
    /// The same crossing between the next two rates (grids with three or more rates).
    pub rate_fast: Option<Crossing>,
    /// Half-width of route (a)'s error bar: the largest of half the ν spread, the shift to the
    /// fast rate pair (the crossover's own rate dependence) and the difference between linear and
    /// log interpolation of n (how far the grid resolves the crossing).
    pub rate_err: f64,
    /// Route (b): mean and standard deviation over ν of the linearised φ_c, mean β of those lines,
    /// and how many ν gave one.
    pub extrap: Option<(f64, f64, f64, usize)>,
    /// n(φ) between the two slowest rates: (φ, mean over ν, standard deviation over ν).
    pub curve: Vec<(f64, f64, f64)>,
    /// The common quasi-static φ of this μ.
    pub qs_phis: Vec<f64>,
    /// φ_c used for the data-derived Eq. 8 fit, its error bar, and which route gave it: route (a)
    /// where its crossing lies inside the grid, else route (b).
    pub data: Option<(f64, f64, &'static str)>,
}

/// Both routes for one μ.
pub fn jamming(points: &[RatePoint], mu: f64) -> Jamming {
    let slow = rate_curve(points, mu, 0);
    let fast = rate_curve(points, mu, 1);
    let pick = |c: &[(f64, f64, f64)], f: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<(f64, f64)> {
        c.iter().map(|p| (p.0, f(p))).collect()
    };
    let rate = crossing(&pick(&slow, &|p| p.1), N_CROSS);
    let lo = crossing(&pick(&slow, &|p| p.1 - p.2), N_CROSS).and_then(Crossing::at);
    let hi = crossing(&pick(&slow, &|p| p.1 + p.2), N_CROSS).and_then(Crossing::at);
    let rate_spread = lo.zip(hi);
    let rate_fast = crossing(&pick(&fast, &|p| p.1), N_CROSS);
    let at = rate.and_then(Crossing::at);
    let at_log = crossing_by(&pick(&slow, &|p| p.1), N_CROSS, true).and_then(Crossing::at);
    let rate_err = match at {
        Some(x) => {
            let spread = rate_spread.map_or(0.0, |(a, b)| 0.5 * (b - a).abs());
            let shift = rate_fast.and_then(Crossing::at).map_or(0.0, |f| (f - x).abs());
            let resolution = at_log.map_or(0.0, |l| (l - x).abs());
            spread.max(shift).max(resolution)
        }
        None => f64::NAN,
    };
    let lines: Vec<(f64, f64)> = qs_sets(points, mu).iter().filter_map(|s| linearised_phi_c(&s.1)).collect();
    let extrap = (!lines.is_empty()).then(|| {
        let (m, s) = mean_sd(&lines.iter().map(|l| l.0).collect::<Vec<_>>());
        let b = lines.iter().map(|l| l.1).sum::<f64>() / lines.len() as f64;
        (m, s, b, lines.len())
    });
    let data = match (at, extrap) {
        (Some(x), _) => Some((x, rate_err, "rate exponent")),
        (None, Some((m, s, _, _))) => Some((m, s, "p̂ → 0 extrapolation")),
        _ => None,
    };
    Jamming {
        mu,
        rate,
        rate_spread,
        rate_fast,
        rate_err,
        extrap,
        curve: slow,
        qs_phis: qs_phis(points, mu),
        data,
    }
}

/// Eq. 8 of one (μ, ν) at the data-derived φ_c and at the ends of its error bar: (α, β, β range).
/// The upper end is held 0.001 below the loosest quasi-static φ (the power law needs φ > φ_c).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct DataFit {
    pub alpha: f64,
    pub beta: f64,
    pub beta_min: f64,
    pub beta_max: f64,
}

pub fn data_fit(set: &[(f64, f64)], phi_c: f64, err: f64) -> Option<DataFit> {
    if set.len() < 3 {
        return None;
    }
    let top = set.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) - 1e-3;
    let at = fit::power_law(set, phi_c)?;
    let ends: Vec<f64> = [phi_c - err, (phi_c + err).min(top)]
        .iter()
        .filter_map(|&pc| fit::power_law(set, pc).map(|f| f.beta))
        .collect();
    let beta_min = ends.iter().copied().fold(at.beta, f64::min);
    let beta_max = ends.iter().copied().fold(at.beta, f64::max);
    Some(DataFit { alpha: at.alpha, beta: at.beta, beta_min, beta_max })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A synthetic grid: quasi-static p̂ = α (φ − φ_c)^β above φ_c, Bagnold p̂ = c γ̂² / (φ_c − φ)²
    /// below it; φ and rates as in the full grid plus three looser φ, with a ν dependence of α.
    fn synthetic(pc: f64, beta: f64) -> Vec<RatePoint> {
        let mut v = Vec::new();
        for (i, &nu) in [0.25, 0.3, 0.35, 0.4, 0.45, 0.5].iter().enumerate() {
            let alpha = 0.5 * (1.0 + 0.2 * i as f64);
            for phi in [0.55, 0.575, 0.6, 0.625, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9] {
                for g in [1e-3, 3e-3, 1e-2] {
                    let p_hat = if phi > pc {
                        alpha * f64::powf(phi - pc, beta)
                    } else {
                        0.05 * g * g / (pc - phi).powi(2)
                    };
                    v.push(RatePoint { mu: 0.0, nu, phi, gamma_hat: g, p_hat });
                }
            }
        }
        v
    }

    /// Both routes recover φ_c = 0.61 and β = 1.5 from the synthetic rate data. Tolerances: route
    /// (a) interpolates n between the grid φ around φ_c (0.6 and 0.625, n = 2 and 0), so it can
    /// only place φ_c within that grid step: |Δφ_c| < 0.025 (it gives 0.619); route (b) is exact
    /// for an exact power law up to the scan step of β (0.001), so 0.002 in φ_c and 0.01 in β; the
    /// refit at the true φ_c returns β to 1e-6, and the β range over φ_c ± 0.01 contains it.
    #[test]
    fn both_routes_recover_phi_c_and_beta() {
        let (pc, beta) = (0.61, 1.5);
        let pts = synthetic(pc, beta);
        let j = jamming(&pts, 0.0);
        let a = j.rate.and_then(Crossing::at).expect("route (a) crosses inside the grid");
        assert!(a >= pc - 1e-9 && a - pc < 0.025, "route (a): {a} ({j:?})");
        let (b, sd, bb, count) = j.extrap.expect("route (b)");
        assert!((b - pc).abs() < 0.002 && sd < 0.002 && count == 6, "route (b): {b} ± {sd} ({j:?})");
        assert!((bb - beta).abs() < 0.01, "route (b) β {bb}");
        for (_, set) in qs_sets(&pts, 0.0) {
            let f = data_fit(&set, pc, 0.01).unwrap();
            assert!((f.beta - beta).abs() < 1e-6 && f.beta_min < beta && f.beta_max > beta, "{f:?}");
        }
        // The crossover's rate dependence is seen: the faster pair crosses at denser φ.
        let fast = j.rate_fast.and_then(Crossing::at).unwrap();
        assert!(fast >= a, "fast {fast} slow {a}");
    }

    /// A borderline φ that passes the test for one ν only (n = 0.49 against 0.51–0.53 for the
    /// others) enters for no ν; one that passes for four ν of six enters for all six.
    #[test]
    fn quasi_static_set_is_the_same_for_every_nu() {
        let mut pts = Vec::new();
        for (i, &nu) in [0.25, 0.3, 0.35, 0.4, 0.45, 0.5].iter().enumerate() {
            let add = |pts: &mut Vec<RatePoint>, phi: f64, n: f64| {
                for g in [1e-3, 3e-3] {
                    pts.push(RatePoint { mu: 0.0, nu, phi, gamma_hat: g, p_hat: 1e-3 * (g / 1e-3).powf(n) });
                }
            };
            add(&mut pts, 0.65, if i == 4 { 0.49 } else { 0.51 + 0.004 * i as f64 });
            add(&mut pts, 0.7, if i < 4 { 0.2 } else { 0.6 });
            add(&mut pts, 0.75, 0.1);
        }
        assert_eq!(qs_phis(&pts, 0.0), vec![0.7, 0.75]);
        let sets = qs_sets(&pts, 0.0);
        assert_eq!(sets.len(), 6);
        for (nu, set) in &sets {
            let phis: Vec<f64> = set.iter().map(|p| p.0).collect();
            assert_eq!(phis, vec![0.7, 0.75], "ν = {nu}");
        }
    }

    #[test]
    fn crossing_cases() {
        let mid = crossing(&[(0.6, 1.0), (0.7, 0.0)], 0.5).and_then(Crossing::at).unwrap();
        assert!((mid - 0.65).abs() < 1e-12, "{mid}");
        assert_eq!(crossing(&[(0.6, 0.4), (0.7, 0.0)], 0.5), Some(Crossing::Below(0.6)));
        assert_eq!(crossing(&[(0.6, 1.0), (0.7, 0.9)], 0.5), Some(Crossing::Above(0.7)));
        assert_eq!(crossing(&[], 0.5), None);
    }
}

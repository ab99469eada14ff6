//! The Eq. 8 response surface p̂ = α |φ − φ_c|^β fitted to the quasi-static limit of the grid
//! (the power law itself is `study::fit`).

use std::collections::BTreeMap;

use serde::Serialize;

use super::grid::Grid;
use super::jamming::{data_fit, jamming, key3, qs_sets, rate_exponent, Jamming, RatePoint};
use super::paper::paper_values;
use super::protocol::RunResult;
use crate::study::fit;

/// One row of the response surface.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceRow {
    pub mu: f64,
    pub nu: f64,
    pub phi_c: f64,
    pub alpha: f64,
    pub beta: f64,
    pub alpha_paper: f64,
    pub beta_paper: f64,
    /// Quasi-static points above jamming used in the fit.
    pub points: usize,
    /// RMS of the log residuals.
    pub rms_log: f64,
    /// Eq. 8 at φ_c from the rate data (`jamming::Jamming::data`): that φ_c, α, β, and the range
    /// of β over φ_c ± its error bar (NaN where there is no such φ_c or fewer than three points).
    pub phi_c_data: f64,
    pub alpha_data: f64,
    pub beta_data: f64,
    pub beta_data_min: f64,
    pub beta_data_max: f64,
}

/// Lower end of the φ_c search for one μ: the densest φ (any ν) that is clearly inertial
/// (p̂ ∝ γ̂^s with s ≥ 1.5 between the two slowest rates); 0.5 when there is none.
pub fn phi_c_floor(results: &[RunResult], mu: f64) -> f64 {
    let pts: Vec<RatePoint> = results.iter().map(RatePoint::of).collect();
    rate_curve_all(&pts, mu).into_iter().filter(|p| p.1 >= 1.5).map(|p| p.0).fold(0.5, f64::max)
}

/// (φ, n) of every (ν, φ) of one μ between the two slowest rates.
fn rate_curve_all(pts: &[RatePoint], mu: f64) -> Vec<(f64, f64)> {
    let mut g: BTreeMap<(i64, i64), Vec<RatePoint>> = BTreeMap::new();
    for p in pts.iter().filter(|p| key3(p.mu) == key3(mu)) {
        g.entry((key3(p.nu), key3(p.phi))).or_default().push(*p);
    }
    g.values_mut()
        .filter_map(|v| {
            v.sort_by(|a, b| a.gamma_hat.total_cmp(&b.gamma_hat));
            rate_exponent(v, 0).map(|n| (v[0].phi, n))
        })
        .collect()
}

pub(super) type PointMap = BTreeMap<(i64, i64), Vec<(f64, f64)>>;

/// Quasi-static points above jamming per (μ, ν): (φ, p̂ at the slowest rate), over the one set of
/// φ per μ that passes the quasi-static test for the majority of ν (`jamming::qs_phis`).
pub(super) fn qs_points(results: &[RunResult]) -> PointMap {
    let pts: Vec<RatePoint> = results.iter().map(RatePoint::of).collect();
    let mus: std::collections::BTreeSet<i64> = pts.iter().map(|p| key3(p.mu)).collect();
    let mut out: PointMap = BTreeMap::new();
    for mu in mus {
        for (nu, set) in qs_sets(&pts, mu as f64 / 1000.0) {
            if !set.is_empty() {
                out.insert((mu, key3(nu)), set);
            }
        }
    }
    out
}

/// φ_c of every μ of the grid from its rate data (`jamming`).
pub fn jamming_of(grid: &Grid, results: &[RunResult]) -> Vec<Jamming> {
    let pts: Vec<RatePoint> = results.iter().map(RatePoint::of).collect();
    grid.mus
        .iter()
        .filter(|&&mu| pts.iter().any(|p| key3(p.mu) == key3(mu)))
        .map(|&mu| jamming(&pts, mu))
        .collect()
}

/// Eq. 8 per (μ, ν), φ_c shared by all ν of one μ.
pub fn response_surface(
    grid: &Grid,
    results: &[RunResult],
) -> (Vec<SurfaceRow>, BTreeMap<String, (f64, f64)>) {
    let pts = qs_points(results);
    let jam = jamming_of(grid, results);
    // (μ, ν) with at least one finished run: a sub-grid study leaves the others without a row
    // (their stopped runs are listed in the report; a (μ, ν) with finished runs but no
    // quasi-static point still gets its row, with 0 points).
    let ran: std::collections::BTreeSet<(i64, i64)> =
        results.iter().map(|r| (key3(r.spec.mu), key3(r.spec.nu))).collect();
    let mut rows = Vec::new();
    let mut phi_c = BTreeMap::new();
    for &mu in &grid.mus {
        let sets: Vec<(f64, Vec<(f64, f64)>)> = grid
            .nus
            .iter()
            .map(|&nu| (nu, pts.get(&(key3(mu), key3(nu))).cloned().unwrap_or_default()))
            .collect();
        let usable: Vec<&(f64, Vec<(f64, f64)>)> = sets.iter().filter(|s| s.1.len() >= 3).collect();
        let floor = phi_c_floor(results, mu);
        let fitted = fit::shared_phi_c(&usable.iter().map(|s| s.1.clone()).collect::<Vec<_>>(), floor);
        if let Some((pc, _)) = &fitted {
            phi_c.insert(format!("{mu}"), (*pc, floor));
        }
        for (nu, set) in &sets {
            if !ran.contains(&(key3(mu), key3(*nu))) {
                continue;
            }
            let (a_p, b_p) = paper_values(mu, *nu).unwrap_or((f64::NAN, f64::NAN));
            let mut row = SurfaceRow {
                mu,
                nu: *nu,
                phi_c: f64::NAN,
                alpha: f64::NAN,
                beta: f64::NAN,
                alpha_paper: a_p,
                beta_paper: b_p,
                points: set.len(),
                rms_log: f64::NAN,
                phi_c_data: f64::NAN,
                alpha_data: f64::NAN,
                beta_data: f64::NAN,
                beta_data_min: f64::NAN,
                beta_data_max: f64::NAN,
            };
            if let Some((pc, err, _)) = jam.iter().find(|j| key3(j.mu) == key3(mu)).and_then(|j| j.data) {
                row.phi_c_data = pc;
                if let Some(d) = data_fit(set, pc, err) {
                    (row.alpha_data, row.beta_data, row.beta_data_min, row.beta_data_max) =
                        (d.alpha, d.beta, d.beta_min, d.beta_max);
                }
            }
            if let Some((pc, fits)) = &fitted {
                if let Some(k) = usable.iter().position(|u| u.0 == *nu) {
                    row.phi_c = *pc;
                    row.alpha = fits[k].alpha;
                    row.beta = fits[k].beta;
                    row.rms_log = (fits[k].sse / set.len() as f64).sqrt();
                }
            }
            rows.push(row);
        }
    }
    (rows, phi_c)
}

//! The Eq. 8 response surface p̂ = α |φ − φ_c|^β fitted to the quasi-static limit of the grid
//! (the power law itself is `study::fit`).

use std::collections::BTreeMap;

use serde::Serialize;

use super::grid::Grid;
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
}

/// Is a (μ, ν, φ) point quasi-static? With two or more shear rates: the pressure grows slower
/// than γ̂^0.5 between the two slowest (inertial flow gives γ̂²). With one rate: the inertial
/// number test p̂/γ̂² = p/(ρ d² γ̇²) > 10³.
pub(super) fn quasi_static(runs: &[&RunResult]) -> Option<f64> {
    let mut rs: Vec<&&RunResult> = runs.iter().collect();
    rs.sort_by(|a, b| a.spec.gamma_hat.total_cmp(&b.spec.gamma_hat));
    let slow = rs.first()?;
    let qs = if let Some(s) = rate_exponent(runs) {
        s < 0.5
    } else {
        slow.p_hat / slow.spec.gamma_hat.powi(2) > 1e3
    };
    (qs && slow.p_hat > 0.0).then_some(slow.p_hat)
}

/// d ln p̂ / d ln γ̂ between the two slowest rates of one (μ, ν, φ) point (None with one rate).
pub(super) fn rate_exponent(runs: &[&RunResult]) -> Option<f64> {
    let mut rs: Vec<&&RunResult> = runs.iter().collect();
    rs.sort_by(|a, b| a.spec.gamma_hat.total_cmp(&b.spec.gamma_hat));
    let (slow, fast) = (rs.first()?, rs.get(1)?);
    Some((fast.p_hat / slow.p_hat).ln() / (fast.spec.gamma_hat / slow.spec.gamma_hat).ln())
}

/// Lower end of the φ_c search for one μ: the densest φ (any ν) that is clearly inertial
/// (p̂ ∝ γ̂^s with s ≥ 1.5 between the two slowest rates); 0.5 when there is none.
pub fn phi_c_floor(results: &[RunResult], mu: f64) -> f64 {
    let mut groups: BTreeMap<(i64, i64), Vec<&RunResult>> = BTreeMap::new();
    for r in results.iter().filter(|r| key3(r.spec.mu) == key3(mu)) {
        groups.entry((key3(r.spec.nu), key3(r.spec.phi))).or_default().push(r);
    }
    groups
        .values()
        .filter(|runs| rate_exponent(runs).is_some_and(|s| s >= 1.5))
        .map(|runs| runs[0].spec.phi)
        .fold(0.5, f64::max)
}

pub(super) type PointMap = BTreeMap<(i64, i64), Vec<(f64, f64)>>;

pub(super) fn key3(x: f64) -> i64 {
    (x * 1000.0).round() as i64
}

/// Quasi-static points above jamming per (μ, ν): (φ, p̂ at the slowest rate).
pub(super) fn qs_points(results: &[RunResult]) -> PointMap {
    let mut groups: BTreeMap<(i64, i64, i64), Vec<&RunResult>> = BTreeMap::new();
    for r in results {
        groups.entry((key3(r.spec.mu), key3(r.spec.nu), key3(r.spec.phi))).or_default().push(r);
    }
    let mut pts: PointMap = BTreeMap::new();
    for ((mu, nu, _), runs) in groups {
        if let Some(p) = quasi_static(&runs) {
            pts.entry((mu, nu)).or_default().push((runs[0].spec.phi, p));
        }
    }
    pts
}

/// Eq. 8 per (μ, ν), φ_c shared by all ν of one μ.
pub fn response_surface(
    grid: &Grid,
    results: &[RunResult],
) -> (Vec<SurfaceRow>, BTreeMap<String, (f64, f64)>) {
    let pts = qs_points(results);
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
            };
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

//! The (φ, μ, ν, γ̂) grid of the study, its options and summary, the cost table's rows, and the
//! small file helpers the runs and the report share.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::protocol::{Protocol, RunSpec, RESTITUTION};
use crate::harness::calibration::calibrated;

/// The parameter grid of a study.
#[derive(Debug, Clone)]
pub struct Grid {
    pub name: String,
    pub phis: Vec<f64>,
    pub mus: Vec<f64>,
    pub nus: Vec<f64>,
    pub gamma_hats: Vec<f64>,
    pub n: usize,
    /// γ of Eq. 2 for every ν; None (the default): each ν's value from the recorded calibration
    /// (`validation/reference/calibration_mcdem.csv`, the paper's Fig. 5 procedure).
    pub gamma_mc: Option<f64>,
    /// MPR of Eq. 3 for every ν; None: from the recorded calibration, as γ.
    pub mpr: Option<f64>,
    pub restitution: f64,
    /// Every run with Eq. 2 iterated to its fixed point within the step ([`RunSpec::eq2_fixed_point`]).
    pub eq2_fixed_point: bool,
    pub protocol: Protocol,
    /// Cost-vs-N measurement: sizes and shear steps timed per size (empty: none).
    pub cost_sizes: Vec<usize>,
    pub cost_steps: u64,
}

impl Grid {
    /// A sub-grid for a few minutes on two cores.
    pub fn quick() -> Self {
        Grid {
            name: "quick".into(),
            phis: vec![0.55, 0.6, 0.65, 0.7, 0.75, 0.8],
            mus: vec![0.0, 0.5],
            nus: vec![0.25, 0.5],
            gamma_hats: vec![1e-3, 4e-3],
            n: 250,
            gamma_mc: None,
            mpr: None,
            restitution: RESTITUTION,
            eq2_fixed_point: false,
            protocol: Protocol::quick(),
            cost_sizes: vec![250, 500, 1000, 2000],
            cost_steps: 300,
        }
    }

    /// The paper's grid (Section 4, App. D).
    pub fn full() -> Self {
        Grid {
            name: "full".into(),
            phis: vec![0.625, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9],
            mus: vec![0.0, 0.1, 0.3, 0.5, 1.0],
            nus: vec![0.25, 0.3, 0.35, 0.4, 0.45, 0.5],
            gamma_hats: vec![1e-3, 3e-3, 1e-2],
            n: 2000,
            gamma_mc: None,
            mpr: None,
            restitution: RESTITUTION,
            eq2_fixed_point: false,
            protocol: Protocol::full(),
            cost_sizes: vec![500, 2000, 8000, 20000],
            cost_steps: 500,
        }
    }

    /// (γ, MPR) of the advanced MC law at ν: the explicit values, else the recorded calibration's.
    pub fn law(&self, nu: f64) -> Result<(f64, f64), String> {
        let cal = calibrated(nu);
        let pick = |given: Option<f64>, from_cal: Option<f64>, what: &str| {
            given.or(from_cal).ok_or_else(|| {
                format!("no recorded calibration for nu = {nu} to take {what} from: give it with --{what}")
            })
        };
        Ok((pick(self.gamma_mc, cal.map(|l| l.gamma), "gamma")?, pick(self.mpr, cal.map(|l| l.mpr), "mpr")?))
    }

    pub fn specs(&self) -> Result<Vec<RunSpec>, String> {
        let mut v = Vec::new();
        for &mu in &self.mus {
            for &nu in &self.nus {
                let (gamma_mc, mpr) = self.law(nu)?;
                for &phi in &self.phis {
                    for &gamma_hat in &self.gamma_hats {
                        v.push(RunSpec {
                            phi,
                            mu,
                            nu,
                            gamma_hat,
                            n: self.n,
                            gamma_mc,
                            mpr,
                            restitution: self.restitution,
                            seed: 1,
                            eq2_fixed_point: self.eq2_fixed_point,
                        });
                    }
                }
            }
        }
        Ok(v)
    }
}

/// Study options.
#[derive(Debug, Clone)]
pub struct Options {
    pub grid: Grid,
    pub out: PathBuf,
    /// Runs side by side (each single-threaded).
    pub threads: usize,
    /// Measure cost vs N only: no grid run is started (finished ones are still reported).
    pub cost_only: bool,
    /// Rewrite the outputs from the finished runs on disk and the cached cost rows: no run and no
    /// cost measurement is started.
    pub report_only: bool,
}

/// Cost-vs-N measurement.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CostRow {
    pub n: usize,
    pub steps: u64,
    pub seconds: f64,
    pub particle_steps_per_s: f64,
    pub seconds_per_step: f64,
    /// The same run with spatial sorting off (particles in creation order), timed right after:
    /// what the sorting buys at this N.
    pub unsorted_seconds_per_step: f64,
    pub phi: f64,
    pub mu: f64,
    pub nu: f64,
    pub gamma_hat: f64,
}

pub(super) fn read_json<T: for<'a> Deserialize<'a>>(path: &Path) -> Option<T> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

pub(super) fn write_atomic(path: &Path, text: &str) -> Result<(), String> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

pub(super) fn single_thread<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, String> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| e.to_string())?;
    Ok(pool.install(f))
}

/// How the report states the law's (γ, MPR): given values, or the calibration's per ν.
pub(super) fn law_text(g: &Grid) -> String {
    let per_nu: Vec<String> = g
        .nus
        .iter()
        .filter_map(|&nu| g.law(nu).ok().map(|(ga, m)| format!("ν = {nu}: γ = {ga}, MPR = {m}")))
        .collect();
    match (g.gamma_mc, g.mpr) {
        (Some(ga), Some(m)) => format!("γ = {ga}, MPR = {m} at every ν"),
        _ => format!(
            "γ and MPR per ν{} — {}",
            if g.gamma_mc.is_some() || g.mpr.is_some() {
                " (one of them given, the other calibrated)"
            } else {
                " from the recorded calibration (validation/reference/calibration_mcdem.csv)"
            },
            per_nu.join("; ")
        ),
    }
}

//! The (φ, μ, ν, γ̂) grid of the study, its runs on the threads (a restarted study skips the runs
//! already on disk) and the cost table.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::protocol::{
    prepare_sorted, run_one, start_shear, time_unit, Protocol, RunResult, RunSpec, RESTITUTION,
};
use super::report::write_outputs;
use super::surface::{response_surface, SurfaceRow};
use crate::harness::calibration::calibrated;
use crate::harness::progress::Progress;

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
}

/// What a study call did.
#[derive(Debug, Clone, Default)]
pub struct Summary {
    pub ran: usize,
    pub skipped: usize,
    pub failed: Vec<(String, String)>,
    pub results: Vec<RunResult>,
    pub surface: Vec<SurfaceRow>,
    /// Per μ: fitted φ_c and the lower end of its search interval.
    pub phi_c: BTreeMap<String, (f64, f64)>,
    pub cost: Vec<CostRow>,
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

/// Runs (or resumes) the study and writes every output into `opts.out`.
pub fn run(opts: &Options, say: &(dyn Fn(&str) + Sync)) -> Result<Summary, String> {
    let runs_dir = opts.out.join("runs");
    std::fs::create_dir_all(&runs_dir).map_err(|e| format!("cannot create {}: {e}", runs_dir.display()))?;
    let specs = opts.grid.specs()?;
    let proto = &opts.grid.protocol;
    let mut done: Vec<RunResult> = Vec::new();
    let mut todo: Vec<RunSpec> = Vec::new();
    let mut failed = Vec::new();
    for s in specs {
        let key = s.key();
        if let Ok(e) = std::fs::read_to_string(runs_dir.join(format!("{key}.failed"))) {
            // A run that stopped (deterministic): not retried; delete the file to retry it.
            failed.push((key, e.trim().to_string()));
            continue;
        }
        match read_json::<RunResult>(&runs_dir.join(format!("{key}.json"))) {
            Some(r) if r.spec == s && &r.protocol == proto => done.push(r),
            _ => todo.push(s),
        }
    }
    if opts.cost_only {
        todo.clear();
    }
    let skipped = done.len() + failed.len();
    let total = todo.len();
    say(&format!(
        "shear study '{}': {} runs to do, {} already finished in {}",
        opts.grid.name,
        total,
        skipped,
        runs_dir.display()
    ));
    // One progress item per grid run; the lines of `say` go above the bar.
    let progress = Progress::new("study shear", total);
    let say_above = |l: &str| progress.suspend(|| say(l));
    let say_run: &(dyn Fn(&str) + Sync) = &say_above;
    // Longest first (slow shear rates), so the two threads finish together.
    todo.sort_by(|a, b| a.gamma_hat.total_cmp(&b.gamma_hat).then(b.phi.total_cmp(&a.phi)));
    // Exactly `threads` runs at a time: plain worker threads take the next run from a shared
    // index, and each runs it inside its own one-thread pool (the engine's pair loop then stays
    // serial). A rayon pool of pools would let a waiting worker start further runs.
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let outcomes: Vec<Result<RunResult, (String, String)>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..opts.threads.max(1))
            .map(|_| {
                scope.spawn(|| -> Vec<Result<RunResult, (String, String)>> {
                    let mut mine = Vec::new();
                    let pool = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                        Ok(p) => p,
                        Err(e) => {
                            mine.push(Err(("thread pool".to_string(), e.to_string())));
                            return mine;
                        }
                    };
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(s) = todo.get(i) else { break };
                        // The grid coordinates, not the file key (which repeats the law and N).
                        let name = format!("phi={:.3} mu={} nu={} g={:.1e}", s.phi, s.mu, s.nu, s.gamma_hat);
                        progress.start(&name);
                        let r = pool.install(|| run_one(s, proto));
                        progress.finish(&name);
                        let k = finished.fetch_add(1, Ordering::Relaxed) + 1;
                        mine.push(finish(s, r, k, total, &runs_dir, say_run));
                    }
                    mine
                })
            })
            .collect();
        workers.into_iter().flat_map(|w| w.join().unwrap_or_default()).collect()
    });
    drop(progress);
    let ran = outcomes.iter().filter(|o| o.is_ok()).count();
    for o in outcomes {
        match o {
            Ok(r) => done.push(r),
            Err(e) => failed.push(e),
        }
    }
    done.sort_by(|a, b| {
        (a.spec.mu, a.spec.nu, a.spec.phi, a.spec.gamma_hat)
            .partial_cmp(&(b.spec.mu, b.spec.nu, b.spec.phi, b.spec.gamma_hat))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let cost = cost_rows(opts, say)?;
    let (surface, phi_c) = response_surface(&opts.grid, &done);
    write_outputs(opts, &done, &failed, &surface, &phi_c, &cost)?;
    Ok(Summary { ran, skipped, failed, results: done, surface, phi_c, cost })
}

/// Stores a finished run (JSON) and reports it.
pub(super) fn finish(
    s: &RunSpec,
    r: Result<RunResult, String>,
    k: usize,
    total: usize,
    runs_dir: &Path,
    say: &(dyn Fn(&str) + Sync),
) -> Result<RunResult, (String, String)> {
    match r {
        Ok(r) => {
            let text = serde_json::to_string_pretty(&r).map_err(|e| (s.key(), e.to_string()))?;
            write_atomic(&runs_dir.join(format!("{}.json", s.key())), &text).map_err(|e| (s.key(), e))?;
            say(&format!(
                "[{k}/{total}] φ {:.3} μ {} ν {} γ̂ {:.1e}: p̂ {:.4e} (kin {:.2e}) Z {:.2} {} strain {:.2}, {:.1} s, {:.2e} particle-steps/s",
                s.phi,
                s.mu,
                s.nu,
                s.gamma_hat,
                r.p_hat,
                r.p_hat_kinetic,
                r.z,
                if r.steady { "steady at" } else { "NOT steady by" },
                if r.steady { r.strain_steady } else { r.strain_avg_to },
                r.wall_s,
                r.particle_steps_per_s
            ));
            Ok(r)
        }
        Err(e) => {
            say(&format!("[{k}/{total}] {} failed: {e}", s.key()));
            let _ = write_atomic(&runs_dir.join(format!("{}.failed", s.key())), &format!("{e}\n"));
            Err((s.key(), e))
        }
    }
}

/// Cost per particle-step at growing N (one grid point, single thread, short shear after a short
/// compression; only the shear steps are timed). Cached in DIR/cost/.
pub(super) fn cost_rows(opts: &Options, say: &(dyn Fn(&str) + Sync)) -> Result<Vec<CostRow>, String> {
    let g = &opts.grid;
    if g.cost_sizes.is_empty() {
        return Ok(Vec::new());
    }
    let dir = opts.out.join("cost");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let (phi, mu, nu, gamma_hat) = (0.7, 0.5, 0.5, 1e-3);
    let (gamma_mc, mpr) = g.law(nu)?;
    let mut rows = Vec::new();
    for &n in &g.cost_sizes {
        let path = dir.join(format!("n{n}_steps{}.json", g.cost_steps));
        if let Some(r) = read_json::<CostRow>(&path) {
            rows.push(r);
            continue;
        }
        let spec = RunSpec { phi, mu, nu, gamma_hat, n, gamma_mc, mpr, restitution: g.restitution, seed: 7 };
        let row = single_thread(|| -> Result<CostRow, String> {
            // Both worlds side by side, timed in alternating chunks so that a slow spell of a
            // shared machine hits both; at least 2e6 particle-steps each, so small N is timed
            // over more than a few milliseconds.
            let steps = g.cost_steps.max(2_000_000 / n as u64);
            let mut worlds = Vec::new();
            for sort in [true, false] {
                let (mut w, l) = prepare_sorted(&spec, 1000, sort)?;
                start_shear(&mut w, gamma_hat / time_unit(nu), l);
                for _ in 0..20 {
                    w.step().map_err(|e| e.to_string())?;
                }
                worlds.push(w);
            }
            const CHUNKS: u64 = 5;
            let mut secs_of = [0.0; 2];
            for c in 0..CHUNKS {
                let todo = steps * (c + 1) / CHUNKS - steps * c / CHUNKS;
                for (w, t) in worlds.iter_mut().zip(secs_of.iter_mut()) {
                    let t0 = Instant::now();
                    for _ in 0..todo {
                        w.step().map_err(|e| e.to_string())?;
                    }
                    *t += t0.elapsed().as_secs_f64();
                }
            }
            let [secs, unsorted] = secs_of;
            Ok(CostRow {
                unsorted_seconds_per_step: unsorted / steps as f64,
                n,
                steps,
                seconds: secs,
                particle_steps_per_s: (n as u64 * steps) as f64 / secs,
                seconds_per_step: secs / steps as f64,
                phi,
                mu,
                nu,
                gamma_hat,
            })
        })??;
        say(&format!(
            "cost N = {n}: {:.3e} particle-steps/s ({:.3e} s per step; {:.3e} without spatial sorting)",
            row.particle_steps_per_s, row.seconds_per_step, row.unsorted_seconds_per_step
        ));
        write_atomic(&path, &serde_json::to_string_pretty(&row).map_err(|e| e.to_string())?)?;
        rows.push(row);
    }
    Ok(rows)
}

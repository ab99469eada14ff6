//! The study's runs on the threads (a restarted study skips the runs already on disk), their
//! outputs, and the cost table.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use super::grid::{read_json, single_thread, write_atomic, CostRow, Options};
use super::jamming::Jamming;
use super::protocol::{prepare_sorted, run_one_from, start_shear, time_unit, RunResult, RunSpec, Stop};
use super::recorded_stop::recorded_stop;
use super::report::write_outputs;
use super::surface::{jamming_of, response_surface, SurfaceRow};
use crate::harness::progress::Progress;

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
    /// Per μ: φ_c from the rate data by both routes (`jamming`).
    pub jamming: Vec<Jamming>,
    pub cost: Vec<CostRow>,
}

/// Runs (or resumes) the study and writes every output into `opts.out`.
pub fn run(opts: &Options, say: &(dyn Fn(&str) + Sync)) -> Result<Summary, String> {
    let runs_dir = opts.out.join("runs");
    std::fs::create_dir_all(&runs_dir).map_err(|e| format!("cannot create {}: {e}", runs_dir.display()))?;
    let specs = opts.grid.specs()?;
    let proto = &opts.grid.protocol;
    let mut done: Vec<RunResult> = Vec::new();
    // Each run to do, with its stop at Δt when that is on record.
    let mut todo: Vec<(RunSpec, Option<Stop>)> = Vec::new();
    let mut failed = Vec::new();
    let running = !(opts.cost_only || opts.report_only);
    for s in specs {
        let key = s.key();
        if let Ok(e) = std::fs::read_to_string(runs_dir.join(format!("{key}.failed"))) {
            // A run that stopped (deterministic): not retried; delete the file to retry it. A stop
            // recorded before stops were classified is classified now from Δt/2 on.
            match recorded_stop(&s, proto, &e) {
                Some(stop) if running => todo.push((s, Some(stop))),
                _ => failed.push((key, e.trim().to_string())),
            }
            continue;
        }
        match read_json::<RunResult>(&runs_dir.join(format!("{key}.json"))) {
            Some(r) if r.spec == s && &r.protocol == proto => done.push(r),
            _ => todo.push((s, None)),
        }
    }
    if !running {
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
    todo.sort_by(|(a, _), (b, _)| a.gamma_hat.total_cmp(&b.gamma_hat).then(b.phi.total_cmp(&a.phi)));
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
                        let Some((s, recorded)) = todo.get(i) else { break };
                        // The grid coordinates, not the file key (which repeats the law and N).
                        let name = format!("phi={:.3} mu={} nu={} g={:.1e}", s.phi, s.mu, s.nu, s.gamma_hat);
                        progress.start(&name);
                        let r = pool.install(|| run_one_from(s, proto, recorded.clone()));
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
    let jamming = jamming_of(&opts.grid, &done);
    write_outputs(opts, &done, &failed, &surface, &phi_c, &jamming, &cost)?;
    Ok(Summary { ran, skipped, failed, results: done, surface, phi_c, jamming, cost })
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
            // A stop on record that the smaller steps ran through: the run's result replaces it.
            let _ = std::fs::remove_file(runs_dir.join(format!("{}.failed", s.key())));
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
        if opts.report_only {
            // Report only: what was measured before, nothing new.
            continue;
        }
        let spec = RunSpec {
            phi,
            mu,
            nu,
            gamma_hat,
            n,
            gamma_mc,
            mpr,
            restitution: g.restitution,
            seed: 7,
            eq2_fixed_point: g.eq2_fixed_point,
        };
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

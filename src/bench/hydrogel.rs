//! The 514-particle hydrogel compression (`liggghts_inputs/hydrogel.in`, the Debian example
//! `hydrogel_multicontact` with its three contact laws, no VTK output) run by every engine
//! available: stock LIGGGHTS (`hertz`, `surface multicontact`), the `mc_advanced` plugin, and the
//! Rust DEM (same three laws) with 1 and 2 threads. Each run is a child process; the rate comes
//! from the "Loop time" lines both engines print.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::{Options, Report, Row};
use crate::outputs::{loop_totals, read_ave_time};
use crate::physics::model_kind::{ModelKind, ModelLabel};

pub const SCENE: &str = "hydrogel_514";

pub(super) const EXAMPLE: &str =
    "/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public/hydrogel_multicontact";

/// (law variable, model name) as in `liggghts_inputs/select_law.inc`.
const LAWS: [(&str, ModelKind); 3] =
    [("1", ModelKind::Hertz), ("2", ModelKind::StandardMc), ("0", ModelKind::McAdvanced)];

pub(super) fn sibling(name: &str) -> Option<PathBuf> {
    let p = std::env::current_exe().ok()?.with_file_name(name);
    p.exists().then_some(p)
}

pub(super) fn on_path(name: &str) -> bool {
    Command::new(name).arg("-h").output().is_ok()
}

/// Whether `mpirun` can be started.
pub(super) fn mpirun_available() -> bool {
    Command::new("mpirun").arg("--version").output().is_ok_and(|o| o.status.success())
}

/// `exe` on two MPI ranks. The ranks yield when idle and are not pinned, so that a rank waiting in
/// a collective does not spin on the core the other one needs (2-core machines).
pub(super) fn on_two_ranks(exe: &Path) -> Command {
    let mut c = Command::new("mpirun");
    c.args(["--allow-run-as-root", "--oversubscribe", "--bind-to", "none", "-np", "2"]);
    c.env("OMPI_MCA_mpi_yield_when_idle", "1").arg(exe);
    c
}

/// Runs one deck; returns (seconds, particle-steps per second, piston force column of the deck's
/// `fix ave/time` file).
fn measure_force(cmd: &mut Command, what: &str) -> Result<(f64, f64, Vec<f64>), String> {
    let work = std::env::temp_dir().join(format!("mcdem-bench-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| e.to_string())?;
    let out = cmd.current_dir(&work).output().map_err(|e| format!("{what}: cannot start: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let table = read_ave_time(&work.join("piston_force.txt"));
    let _ = std::fs::remove_dir_all(&work);
    if !out.status.success() {
        let tail: Vec<&str> = text.lines().rev().take(5).collect();
        return Err(format!("{what} failed: {}", tail.join(" | ")));
    }
    let force = table?
        .iter()
        .map(|r| r.get(3).copied().ok_or_else(|| format!("{what}: piston_force.txt has no 4th column")))
        .collect::<Result<Vec<f64>, String>>()?;
    let lt = loop_totals(&text).ok_or_else(|| format!("{what}: no 'Loop time' line"))?;
    Ok((lt.seconds, lt.rate(), force))
}

/// Largest piston-force difference over the force range of `exact`.
fn force_error(exact: &[f64], other: &[f64]) -> f64 {
    let range =
        exact.iter().cloned().fold(f64::MIN, f64::max) - exact.iter().cloned().fold(f64::MAX, f64::min);
    if exact.len() != other.len() || range <= 0.0 {
        return f64::NAN;
    }
    exact.iter().zip(other).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / range
}

/// The approximate `mc_advanced` rows beside the exact one: (geometry tolerance as a fraction of
/// the radius, update interval in steps), docs/dem.md. Each runs in the Rust DEM (1 thread); the
/// ones marked also run in the plugin.
pub const APPROXIMATIONS: [(f64, u64, bool); 5] =
    [(1e-4, 1, false), (1e-3, 1, true), (0.0, 10, true), (1e-3, 5, false), (1e-3, 10, true)];

/// The approximation the cost target (`mc_advanced` ≤ 1.3× Hertz) is checked with, also the one
/// the plugin runs on two ranks: the fastest of [`APPROXIMATIONS`].
pub const TARGET_APPROXIMATION: (f64, u64) = (1e-3, 10);

/// Whether a round repeats the approximate row (tol, every).
fn in_round(round: usize, tol: f64, every: u64) -> bool {
    round == 0 || (tol, every) == TARGET_APPROXIMATION
}

/// The model name of an approximate row: `mc_advanced tol=1e-3`, `mc_advanced every=10`,
/// `mc_advanced tol=1e-3 every=5`.
pub fn approximate_model(tol: f64, every: u64) -> String {
    let mut m = ModelKind::McAdvanced.name().to_string();
    if tol > 0.0 {
        m += &format!(" tol={tol:e}");
    }
    if every > 1 {
        m += &format!(" every={every}");
    }
    m
}

/// The rows of one round (`round` from 0). The first runs every row; later rounds repeat the
/// rows the bench's targets read ([`TARGET_APPROXIMATION`], Hertz on one and two cores, exact
/// `mc_advanced` on one), so that their medians come from several moments of the machine's load
/// without re-running the slow stock `surface multicontact` row each time.
pub fn rows(
    opts: &Options,
    round: usize,
    report: &mut Report,
    say: &mut dyn FnMut(&str),
) -> Result<(), String> {
    let decks = Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs");
    if !decks.join("hydrogel.in").exists() || !Path::new(EXAMPLE).join("data/input.data").exists() {
        report.notes.push(format!(
            "hydrogel rows skipped: needs {} and the liggghts-doc example in {EXAMPLE}",
            decks.join("hydrogel.in").display()
        ));
        return Ok(());
    }
    let (stroke, strokes) = if opts.quick { ("1500", "2") } else { ("30000", "4") };
    let deck = decks.join("hydrogel.in");
    let vars = |law: &str| -> Vec<String> {
        ["-var", "law", law, "-var", "stroke", stroke, "-var", "strokes", strokes, "-var", "dir"]
            .iter()
            .map(|s| s.to_string())
            .chain([decks.display().to_string()])
            .collect()
    };
    report.notes.push(format!("hydrogel: {strokes} strokes of {stroke} steps (the example: 4 of 30000)"));

    // LIGGGHTS: the stock laws with the Debian `liggghts`, mc_advanced with the plugin executable.
    let plugin = sibling("mcdem-liggghts");
    let stock = if on_path("liggghts") { Some(PathBuf::from("liggghts")) } else { plugin.clone() };
    match (&stock, &plugin) {
        (None, None) => {
            report.notes.push("LIGGGHTS rows skipped: neither liggghts nor mcdem-liggghts found".into())
        }
        _ => {
            if plugin.is_none() {
                report
                    .notes
                    .push("LIGGGHTS mc_advanced row skipped: build mcdem-liggghts (feature liggghts)".into());
            }
            // A LIGGGHTS run's arguments: the law, and for the plugin an approximation (tol, every).
            let deck_args = |c: &mut Command, law: &str, approx: Option<(f64, u64)>| {
                c.arg("-in").arg(&deck).args(vars(law)).args(["-log", "none"]);
                if let Some((tol, every)) = approx {
                    c.args(["-var", "geomtol", &tol.to_string(), "-var", "mcevery", &every.to_string()]);
                }
            };
            let mut exact = Vec::new();
            for (law, model) in LAWS {
                let exe = if law == "0" { plugin.as_ref() } else { stock.as_ref() };
                let Some(exe) = exe else { continue };
                if model == ModelKind::StandardMc && round > 0 {
                    continue;
                }
                let mut c = Command::new(exe);
                deck_args(&mut c, law, None);
                let (t, rate, force) = measure_force(&mut c, &format!("liggghts {model}"))?;
                say(&format!("hydrogel, liggghts {model}: {rate:.3e} particle-steps/s"));
                push(report, "liggghts", model, 1, (t, rate));
                if law == "0" {
                    exact = force;
                }
            }
            // The plugin's approximate rows, each with its piston-force error against its exact run.
            for (tol, every, _) in APPROXIMATIONS.iter().filter(|a| a.2 && in_round(round, a.0, a.1)) {
                let Some(exe) = plugin.as_ref() else { break };
                let model = approximate_model(*tol, *every);
                let mut c = Command::new(exe);
                deck_args(&mut c, "0", Some((*tol, *every)));
                let run = measure_force(&mut c, &format!("liggghts {model}"))?;
                approximate_row(report, say, "liggghts", &model, 1, &exact, run);
            }
            // Both cores as MPI ranks: stock Hertz, and the plugin with the fastest approximation
            // (its piston-force error against the exact one-rank run: the decomposition reorders
            // sums, the approximation does the rest).
            if mpirun_available() {
                if let Some(exe) = &stock {
                    let mut c = on_two_ranks(exe);
                    deck_args(&mut c, "1", None);
                    let (t, rate, _) = measure_force(&mut c, "liggghts hertz, 2 ranks")?;
                    say(&format!("hydrogel, liggghts hertz, 2 ranks: {rate:.3e} particle-steps/s"));
                    push(report, "liggghts", ModelKind::Hertz, 2, (t, rate));
                }
                if let (Some(exe), 0) = (&plugin, round) {
                    let (tol, every) = TARGET_APPROXIMATION;
                    let model = approximate_model(tol, every);
                    let mut c = on_two_ranks(exe);
                    deck_args(&mut c, "0", Some((tol, every)));
                    let run = measure_force(&mut c, &format!("liggghts {model}, 2 ranks"))?;
                    approximate_row(report, say, "liggghts", &model, 2, &exact, run);
                }
            } else {
                report.notes.push("hydrogel: mpirun not found, LIGGGHTS on one rank only".into());
            }
        }
    }
    // Rust DEM, 1 and 2 threads; `mc_advanced` also approximate (1 thread), each with its
    // piston-force error against the exact run.
    let me = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut exact = Vec::new();
    let rust = |law: &str, threads: usize, (tol, every): (f64, u64), model: &str| {
        let mut c = Command::new(&me);
        c.arg("run").arg(&deck).args(vars(law)).args(["-log", "none", "--no-progress"]);
        c.arg(format!("--mc-geometry-tolerance={tol}"));
        c.arg(format!("--mc-update-every={every}"));
        c.env("RAYON_NUM_THREADS", threads.to_string());
        measure_force(&mut c, &format!("mcdem run {model}"))
    };
    for (law, model) in LAWS {
        for threads in [1usize, 2] {
            if round > 0
                && (model == ModelKind::StandardMc || (model == ModelKind::McAdvanced && threads == 2))
            {
                continue;
            }
            let (t, rate, force) = rust(law, threads, (0.0, 1), model.name())?;
            say(&format!("hydrogel, rust {model}, {threads} thread(s): {rate:.3e} particle-steps/s"));
            push(report, "rust", model, threads, (t, rate));
            if law == "0" && threads == 1 {
                exact = force;
            }
        }
    }
    for (tol, every, _) in APPROXIMATIONS.into_iter().filter(|a| in_round(round, a.0, a.1)) {
        let model = approximate_model(tol, every);
        let run = rust("0", 1, (tol, every), &model)?;
        approximate_row(report, say, "rust", &model, 1, &exact, run);
    }
    Ok(())
}

/// One row of this scene.
fn push(
    report: &mut Report,
    engine: &'static str,
    model: impl Into<ModelLabel>,
    threads: usize,
    (secs, rate): (f64, f64),
) {
    report.rows.push(Row {
        engine,
        model: model.into(),
        scene: SCENE.into(),
        n: 514,
        threads,
        particle_steps_per_s: rate,
        wall_time_s: secs,
        memory_bytes_per_particle: None,
        rounds_particle_steps_per_s: Vec::new(),
    })
}

/// An approximate `mc_advanced` row on `threads` threads or ranks, with its piston-force error
/// against the same engine's exact run on one, `exact`.
fn approximate_row(
    report: &mut Report,
    say: &mut dyn FnMut(&str),
    engine: &'static str,
    model: &str,
    threads: usize,
    exact: &[f64],
    (t, rate, force): (f64, f64, Vec<f64>),
) {
    let err = force_error(exact, &force);
    let cores = if threads > 1 { format!(", {threads} cores") } else { String::new() };
    say(&format!(
        "hydrogel, {engine} {model}{cores}: {rate:.3e} particle-steps/s, piston force error {err:.2e} of its range"
    ));
    push(report, engine, model, threads, (t, rate));
    report
        .errors
        .insert(format!("hydrogel {engine} {model}{cores}: max piston-force error / range vs exact"), err);
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_target_approximation_runs_in_both_engines() {
        let (tol, every) = super::TARGET_APPROXIMATION;
        assert!(super::APPROXIMATIONS.contains(&(tol, every, true)));
    }
}

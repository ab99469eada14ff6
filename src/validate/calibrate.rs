//! `mcdem calibrate` (paper Fig. 5): per Poisson ratio ν, the advanced-MC parameters γ and MPR (and
//! the Young's modulus E where ν > 0.3, as the paper does) that minimise the NRMSE of the piston
//! stress against the nonlocal reference on the 514-particle second compression.
//!
//! Objective: one DEM compression from the common start state of the `uniaxial` case (the packing
//! after one Hertz cycle), NRMSE over φ ≥ 0.66 against the nonlocal solution from the same state.
//! Search: golden-section line searches, one parameter at a time (γ, then MPR, then E); an
//! unstable run counts as an infinite error. The search is coarse on purpose (a few tens of DEM
//! runs per ν); the report gives the number of evaluations and the best value found, not a claim
//! of a global minimum.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::uniaxial::{self, Setup};
use crate::harness::calibration::{Law, E_HYDROGEL};
use crate::harness::progress::Progress;
use crate::nonlocal::KernelKind;

#[derive(Debug, Clone)]
pub struct Options {
    pub quick: bool,
    pub nus: Vec<f64>,
    pub out: PathBuf,
}

/// The calibrated parameters of one ν.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Fit {
    pub nu: f64,
    pub gamma: f64,
    pub mpr: f64,
    pub youngs_modulus_pa: f64,
    pub nrmse: f64,
    pub hertz_nrmse: f64,
    pub evaluations: usize,
    pub wall_time_s: f64,
}

/// Golden-section search for the minimum of `f` on [a, b] with `iters` interval reductions.
pub(crate) fn golden(mut a: f64, mut b: f64, iters: usize, f: &mut dyn FnMut(f64) -> f64) -> (f64, f64) {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (b - r * (b - a), a + r * (b - a));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iters {
        if f1 <= f2 {
            b = x2;
            (x2, f2) = (x1, f1);
            x1 = b - r * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            (x1, f1) = (x2, f2);
            x2 = a + r * (b - a);
            f2 = f(x2);
        }
    }
    if f1 <= f2 {
        (x1, f1)
    } else {
        (x2, f2)
    }
}

fn calibrate_one(
    nu: f64,
    s: &Setup,
    kind: KernelKind,
    dir: &Path,
    say: &(dyn Fn(&str) + Sync),
    note: &dyn Fn(&str, Option<f64>),
) -> Result<Fit, String> {
    let t = Instant::now();
    note("start state", None);
    let (dump, data) = uniaxial::start_state(nu, s, dir)?;
    note("nonlocal reference", None);
    let (refc, ref_secs) = uniaxial::reference(&dump, nu, kind, s.nonlocal_steps, &mut |_| {})?;
    say(&format!("ν = {nu}: nonlocal reference ({}) in {ref_secs:.1} s", kind.name()));
    note("hertz", None);
    let (hc, _) = uniaxial::compress(Law::HERTZ, nu, s, &data)?;
    let hertz_nrmse = uniaxial::error(&hc, &refc);
    let mut evals = 0;
    let (gi, mi, ei) = if s.stroke < 30000 { (4, 3, 3) } else { (8, 6, 6) };
    // An unstable run (the engine stopped on an instability) counts as an infinite error; any
    // other failure (a deck or file problem) ends the calibration, so that it cannot pass for a
    // search result.
    let mut failure: Option<String> = None;
    // Evaluations of the three line searches (two starting points, then one per reduction).
    let planned = gi + mi + 4 + if nu > 0.3 + 1e-9 { ei + 2 } else { 0 };
    let mut eval = |gamma: f64, mpr: f64, e: f64| -> f64 {
        evals += 1;
        if failure.is_some() {
            return f64::INFINITY;
        }
        // The evaluations done of those planned: the pace of this ν's estimate.
        note(&format!("eval {evals}/{planned}"), Some((evals - 1) as f64 / planned as f64));
        let err = match objective(Law { youngs_modulus: e, ..Law::advanced(gamma, mpr) }, nu, s, &data, &refc)
        {
            Ok(err) => err,
            Err(f) if f.instability.is_some() => f64::INFINITY,
            Err(f) => {
                failure = Some(f.message);
                f64::INFINITY
            }
        };
        say(&format!(
            "ν = {nu}: eval {evals}: γ = {gamma:.4} MPR = {mpr:.4} E = {e:.4e} Pa → NRMSE {:.3} %",
            100.0 * err
        ));
        if err.is_finite() {
            err
        } else {
            f64::INFINITY
        }
    };
    let mut mpr = 0.08;
    let (gamma, _) = golden(0.2, 2.0, gi, &mut |g| eval(g, mpr, E_HYDROGEL));
    let (m, mut best) = golden(0.02, 0.2, mi, &mut |m| eval(gamma, m, E_HYDROGEL));
    mpr = m;
    let mut e = E_HYDROGEL;
    if nu > 0.3 + 1e-9 {
        let (ef, be) = golden(0.5, 1.5, ei, &mut |f| eval(gamma, mpr, f * E_HYDROGEL));
        if be < best {
            e = ef * E_HYDROGEL;
            best = be;
        }
    }
    if let Some(m) = failure {
        return Err(format!("ν = {nu}: a calibration run failed (not an instability): {m}"));
    }
    Ok(Fit {
        nu,
        gamma,
        mpr,
        youngs_modulus_pa: e,
        nrmse: best,
        hertz_nrmse,
        evaluations: evals,
        wall_time_s: t.elapsed().as_secs_f64(),
    })
}

/// The calibration's objective: NRMSE of `law`'s compression from the start state `data` against
/// the nonlocal curve `reference` (both from [`uniaxial::start_state`] and [`uniaxial::reference`]).
pub fn objective(
    law: Law,
    nu: f64,
    s: &Setup,
    data: &Path,
    reference: &uniaxial::Curve,
) -> Result<f64, crate::deck::DeckFailure> {
    uniaxial::compress(law, nu, s, data).map(|(c, _)| uniaxial::error(&c, reference))
}

/// Least-squares line y = a + b x.
fn line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let (sx, sy) = points.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| (my - sxy / sxx * mx, sxy / sxx))
}

/// Runs the calibration for every ν (two at a time, one per core) and writes
/// `calibration.csv`, `calibration.json`, `calibration.md` and `calibration.png` into `opts.out`.
pub fn run(opts: &Options) -> Result<Vec<Fit>, String> {
    let mut s = uniaxial::setup(opts.quick);
    if !opts.nus.is_empty() {
        s.nus = opts.nus.clone();
    } else if opts.quick {
        s.nus = vec![0.5];
    }
    for &nu in &s.nus {
        if !(0.0..=0.5).contains(&nu) {
            return Err(format!("Poisson ratio {nu} outside [0, 0.5]"));
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| format!("cannot create {}: {e}", opts.out.display()))?;
    let kind = s.kernel;
    let scratch = crate::harness::runner::Scratch::new()?;
    let scratch = &scratch.0;
    let t = Instant::now();
    let journal =
        opts.out.join(if opts.quick { "calibration_done_quick.jsonl" } else { "calibration_done.jsonl" });
    // One progress item per ν; a ν found in the journal counts as done.
    let progress = Progress::new("calibrate", s.nus.len());
    let say = |l: &str| progress.println(l);
    progress.skip(journal_fits(&s.nus, &journal, &say)?.len());
    let fit = |nu: f64| {
        let name = format!("nu={nu}");
        progress.start(&name);
        let note = |what: &str, fraction: Option<f64>| {
            progress.detail(&name, "eval", what.to_string());
            if let Some(f) = fraction {
                progress.fraction(&name, f);
            }
        };
        let r = calibrate_one(nu, &s, kind, &scratch.join(format!("nu{nu}")), &say, &note);
        progress.finish(&name);
        r
    };
    let fits = fit_resumable(&s.nus, &journal, &fit, &say);
    drop(progress);
    let fits = fits?;
    write_outputs(opts, &s, kind, &fits, t.elapsed().as_secs_f64())?;
    Ok(fits)
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

/// The fits of `journal` (one JSON line each) whose ν is one of `nus`; no journal is no fit.
///
/// A line that is not a fit is an error naming the file and line: silently refitting would hide
/// a damaged journal and cost hours. The one exception is a last line without its newline, the
/// trace of a run killed while appending: it is cut from the file (so the next append starts on
/// a fresh line) and that ν is fitted again.
fn journal_fits(nus: &[f64], journal: &Path, say: &dyn Fn(&str)) -> Result<Vec<Fit>, String> {
    let text = match std::fs::read_to_string(journal) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(format!("cannot read {}: {e}", journal.display())),
    };
    let whole = text.rfind('\n').map_or(0, |i| i + 1);
    let torn = whole < text.len() && serde_json::from_str::<Fit>(&text[whole..]).is_err();
    if torn {
        say(&format!(
            "{}:{}: an unfinished last line (a run stopped while writing it) is dropped",
            journal.display(),
            text[..whole].lines().count() + 1
        ));
        std::fs::write(journal, &text[..whole])
            .map_err(|e| format!("cannot write {}: {e}", journal.display()))?;
    }
    let kept = if torn { &text[..whole] } else { &text[..] };
    let mut fits = Vec::new();
    for (i, l) in kept.lines().enumerate() {
        if l.trim().is_empty() {
            continue;
        }
        let f: Fit = serde_json::from_str(l).map_err(|e| {
            format!(
                "{}:{}: not a calibration fit ({e}); remove the line to fit that ν again",
                journal.display(),
                i + 1
            )
        })?;
        if nus.iter().any(|&nu| same(nu, f.nu)) {
            fits.push(f);
        }
    }
    Ok(fits)
}

/// The resumable loop of [`run`]: fits every ν of `nus` with `fit` (two at a time, one per core)
/// and returns the fits sorted by ν. Every finished ν is appended to `journal` (one JSON line), and
/// a ν found there is taken from it instead of being fitted again, so a run stopped part way and
/// started again with the same mode finishes with the fits of an uninterrupted run.
pub fn fit_resumable(
    nus: &[f64],
    journal: &Path,
    fit: &(dyn Fn(f64) -> Result<Fit, String> + Sync),
    say: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Fit>, String> {
    let done = journal_fits(nus, journal, say)?;
    for f in &done {
        say(&format!(
            "ν = {}: taken from {} (γ = {:.4}, MPR = {:.4})",
            f.nu,
            journal.display(),
            f.gamma,
            f.mpr
        ));
    }
    let todo: Vec<f64> = nus.iter().copied().filter(|&nu| !done.iter().any(|f| same(f.nu, nu))).collect();
    let append = Mutex::new(());
    let fits: Vec<Result<Fit, String>> = todo
        .par_iter()
        .map(|&nu| {
            let fit = fit(nu)?;
            let _g = append.lock();
            let line = serde_json::to_string(&fit).map_err(|e| e.to_string())? + "\n";
            use std::io::Write;
            std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(journal)
                .and_then(|mut f| f.write_all(line.as_bytes()))
                .map_err(|e| format!("cannot write {}: {e}", journal.display()))?;
            Ok(fit)
        })
        .collect();
    let mut fits: Vec<Fit> = fits.into_iter().collect::<Result<_, _>>()?;
    fits.extend(done);
    fits.sort_by(|a, b| a.nu.total_cmp(&b.nu));
    Ok(fits)
}

fn write_outputs(
    opts: &Options,
    s: &Setup,
    kind: KernelKind,
    fits: &[Fit],
    total: f64,
) -> Result<(), String> {
    let io = |p: &Path, e: std::io::Error| format!("cannot write {}: {e}", p.display());
    let mut csv = String::from("nu,gamma,mpr,youngs_modulus_pa,nrmse,hertz_nrmse,evaluations,wall_time_s\n");
    for f in fits {
        let _ = writeln!(
            csv,
            "{},{:.5},{:.5},{:.6e},{:.6e},{:.6e},{},{:.1}",
            f.nu, f.gamma, f.mpr, f.youngs_modulus_pa, f.nrmse, f.hertz_nrmse, f.evaluations, f.wall_time_s
        );
    }
    let p = opts.out.join("calibration.csv");
    std::fs::write(&p, csv).map_err(|e| io(&p, e))?;
    let p = opts.out.join("calibration.json");
    let json = serde_json::json!({"kernel": kind.name(), "quick": opts.quick, "stroke": s.stroke, "total_wall_time_s": total, "fits": fits});
    std::fs::write(&p, serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?)
        .map_err(|e| io(&p, e))?;
    let gl = line(&fits.iter().map(|f| (f.nu, f.gamma)).collect::<Vec<_>>());
    let el = line(&fits.iter().map(|f| (f.nu, f.youngs_modulus_pa)).collect::<Vec<_>>());
    let (mlo, mhi) =
        fits.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, f| (a.0.min(f.mpr), a.1.max(f.mpr)));
    let mut md = format!(
        "# Calibration of advanced MC against the nonlocal reference (kernel `{}`)\n\n{} piston speed ({} steps per example stroke), \
         wall time of this invocation {total:.0} s (each ν's own fit time is in the table; ν taken from the journal were fitted earlier).\n\n| ν | γ | MPR | E [Pa] | NRMSE | Hertz NRMSE | evaluations | time [s] |\n|---|---|---|---|---|---|---|---|\n",
        kind.name(),
        if opts.quick { "Quick run, 4×" } else { "Full run, the paper's" },
        s.stroke
    );
    for f in fits {
        let _ = writeln!(
            md,
            "| {} | {:.3} | {:.3} | {:.4e} | {:.2} % | {:.2} % | {} | {:.0} |",
            f.nu,
            f.gamma,
            f.mpr,
            f.youngs_modulus_pa,
            100.0 * f.nrmse,
            100.0 * f.hertz_nrmse,
            f.evaluations,
            f.wall_time_s
        );
    }
    let _ = writeln!(md, "\n| statement of the paper (Sect. 3, Fig. 5) | mcdem |\n|---|---|");
    let _ = writeln!(
        md,
        "| γ decreases linearly with ν | {} |",
        gl.map(|(a, b)| format!(
            "γ(ν) = {a:.3} {} {:.3} ν ({})",
            if b < 0.0 { "−" } else { "+" },
            b.abs(),
            if b < 0.0 { "decreasing" } else { "NOT decreasing" }
        ))
        .unwrap_or_else(|| "one ν only: no line".into())
    );
    let _ = writeln!(md, "| MPR in 0.07–0.09 | MPR in {mlo:.3}–{mhi:.3} |");
    let _ = writeln!(
        md,
        "| E adjusted for ν > 0.3 | {} |",
        el.map(|(a, b)| format!("E(ν) = {a:.4e} {} {:.4e} ν Pa", if b < 0.0 { "−" } else { "+" }, b.abs()))
            .unwrap_or_else(|| "one ν only: no line".into())
    );
    let series = vec![
        crate::harness::plot::Series {
            label: "γ".into(),
            points: fits.iter().map(|f| (f.nu, f.gamma)).collect(),
            markers: true,
            thin: false,
        },
        crate::harness::plot::Series {
            label: "E / 23.3 kPa".into(),
            points: fits.iter().map(|f| (f.nu, f.youngs_modulus_pa / E_HYDROGEL)).collect(),
            markers: true,
            thin: false,
        },
        crate::harness::plot::Series {
            label: "MPR × 10".into(),
            points: fits.iter().map(|f| (f.nu, 10.0 * f.mpr)).collect(),
            markers: true,
            thin: false,
        },
    ];
    crate::harness::plot::draw(
        &opts.out.join("calibration.png"),
        &crate::harness::plot::Chart {
            title: "Calibrated advanced-MC parameters (Fig. 5 analogue)",
            x_label: "Poisson ratio ν",
            y_label: "value",
            log_x: false,
            log_y: false,
            series,
        },
    )?;
    let _ = writeln!(md, "\n![calibrated parameters](calibration.png)");
    let p = opts.out.join("calibration.md");
    std::fs::write(&p, md).map_err(|e| io(&p, e))
}

#[cfg(test)]
mod tests {
    #[test]
    fn golden_section_finds_a_parabola_minimum() {
        let mut n = 0;
        let (x, fx) = super::golden(0.0, 4.0, 30, &mut |x| {
            n += 1;
            (x - 1.3).powi(2) + 2.0
        });
        assert!((x - 1.3).abs() < 1e-4 && (fx - 2.0).abs() < 1e-8, "{x} {fx}");
        assert_eq!(n, 32);
    }

    #[test]
    fn least_squares_line() {
        let (a, b) = super::line(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]).unwrap();
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
        assert!(super::line(&[(0.5, 1.0)]).is_none());
    }
}

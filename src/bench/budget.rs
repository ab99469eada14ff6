//! The accuracy budget's speed–error front (`mcdem bench --scene budget`; docs/bench.md,
//! "Accuracy budget: the speed–error front"). On each scene ([`budget_scenes::SCENES`]) the same
//! run under Hertz, exact `mc_advanced`, `mcAccuracy` 1e-2, 1e-3, 1e-4 and the fixed settings
//! `geometryTolerance 1e-3 updateEvery 10` and `geometryTolerance 1e-4`: cost against Hertz
//! (CPU time, one thread, settings interleaved round by round), error of the scene's force measure
//! against the exact run, and for the budget the shadow check's measured radius-change error next
//! to its bound. One PNG per scene.

use std::path::Path;

use serde::Serialize;

use super::budget_scenes::{self as scenes, Outcome, Setting};
use super::{median, Options, Report, Target};
use crate::harness::plot::{draw, Chart, Series};

/// The budgets measured.
pub const EPS: [f64; 3] = [1e-2, 1e-3, 1e-4];

/// The fixed settings of today beside them: (geometry tolerance, update interval).
pub const FIXED: [(f64, u64); 2] = [(1e-3, 10), (1e-4, 1)];

/// A budget "matches" a fixed setting when its cost is at most this factor of the fixed
/// setting's: cost ratios formed within one round still move by several per cent between rounds
/// on the shared machine (docs/bench.md, "Why ratios"), so a smaller difference is not resolved.
pub const MATCH: f64 = 1.1;

/// One setting on one scene.
#[derive(Debug, Clone, Serialize)]
pub struct FrontRow {
    pub setting: String,
    /// The budget's EPS (budget rows only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eps: Option<f64>,
    /// Median CPU time of the measured steps over the rounds [s] (None: run once, untimed).
    pub cpu_s: Option<f64>,
    /// Median over the rounds of the per-round cost ratio to Hertz, with its range.
    pub cost_vs_hertz: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cost_range: Option<[f64; 2]>,
    /// Error of the force measure against the exact run (None for Hertz, another law).
    pub error: Option<f64>,
    /// Fraction of the particle-steps with two or more contacts recomputed (budget rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub recomputed: Option<f64>,
    /// Shadow check: largest measured radius-change error and largest bound, both relative to
    /// the particle's scale (budget rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measured: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bound: Option<f64>,
    /// measured ≤ bound ≤ EPS (the run stops anyway if a particle's error exceeds its bound).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bound_held: Option<bool>,
    /// Share of the budget's exact evaluations by reason (docs/dem.md, "Accuracy budget").
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub exact_by_reason: Vec<(String, f64)>,
    /// Cost over that of the cheapest fixed setting whose error is at least this row's (budget
    /// rows; None when every fixed setting is more accurate).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vs_best_fixed: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub best_fixed: Option<String>,
    /// Cost over that of the cheapest fixed setting whose error is at most this row's (budget
    /// rows; above [`MATCH`] the budget is dominated: a fixed setting is as accurate and cheaper).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vs_accurate_fixed: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accurate_fixed: Option<String>,
}

/// One scene's front.
#[derive(Debug, Clone, Serialize)]
pub struct Front {
    pub scene: String,
    /// The force measure the errors are of.
    pub measure: String,
    pub n: usize,
    pub steps: u64,
    pub rounds: usize,
    pub rows: Vec<FrontRow>,
    /// The PNG of the front, when it was written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub png: Option<String>,
}

/// The settings of a scene, in run order (the hydrogel deck runs as a child process, which cannot
/// move one particle: no chaos-floor row there).
fn settings(scene: &str) -> Vec<Setting> {
    let mut s = vec![Setting::Hertz, Setting::Exact];
    if scene != "hydrogel" {
        s.push(Setting::Perturbed);
    }
    s.extend(EPS.iter().map(|&e| Setting::Budget(e)));
    s.extend(FIXED.iter().map(|&(t, k)| Setting::Fixed(t, k)));
    s
}

/// Largest |other − exact| over the range (hydrogel: max − min; elsewhere the largest |value|)
/// of `exact`; NaN when the series differ in length or `exact` is flat at zero.
pub fn error(scene: &str, exact: &[f64], other: &[f64]) -> f64 {
    let hi = exact.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lo = exact.iter().copied().fold(f64::INFINITY, f64::min);
    let scale = if scene == "hydrogel" { hi - lo } else { hi.abs().max(lo.abs()) };
    if exact.len() != other.len() || scale.is_nan() || scale <= 0.0 {
        return f64::NAN;
    }
    exact.iter().zip(other).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / scale
}

/// Runs the group: every scene, every setting, `opts.rounds` timed rounds (settings interleaved
/// within a round), then one untimed shadow-checked run per budget and the chaos-floor run.
pub fn rows(opts: &Options, report: &mut Report, say: &mut dyn FnMut(&str)) -> Result<(), String> {
    let hydrogel_ok = Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs/hydrogel.in").exists()
        && Path::new(super::hydrogel::EXAMPLE).join("data/input.data").exists();
    for scene in scenes::SCENES {
        if scene == "hydrogel" && !hydrogel_ok {
            report.notes.push(format!(
                "budget: hydrogel front skipped (needs the liggghts-doc example in {})",
                super::hydrogel::EXAMPLE
            ));
            continue;
        }
        let front = front(opts, scene, say)?;
        report.budget.push(front);
    }
    report.notes.push(format!(
        "budget: cost = CPU time of the measured steps on one thread (in process: the thread's, hydrogel: the child's), {} interleaved round(s); errors against the exact run of the same scene; shadow check every {} steps in a separate untimed run",
        opts.rounds.max(1),
        scenes::CHECK_EVERY
    ));
    Ok(())
}

fn front(opts: &Options, scene: &str, say: &mut dyn FnMut(&str)) -> Result<Front, String> {
    let list = settings(scene);
    let (n, steps, _) = scenes::size(scene, opts.quick);
    let rounds = opts.rounds.max(1);
    // cpu[k][r]; first[k]: round 0's outcome (samples, recomputed).
    let mut cpu: Vec<Vec<f64>> = vec![Vec::new(); list.len()];
    let mut first: Vec<Option<Outcome>> = vec![None; list.len()];
    for r in 0..rounds {
        for (k, s) in list.iter().enumerate() {
            if *s == Setting::Perturbed && r > 0 {
                continue;
            }
            let o = scenes::run(scene, opts.quick, *s, false)?;
            if *s != Setting::Perturbed {
                cpu[k].push(o.cpu_s);
            }
            say(&format!("budget {scene}, {}: {:.2} s CPU (round {})", s.label(), o.cpu_s, r + 1));
            if r == 0 {
                first[k] = Some(o);
            }
        }
    }
    let hertz = cpu[0].clone();
    let exact = first[1].as_ref().map(|o| o.samples.clone()).unwrap_or_default();
    let mut rows = Vec::with_capacity(list.len());
    for (k, s) in list.iter().enumerate() {
        let o = first[k].take().unwrap_or_default();
        let mut ratios: Vec<f64> = cpu[k].iter().zip(&hertz).map(|(a, h)| a / h).collect();
        let cost_range = (ratios.len() > 1).then(|| {
            [
                ratios.iter().copied().fold(f64::INFINITY, f64::min),
                ratios.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ]
        });
        let mut row = FrontRow {
            setting: s.label(),
            eps: None,
            cpu_s: (!cpu[k].is_empty()).then(|| median(&mut cpu[k].clone())),
            cost_vs_hertz: (!ratios.is_empty()).then(|| median(&mut ratios)),
            cost_range,
            error: (*s != Setting::Hertz).then(|| error(scene, &exact, &o.samples)),
            recomputed: o.recomputed,
            exact_by_reason: o.why.clone(),
            measured: None,
            bound: None,
            bound_held: None,
            vs_best_fixed: None,
            best_fixed: None,
            vs_accurate_fixed: None,
            accurate_fixed: None,
        };
        if let Setting::Budget(eps) = *s {
            row.eps = Some(eps);
            let c = scenes::run(scene, opts.quick, *s, true)?;
            if let Some((m, b)) = c.checked {
                row.measured = Some(m);
                row.bound = Some(b);
                // The bound is EPS × scale or less by construction; 1e-9 of it for its rounding.
                row.bound_held = Some(m <= b && b <= eps * (1.0 + 1e-9));
            }
            let (same, timed) = (error(scene, &exact, &c.samples), row.error.unwrap_or(f64::NAN));
            if same.to_bits() != timed.to_bits() {
                return Err(format!(
                    "budget {scene}, {}: the shadow-checked run's force measure differs from the timed run's ({same:e} against {:e}): the check must not touch the forces",
                    s.label(),
                    timed
                ));
            }
        }
        rows.push(row);
    }
    compare_with_fixed(&mut rows);
    for r in &rows {
        say(&format!("budget {scene}: {}", line(r)));
    }
    let mut f = Front {
        scene: scene.into(),
        measure: scenes::measure(scene).into(),
        n,
        steps,
        rounds,
        rows,
        png: None,
    };
    std::fs::create_dir_all(&opts.plots).map_err(|e| format!("--plots {}: {e}", opts.plots.display()))?;
    let png = opts.plots.join(format!("budget_{scene}.png"));
    plot(&f, &png)?;
    f.png = Some(png.display().to_string());
    Ok(f)
}

/// For each budget row: the cheapest fixed setting whose error is at least the row's (the issue's
/// comparison: the budget should cost no more than a fixed setting that is no more accurate), and
/// the cheapest whose error is at most the row's (a fixed setting as accurate and cheaper
/// dominates the budget), with the row's cost over each.
fn compare_with_fixed(rows: &mut [FrontRow]) {
    let fixed: Vec<(String, f64, f64)> = rows
        .iter()
        .filter(|r| r.setting.starts_with("geometryTolerance"))
        .filter_map(|r| Some((r.setting.clone(), r.error?, r.cost_vs_hertz?)))
        .collect();
    let cheapest = |keep: &dyn Fn(f64) -> bool| {
        fixed.iter().filter(|f| keep(f.1)).min_by(|a, b| a.2.total_cmp(&b.2)).cloned()
    };
    for r in rows.iter_mut().filter(|r| r.eps.is_some()) {
        let (Some(e), Some(c)) = (r.error, r.cost_vs_hertz) else { continue };
        if let Some((name, _, fc)) = cheapest(&|fe| fe >= e) {
            r.vs_best_fixed = Some(c / fc);
            r.best_fixed = Some(name);
        }
        if let Some((name, _, fc)) = cheapest(&|fe| fe <= e) {
            r.vs_accurate_fixed = Some(c / fc);
            r.accurate_fixed = Some(name);
        }
    }
}

/// "1.23x NAME (beats|matches|slower)".
fn versus(v: Option<f64>, name: &Option<String>) -> Option<String> {
    let (v, name) = (v?, name.as_ref()?);
    let word = if v < 1.0 / MATCH {
        "beats"
    } else if v <= MATCH {
        "matches"
    } else {
        "slower"
    };
    Some(format!("{v:.2}x {name} ({word})"))
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map_or_else(|| "-".into(), f)
}

/// One row as text.
fn line(r: &FrontRow) -> String {
    let budget = r.eps.is_some();
    let worse = versus(r.vs_best_fixed, &r.best_fixed).unwrap_or_else(|| {
        if budget {
            "none".into()
        } else {
            "-".into()
        }
    });
    let better = versus(r.vs_accurate_fixed, &r.accurate_fixed).unwrap_or_else(|| {
        if budget {
            "none".into()
        } else {
            "-".into()
        }
    });
    format!(
        "{:<40} {:>7} {:>14} {:>10} {:>8} {:>21} {:>5}  vs >= error: {worse}; vs <= error: {better}",
        r.setting,
        opt(r.cost_vs_hertz, |v| format!("{v:.2}")),
        r.cost_range.map_or("-".into(), |[a, b]| format!("[{a:.2}, {b:.2}]")),
        opt(r.error, |v| format!("{v:.2e}")),
        opt(r.recomputed, |v| format!("{:.1} %", 100.0 * v)),
        match (r.measured, r.bound) {
            (Some(m), Some(b)) => format!("{m:.2e} / {b:.2e}"),
            _ => "-".into(),
        },
        r.bound_held.map_or("-", |h| if h { "yes" } else { "NO" }),
    )
}

/// The fronts as text: one table per scene.
pub fn table(fronts: &[Front]) -> String {
    let mut s = String::new();
    for f in fronts {
        s.push_str(&format!(
            "\naccuracy budget front, {} (N = {}, {} steps, {} round(s)); error: {}\n",
            f.scene, f.n, f.steps, f.rounds, f.measure
        ));
        s.push_str(&format!(
            "  {:<40} {:>7} {:>14} {:>10} {:>8} {:>21} {:>5}  {}\n",
            "setting",
            "cost",
            "[min, max]",
            "error",
            "recomp.",
            "measured / bound",
            "held",
            "cost over the cheapest fixed setting of >= / <= error"
        ));
        for r in &f.rows {
            s.push_str(&format!("  {}\n", line(r)));
        }
        for r in f.rows.iter().filter(|r| !r.exact_by_reason.is_empty()) {
            let parts: Vec<String> =
                r.exact_by_reason.iter().map(|(k, v)| format!("{k} {:.1} %", 100.0 * v)).collect();
            s.push_str(&format!("  {}: exact evaluations by reason: {}\n", r.setting, parts.join(", ")));
        }
        if let Some(p) = &f.png {
            s.push_str(&format!("  plot: {p}\n"));
        }
    }
    s
}

/// The front's targets: the bound held, and the budget costs at most [`MATCH`] × the cheapest
/// fixed setting of equal or larger error.
pub fn targets(fronts: &[Front], t: &mut Vec<Target>) {
    for f in fronts {
        for r in f.rows.iter().filter(|r| r.eps.is_some()) {
            let name = |what: &str| format!("budget {} {}: {what}", f.scene, r.setting);
            if let (Some(m), Some(b), Some(held)) = (r.measured, r.bound, r.bound_held) {
                let value = if b > 0.0 { m / b } else { 0.0 };
                t.push(Target {
                    name: name("measured / bound (radius changes)"),
                    value,
                    relation: "<=",
                    bound: 1.0,
                    met: held,
                });
            }
            for (v, fixed, what) in [
                (r.vs_best_fixed, &r.best_fixed, "no more accurate"),
                (r.vs_accurate_fixed, &r.accurate_fixed, "as accurate"),
            ] {
                if let (Some(v), Some(fixed)) = (v, fixed) {
                    t.push(Target {
                        name: name(&format!("cost / {fixed} ({what})")),
                        value: v,
                        relation: "<=",
                        bound: MATCH,
                        met: v <= MATCH,
                    });
                }
            }
        }
    }
}

/// The front as a PNG: cost against Hertz over the error, log-scaled; the budget's points joined
/// in EPS order, each fixed setting a marker, exact and Hertz as horizontal lines, the chaos floor
/// as a vertical one.
fn plot(f: &Front, path: &Path) -> Result<(), String> {
    let pts = |pred: &dyn Fn(&FrontRow) -> bool| -> Vec<(f64, f64)> {
        f.rows.iter().filter(|r| pred(r)).filter_map(|r| Some((r.error?, r.cost_vs_hertz?))).collect()
    };
    let budget = pts(&|r| r.eps.is_some());
    let errors: Vec<f64> = f.rows.iter().filter_map(|r| r.error).filter(|e| *e > 0.0).collect();
    let lo = errors.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = errors.iter().copied().fold(0.0f64, f64::max);
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (1e-6, 1.0) };
    let mut series = vec![
        Series {
            label: "mcAccuracy 1e-2, 1e-3, 1e-4".into(),
            points: budget.clone(),
            markers: false,
            thin: false,
        },
        Series { label: String::new(), points: budget, markers: true, thin: false },
    ];
    for r in f.rows.iter().filter(|r| r.setting.starts_with("geometryTolerance")) {
        if let (Some(e), Some(c)) = (r.error, r.cost_vs_hertz) {
            series.push(Series {
                label: r.setting.clone(),
                points: vec![(e, c)],
                markers: true,
                thin: false,
            });
        }
    }
    let level = |name: &str| f.rows.iter().find(|r| r.setting == name).and_then(|r| r.cost_vs_hertz);
    if let Some(c) = level("exact") {
        series.push(Series {
            label: format!("exact (error 0), cost {c:.2}"),
            points: vec![(lo, c), (hi, c)],
            markers: false,
            thin: true,
        });
    }
    series.push(Series {
        label: "hertz".into(),
        points: vec![(lo, 1.0), (hi, 1.0)],
        markers: false,
        thin: true,
    });
    if let Some(e) = f.rows.iter().find(|r| r.setting.starts_with("exact,")).and_then(|r| r.error) {
        let top = f.rows.iter().filter_map(|r| r.cost_vs_hertz).fold(1.0f64, f64::max);
        series.push(Series {
            label: "exact with 1e-12 d moved (chaos floor)".into(),
            points: vec![(e, 1.0), (e, top)],
            markers: false,
            thin: true,
        });
    }
    let title = format!("accuracy budget, {} (N = {}, {} steps)", f.scene, f.n, f.steps);
    let x_label = format!("error vs exact: {}", f.measure);
    draw(
        path,
        &Chart {
            title: &title,
            x_label: &x_label,
            y_label: "cost vs hertz (CPU time)",
            log_x: true,
            log_y: false,
            series,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(setting: &str, eps: Option<f64>, error: f64, cost: f64) -> FrontRow {
        FrontRow {
            setting: setting.into(),
            eps,
            cpu_s: Some(cost),
            cost_vs_hertz: Some(cost),
            cost_range: None,
            error: Some(error),
            recomputed: None,
            exact_by_reason: Vec::new(),
            measured: None,
            bound: None,
            bound_held: None,
            vs_best_fixed: None,
            best_fixed: None,
            vs_accurate_fixed: None,
            accurate_fixed: None,
        }
    }

    #[test]
    fn a_budget_is_compared_with_the_cheapest_fixed_setting_of_equal_or_larger_error() {
        let mut rows = vec![
            row("mcAccuracy 1e-2", Some(1e-2), 1e-3, 3.0),
            row("mcAccuracy 1e-4", Some(1e-4), 1e-7, 4.0),
            row("geometryTolerance 1e-3 updateEvery 10", None, 7e-3, 1.5),
            row("geometryTolerance 1e-4", None, 6e-5, 2.0),
        ];
        compare_with_fixed(&mut rows);
        // 1e-3: both fixed settings have more error; the cheaper is 1.5.
        assert_eq!(rows[0].vs_best_fixed, Some(2.0));
        assert_eq!(rows[0].best_fixed.as_deref(), Some("geometryTolerance 1e-3 updateEvery 10"));
        // Tolerance 1e-4 is more accurate (6e-5) and cheaper (2.0): it dominates this budget.
        assert_eq!(rows[0].vs_accurate_fixed, Some(1.5));
        assert_eq!(rows[0].accurate_fixed.as_deref(), Some("geometryTolerance 1e-4"));
        // 1e-7: both fixed settings have more error, the cheaper costs 1.5; none is as accurate.
        assert_eq!(rows[1].vs_best_fixed, Some(4.0 / 1.5));
        assert_eq!(rows[1].vs_accurate_fixed, None);
        let mut t = Vec::new();
        let f =
            Front { scene: "x".into(), measure: String::new(), n: 1, steps: 1, rounds: 1, rows, png: None };
        targets(std::slice::from_ref(&f), &mut t);
        assert_eq!(t.len(), 3);
        assert!(!t[0].met, "2.0 > {MATCH}");
        assert!(t.iter().any(|x| x.name.contains("as accurate") && !x.met));
    }

    #[test]
    fn the_error_is_relative_to_the_exact_runs_range_or_size() {
        let exact = [1.0, 3.0, 2.0];
        let other = [1.0, 3.5, 2.0];
        assert_eq!(error("hydrogel", &exact, &other), 0.25);
        assert_eq!(error("packing", &exact, &other), 0.5 / 3.0);
        assert!(error("packing", &exact, &other[..2]).is_nan());
        assert!(error("packing", &[0.0, 0.0], &[0.0, 1.0]).is_nan());
    }
}

//! `mcdem validate`: runs the validation cases and writes the report.
//!
//! Output contract in the report directory:
//! - `<case>.csv`: long form, columns `case,model,params,x_name,x,quantity,value`;
//! - `summary.json`: per case and model `nrmse` (against the reference where defined),
//!   `wall_time_s`, `particle_steps_per_s`, plus whether the case passed;
//! - `report.md`: one section per case with its tables and notes.

pub mod calibrate;
pub mod continuum;
pub mod die;
pub mod hard_cases;
pub mod heldout;
mod heldout_report;
pub mod packing;
pub mod physics;
pub mod uniaxial;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::harness::plot;
use crate::harness::progress::Progress;
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use crate::physics::model_kind::{ModelKind, ModelLabel};

/// One value of the long-form CSV.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub case: &'static str,
    pub model: ModelLabel,
    pub params: String,
    pub x_name: String,
    pub x: f64,
    pub quantity: String,
    pub value: f64,
}

/// Per-model figures of merit of one case.
#[derive(Debug, Clone, Serialize)]
pub struct ModelSummary {
    pub model: ModelLabel,
    /// NRMSE against the case's reference, where the case has one.
    pub nrmse: Option<f64>,
    pub wall_time_s: f64,
    /// Particle-steps per second for dynamic runs; `None` for static or kernel-level cases.
    pub particle_steps_per_s: Option<f64>,
    /// Further named figures (e.g. NRMSE per quantity and per reference kernel).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub metrics: std::collections::BTreeMap<String, f64>,
}

/// Everything a case produced.
#[derive(Debug, Clone, Default, Serialize)]
pub struct CaseResult {
    pub name: &'static str,
    pub title: String,
    /// Every check of the case held (correctness: analytic limits, cross-engine agreement, the
    /// reference table). A failed check makes `mcdem validate` exit non-zero.
    pub passed: bool,
    /// Agreement targets with the paper's claims: reported met or not, never tuned to pass; a
    /// missed target is a finding, not a failure of the code.
    #[serde(default)]
    pub targets: Vec<Target>,
    #[serde(skip)]
    pub rows: Vec<Row>,
    pub models: Vec<ModelSummary>,
    /// Markdown body of the case's report section (tables, notes).
    #[serde(skip)]
    pub markdown: String,
    pub wall_time_s: f64,
}

impl CaseResult {
    /// `passed` or `FAILED`, as the console and the report print it.
    pub fn status(&self) -> &'static str {
        if self.passed {
            "passed"
        } else {
            "FAILED"
        }
    }
}

/// One stated target: the measured value against its limit.
#[derive(Debug, Clone, Serialize)]
pub struct Target {
    pub name: String,
    pub value: f64,
    pub limit: f64,
    pub met: bool,
}

impl Target {
    /// A target of the form value ≤ limit.
    pub fn at_most(name: impl Into<String>, value: f64, limit: f64) -> Self {
        Self { name: name.into(), value, limit, met: value <= limit }
    }
}

/// A validation case: a name users pass to `--case` and the function that runs it.
pub struct Case {
    pub name: &'static str,
    pub run: fn(&Options) -> Result<CaseResult, String>,
}

/// Options of one `validate` invocation.
#[derive(Debug, Clone)]
pub struct Options {
    pub quick: bool,
    pub out: PathBuf,
    /// The progress display of the run, which a case may tell what it is on (set by [`run`]).
    pub progress: Option<Arc<Progress>>,
}

/// The wall time [s] of `case` in the previous `summary.json` under `out`, if any and of the same
/// mode: the expected time of the case in the progress display.
fn previous_wall_time(out: &Path, case: &str, quick: bool) -> Option<f64> {
    let text = std::fs::read_to_string(out.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    if v["quick"].as_bool()? != quick {
        return None;
    }
    v["cases"].as_array()?.iter().find(|c| c["name"] == case)?["wall_time_s"].as_f64()
}

/// Every case, in report order.
pub fn cases() -> Vec<Case> {
    vec![
        Case { name: "physics_checks", run: physics::run },
        Case { name: "single_particle", run: die::run_single },
        Case { name: "bcc", run: die::run_bcc },
        Case { name: "uniaxial", run: uniaxial::run },
        Case { name: "hard_cases", run: hard_cases::run },
    ]
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn write_csv(path: &Path, rows: &[Row]) -> Result<(), String> {
    let mut s = String::from("case,model,params,x_name,x,quantity,value\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{:e},{},{:e}",
            r.case,
            csv_field(r.model.as_str()),
            csv_field(&r.params),
            csv_field(&r.x_name),
            r.x,
            csv_field(&r.quantity),
            r.value
        );
    }
    std::fs::write(path, s).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Runs the selected cases (all when `only` is empty) and writes the report files.
pub fn run(opts: &Options, only: &[String]) -> Result<Vec<CaseResult>, String> {
    let all = cases();
    for name in only {
        if !all.iter().any(|c| c.name == name) {
            let known: Vec<_> = all.iter().map(|c| c.name).collect();
            return Err(format!("unknown case '{name}': known cases are {}", known.join(", ")));
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| format!("cannot create {}: {e}", opts.out.display()))?;
    let start = Instant::now();
    let mut results = Vec::new();
    let selected: Vec<&Case> =
        all.iter().filter(|c| only.is_empty() || only.iter().any(|n| n == c.name)).collect();
    let progress = Arc::new(Progress::new("validate", selected.len()));
    for case in &selected {
        if let Some(t) = previous_wall_time(&opts.out, case.name, opts.quick) {
            progress.expect(case.name, t);
        }
    }
    let case_opts = Options { progress: Some(progress.clone()), ..opts.clone() };
    for case in selected {
        progress.println(&format!("validate: running {}", case.name));
        let t = Instant::now();
        progress.start(case.name);
        // A case that cannot run (missing input, unstable model) is reported as failed with its
        // message; the other cases still run.
        let mut r = (case.run)(&case_opts).unwrap_or_else(|e| {
            progress.println(&format!("validate: {}: {e}", case.name));
            CaseResult {
                name: case.name,
                title: "did not run".into(),
                passed: false,
                markdown: format!("**Error:** {e}\n"),
                ..Default::default()
            }
        });
        r.wall_time_s = t.elapsed().as_secs_f64();
        progress.finish(case.name);
        write_csv(&opts.out.join(format!("{}.csv", case.name)), &r.rows)?;
        progress.println(&format!("validate: {} {} in {:.1} s", case.name, r.status(), r.wall_time_s));
        results.push(r);
    }
    // The display ends (and its thread with it) before the report is written.
    drop(case_opts);
    drop(progress);
    let total = start.elapsed().as_secs_f64();
    let summary = serde_json::json!({
        "quick": opts.quick,
        "total_wall_time_s": total,
        "cases": results,
    });
    let path = opts.out.join("summary.json");
    std::fs::write(&path, serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let mut md = format!(
        "# mcdem validation report\n\nMode: {}. Total wall time: {total:.1} s. mcdem {}.\n\n| case | checks | targets met | wall time [s] |\n|---|---|---|---|\n",
        if opts.quick { "quick" } else { "full" },
        env!("CARGO_PKG_VERSION")
    );
    for r in &results {
        let _ = writeln!(
            md,
            "| {} | {} | {}/{} | {:.2} |",
            r.name,
            r.status(),
            r.targets.iter().filter(|t| t.met).count(),
            r.targets.len(),
            r.wall_time_s
        );
    }
    md.push_str(&speed_vs_error(opts, &results)?);
    for r in &results {
        let _ = write!(md, "\n## {}: {}\n\n{}\n", r.name, r.title, r.markdown);
        if !r.targets.is_empty() {
            md.push_str("\n| target | value | limit | met |\n|---|---|---|---|\n");
            for t in &r.targets {
                let _ = writeln!(
                    md,
                    "| {} | {:.4} | {:.4} | {} |",
                    t.name,
                    t.value,
                    t.limit,
                    if t.met { "yes" } else { "NO" }
                );
            }
        }
    }
    let path = opts.out.join("report.md");
    std::fs::write(&path, md).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(results)
}

/// The speed-against-error picture, one panel per case: every model run of the case that has an
/// NRMSE against its reference and a wall time, all measured in this run, and the reference's own
/// cost as a vertical line (what it costs to have the "exact" answer).
fn speed_vs_error(opts: &Options, results: &[CaseResult]) -> Result<String, String> {
    let mut table = String::from(
        "\n## Speed against error\n\nEvery model run of this invocation that has an NRMSE against its reference \
         (wall time includes setup; one point per model and setting), and the cost of each reference run.\n\n\
         | case | model | NRMSE | wall time [s] | particle-steps/s |\n|---|---|---|---|---|\n",
    );
    let mut panels: Vec<(String, Vec<plot::Series>)> = Vec::new();
    for r in results {
        let mut series: Vec<plot::Series> = Vec::new();
        let mut references: Vec<(String, f64)> = Vec::new();
        for m in &r.models {
            let Some(e) = m.nrmse else {
                if m.model.as_str().starts_with("nonlocal") {
                    references.push((m.model.to_string(), m.wall_time_s));
                    let _ = writeln!(
                        table,
                        "| {} | {} (reference) | - | {:.3} | - |",
                        r.name, m.model, m.wall_time_s
                    );
                }
                continue;
            };
            let _ = writeln!(
                table,
                "| {} | {} | {:.3} % | {:.3} | {} |",
                r.name,
                m.model,
                100.0 * e,
                m.wall_time_s,
                m.particle_steps_per_s.map(|v| format!("{v:.3e}")).unwrap_or_else(|| "-".into())
            );
            // One colour per engine and model family within a panel; the table names every point.
            let model = m.model.as_str();
            let engine = if model.starts_with("liggghts_") { "LIGGGHTS" } else { "Rust DEM" };
            let family = [ModelKind::McAdvanced, ModelKind::StandardMc, ModelKind::Hertz]
                .into_iter()
                .map(ModelKind::name)
                .find(|f| model.contains(f))
                .unwrap_or(model);
            // The approximate passes (docs/dem.md) get their own colour: their speed is the point.
            let approx =
                if model.contains("_tol") || model.contains("_every") { ", approximate" } else { "" };
            let label = format!("{family}{approx} ({engine})");
            let point = (m.wall_time_s.max(1e-4), (100.0 * e).max(1e-4));
            match series.iter_mut().find(|s| s.label == label) {
                Some(s) => s.points.push(point),
                None => series.push(plot::Series { label, points: vec![point], markers: true, thin: false }),
            }
        }
        if series.is_empty() {
            continue;
        }
        // The reference's cost: a vertical line over the panel's error range, one per reference
        // run (e.g. one per Poisson ratio).
        let ys = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
        let (lo, hi) = ys.fold((f64::INFINITY, 0.0_f64), |(lo, hi), y| (lo.min(y), hi.max(y)));
        for (name, t) in references {
            let label = format!("reference cost: {}", name.split(' ').next().unwrap_or(&name));
            let points = vec![(t.max(1e-4), lo / 1.2), (t.max(1e-4), hi * 1.2)];
            match series.iter_mut().find(|s| s.label == label) {
                // A second reference run of the same kind: its own vertical segment, drawn as a
                // separate series with the same label would repeat the legend, so draw it thin.
                Some(_) => {
                    series.push(plot::Series { label: String::new(), points, markers: false, thin: true })
                }
                None => series.push(plot::Series { label, points, markers: false, thin: true }),
            }
        }
        panels.push((r.name.to_string(), series));
    }
    if panels.is_empty() {
        return Ok(String::new());
    }
    let titles: Vec<String> =
        panels.iter().map(|(c, _)| format!("{c}: speed against error (this run)")).collect();
    let charts: Vec<plot::Chart> = panels
        .into_iter()
        .zip(&titles)
        .map(|((_, series), title)| plot::Chart {
            title,
            x_label: "wall time [s]",
            y_label: "NRMSE vs reference [%]",
            log_x: true,
            log_y: true,
            series,
        })
        .collect();
    let file = "speed_vs_error.png";
    plot::draw_panels(&opts.out.join(file), &charts, 2)?;
    let _ = writeln!(table, "\n![speed against error, one panel per case]({file})");
    Ok(table)
}

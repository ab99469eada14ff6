//! Cases `single_particle` and `bcc` (paper App. B, Fig. B.2; docs/spec.md §5.1): hydrogel spheres
//! (d = 2 mm) in a rigid cubic die, top plate pushed down at 0.01 m/s, gravity off. Plate stress and
//! side-wall stress against plate displacement / r for Hertz, standard MC (γ = 0.82) and advanced
//! MC (γ = 0.81, MPR = 0.11), run by the Rust DEM (and by the LIGGGHTS plugin when it is built),
//! against the nonlocal quasi-static solution.
//!
//! Stresses are force / L² for every wall (L the die side), in both engines and the reference, so
//! the side-wall stress is the paper's "lateral stress" up to the shrinking height of the wall;
//! comparisons are unaffected because every curve uses the same definition.

use std::fmt::Write as _;

use serde_json::json;

use super::continuum::Curve;
use super::{CaseResult, ModelSummary, Options, Row, Target};
use crate::harness::runner::{self, DeckRun};
use crate::nonlocal::scene::Scene;
use crate::nonlocal::KernelKind;
use crate::outputs::nrmse;
use crate::physics::model_kind::ModelKind;

/// Sphere diameter [m] and plate speed [m/s] of App. B; the decks' time step [s].
const D: f64 = 0.002;
const R: f64 = D / 2.0;
const V_PLATE: f64 = 0.01;
const DT: f64 = 1e-5;
/// Plate travel of the comparison, in radii (the docs/spec.md §4 die table goes to 0.3).
const TRAVEL: f64 = 0.3;
/// Nonlocal load steps over the travel (one per 0.01 r, the DEM output interval).
const NONLOCAL_STEPS: usize = 30;
/// The App. B calibration the case checks (paper App. B).
const GAMMA_STANDARD: f64 = 0.82;
const GAMMA_ADVANCED: f64 = 0.81;
const MPR_ADVANCED: f64 = 0.11;
/// Required agreement of the calibrated MC models with the reference (the validation issue).
const TARGET_NRMSE: f64 = 0.05;
/// Friction of the paper's runs (Fig. B.1); the comparison with the frictionless reference uses 0.
const MU_PAPER: f64 = 0.03;
/// Poisson ratio of the hydrogel in the decks and the nonlocal scene (die_common.inc).
const NU_PARTICLE: f64 = 0.5;
/// Engine vs plugin on the same deck: both integrate the same equations with the same time step,
/// so the curves agree to round-off; 1e-6 of the curve's scale leaves room for printed precision.
const ENGINE_TOLERANCE: f64 = 1e-6;
/// Engine vs stock LIGGGHTS `surface multicontact` (different code, emulated conventions).
const STOCK_TOLERANCE: f64 = 1e-3;

/// One die scene.
pub(super) struct Die {
    pub(super) case: &'static str,
    title: &'static str,
    pub(super) deck: &'static str,
    pub(super) side: f64,
    centres: Vec<[f64; 3]>,
}

pub(super) fn single() -> Die {
    Die {
        case: "single_particle",
        title: "single hydrogel sphere in a rigid die (App. B, Fig. B.2a)",
        deck: "single_particle_plates.in",
        side: D,
        centres: vec![[R, R, R]],
    }
}

pub(super) fn bcc() -> Die {
    let l = D * (1.0 + 2.0 / 3f64.sqrt());
    let (lo, hi) = (R, l - R);
    let mut centres = Vec::new();
    for z in [lo, hi] {
        for y in [lo, hi] {
            for x in [lo, hi] {
                centres.push([x, y, z]);
            }
        }
    }
    centres.push([l / 2.0; 3]);
    Die {
        case: "bcc",
        title: "nine hydrogel spheres, bcc cell in a rigid die (App. B, Fig. B.2b)",
        deck: "bcc_box.in",
        side: l,
        centres,
    }
}

struct DemModel {
    name: ModelKind,
    law: &'static str,
    gamma: f64,
    mpr: f64,
}

const MODELS: [DemModel; 3] = [
    DemModel { name: ModelKind::Hertz, law: "1", gamma: 1.0, mpr: 0.0 },
    DemModel { name: ModelKind::StandardMc, law: "2", gamma: GAMMA_STANDARD, mpr: 0.0 },
    DemModel { name: ModelKind::McAdvanced, law: "0", gamma: GAMMA_ADVANCED, mpr: MPR_ADVANCED },
];

impl DemModel {
    fn params(&self) -> String {
        match self.law {
            "1" => "hertz".into(),
            "2" => format!("gamma={}", self.gamma),
            _ => format!("gamma={} mpr={}", self.gamma, self.mpr),
        }
    }

    fn vars(&self, mu: f64) -> Vec<(&'static str, String)> {
        let steps = (TRAVEL * R / V_PLATE / DT).round() as u64;
        vec![
            ("mu", mu.to_string()),
            ("law", self.law.into()),
            ("gamma", self.gamma.to_string()),
            ("mpr", self.mpr.to_string()),
            ("steps", steps.to_string()),
            ("every", "100".into()),
        ]
    }
}

/// Deck variables of a frictionless die run with `m` at the particles' Poisson ratio `nu`
/// (die_common.inc's `nu` and `E`; the case itself runs the decks' defaults, 0.5 and 23.3 kPa).
pub(super) fn law_vars(m: crate::harness::calibration::Law, nu: f64) -> Vec<(&'static str, String)> {
    let steps = (TRAVEL * R / V_PLATE / DT).round() as u64;
    vec![
        ("mu", "0".into()),
        ("law", m.law.into()),
        ("gamma", m.gamma.to_string()),
        ("mpr", m.mpr.to_string()),
        ("steps", steps.to_string()),
        ("every", "100".into()),
        ("nu", nu.to_string()),
        ("E", m.youngs_modulus.to_string()),
    ]
}

/// The decks write `v_disp f_plate_m[3] f_side_m[1]`; the side wall is the x = 0 face, pushed in −x.
pub(super) fn curve_of(run: &DeckRun, side: f64) -> Result<Curve, String> {
    let area = side * side;
    run.table
        .iter()
        .map(|r| match r.as_slice() {
            [_, disp, fz, fx, ..] => Ok((disp / R, fz / area, -fx / area)),
            _ => Err("die deck output: expected columns step disp plate_fz side_fx".to_string()),
        })
        .collect()
}

/// The nonlocal solution of the same die: kernel `kind` scaled by `scale`.
fn nonlocal(die: &Die, kind: KernelKind, scale: f64) -> Result<(Curve, f64), String> {
    nonlocal_nu(die, kind, scale, NU_PARTICLE)
}

/// [`nonlocal`] with the particles' Poisson ratio `nu` (the walls keep 0.5: at E = 50 MPa they
/// are rigid against the particles whatever their ν).
pub(super) fn nonlocal_nu(die: &Die, kind: KernelKind, scale: f64, nu: f64) -> Result<(Curve, f64), String> {
    let l = die.side;
    let spheres: Vec<_> = die.centres.iter().map(|c| json!({"x": c, "radius": R})).collect();
    let scene = json!({
        "spheres": spheres,
        "particle_material": {"youngs_modulus": 23.3e3, "poisson_ratio": nu},
        "wall_material": {"youngs_modulus": 50e6, "poisson_ratio": 0.5},
        "kernel": kind.name(),
        "kernel_scale": scale,
        "walls": [
            {"name": "bottom", "point": [0, 0, 0], "normal": [0, 0, 1]},
            {"name": "top", "point": [0, 0, l], "normal": [0, 0, -1], "displacement": [0, 0, -TRAVEL * R]},
            {"name": "xlo", "point": [0, 0, 0], "normal": [1, 0, 0]},
            {"name": "xhi", "point": [l, 0, 0], "normal": [-1, 0, 0]},
            {"name": "ylo", "point": [0, 0, 0], "normal": [0, 1, 0]},
            {"name": "yhi", "point": [0, l, 0], "normal": [0, -1, 0]}
        ],
        "steps": NONLOCAL_STEPS
    });
    let mut s = Scene::from_json(&scene.to_string(), std::path::Path::new("."))?;
    let mut csv = Vec::new();
    let summary = s.run(&mut csv, None, &mut |_| {})?;
    let text = String::from_utf8_lossy(&csv);
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().ok_or("nonlocal: empty output")?.split(',').collect();
    let col =
        |name: &str| header.iter().position(|h| *h == name).ok_or(format!("nonlocal: no column {name}"));
    let (top_pos, top_f, side_f) = (col("top_position")?, col("top_force")?, col("xlo_force")?);
    let mut curve = Curve::new();
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap_or(f64::NAN)).collect();
        // top_position is the plane's offset along its inward normal −z, i.e. −z_top.
        let disp = l + v[top_pos];
        curve.push((disp / R, v[top_f] / (l * l), v[side_f] / (l * l)));
    }
    Ok((curve, summary.wall_seconds))
}

/// NRMSE of `model` against `reference` on the reference's points (x > 0), plate and side.
pub(super) fn errors(model: &Curve, reference: &Curve) -> (f64, f64) {
    let plate: Vec<(f64, f64)> = model.iter().map(|p| (p.0, p.1)).collect();
    let side: Vec<(f64, f64)> = model.iter().map(|p| (p.0, p.2)).collect();
    let (mut mp, mut rp, mut ms, mut rs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &(x, p, s) in reference.iter().filter(|p| p.0 > 1e-9) {
        if let (Some(a), Some(b)) = (runner::interpolate(&plate, x), runner::interpolate(&side, x)) {
            mp.push(a);
            rp.push(p);
            ms.push(b);
            rs.push(s);
        }
    }
    if mp.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    (nrmse(&mp, &rp), nrmse(&ms, &rs))
}

/// Largest difference between two curves on common points, relative to the larger curve's range.
fn curve_difference(a: &Curve, b: &Curve) -> f64 {
    let scale = a.iter().chain(b).map(|p| p.1.abs().max(p.2.abs())).fold(0.0, f64::max).max(1e-300);
    a.iter().zip(b).map(|(p, q)| (p.1 - q.1).abs().max((p.2 - q.2).abs()) / scale).fold(0.0, f64::max)
}

fn push_curve(rows: &mut Vec<Row>, case: &'static str, model: &str, params: &str, curve: &Curve) {
    for &(x, p, s) in curve {
        for (q, v) in [("plate_stress_pa", p), ("side_stress_pa", s)] {
            rows.push(Row {
                case,
                model: model.into(),
                params: params.into(),
                x_name: "plate_disp_over_r".into(),
                x,
                quantity: q.into(),
                value: v,
            });
        }
    }
}

fn run_die(die: Die, opts: &Options) -> Result<CaseResult, String> {
    let mut rows = Vec::new();
    let mut md = String::new();
    let mut models = Vec::new();
    let mut ok = true;
    let mut notes = Vec::new();
    let mut targets = Vec::new();

    // References: both kernels, `sphere` first (docs/spec.md §4.1 default, the primary reference).
    let mut refs = Vec::new();
    for kind in [KernelKind::Sphere, KernelKind::Boussinesq] {
        let (c, secs) = nonlocal(&die, kind, 1.0)?;
        let name = format!("nonlocal_{}", kind.name());
        push_curve(&mut rows, die.case, &name, "kernel_scale=1", &c);
        models.push(ModelSummary {
            model: name.clone().into(),
            nrmse: None,
            wall_time_s: secs,
            particle_steps_per_s: None,
            metrics: Default::default(),
        });
        refs.push((kind, c));
    }
    let primary = &refs[0];
    // Consistency partners: kernel `none` is quasi-static Hertz; boussinesq × 0.82 is the fixed
    // point standard MC (γ = 0.82) iterates towards (docs/spec.md §4 consequence (b)).
    let (hertz_qs, _) = nonlocal(&die, KernelKind::None, 1.0)?;
    let (mc_qs, _) = nonlocal(&die, KernelKind::Boussinesq, GAMMA_STANDARD)?;
    push_curve(&mut rows, die.case, "nonlocal_none", "kernel_scale=1", &hertz_qs);
    push_curve(&mut rows, die.case, "nonlocal_boussinesq", &format!("kernel_scale={GAMMA_STANDARD}"), &mc_qs);

    let plugin = runner::plugin_exe();
    let _ = writeln!(
        md,
        "Die side {:.4} mm, {} sphere(s) of d = 2 mm, plate at {V_PLATE} m/s to {TRAVEL} r, dt = {DT} s. \
         Stress = wall force / L² [Pa]. Reference: nonlocal, kernel `{}` (γ = 1), frictionless; the DEM rows are frictionless too (μ = 0, e = 0.95) except `*_mu0.03`, the paper's friction. LIGGGHTS plugin: {}.\n",
        die.side * 1e3,
        die.centres.len(),
        primary.0.name(),
        if plugin.is_some() { "ran (rows `liggghts_*`)" } else { "not built, skipped" }
    );
    let mut header = String::from("| engine | model | params | wall time [s] | particle-steps/s |");
    for (k, _) in &refs {
        let _ = write!(header, " NRMSE plate vs {0} | NRMSE side vs {0} |", k.name());
    }
    let _ = writeln!(md, "{header}\n|{}", "---|".repeat(5 + 2 * refs.len()));

    let mut curves = Vec::new();
    for m in &MODELS {
        let run = runner::run_rust(die.deck, &m.vars(0.0))?;
        let curve = curve_of(&run, die.side)?;
        push_curve(&mut rows, die.case, m.name.name(), &m.params(), &curve);
        let mut line = format!(
            "| rust | {} | {} | {:.3} | {:.3e} |",
            m.name,
            m.params(),
            run.wall_time_s,
            run.particle_steps_per_s
        );
        let mut metrics = std::collections::BTreeMap::new();
        for (k, rc) in &refs {
            let (p, s) = errors(&curve, rc);
            let _ = write!(line, " {:.2} % | {:.2} % |", 100.0 * p, 100.0 * s);
            metrics.insert(format!("nrmse_plate_{}", k.name()), p);
            metrics.insert(format!("nrmse_side_{}", k.name()), s);
        }
        let (p, s) = errors(&curve, &primary.1);
        let _ = writeln!(md, "{line}");
        if m.law != "1" {
            for (q, v) in [("plate", p), ("side", s)] {
                targets.push(Target::at_most(
                    format!("{} {q} NRMSE vs nonlocal {}", m.name, primary.0.name()),
                    v,
                    TARGET_NRMSE,
                ));
            }
        }
        models.push(ModelSummary {
            model: m.name.into(),
            nrmse: Some(p.max(s)),
            wall_time_s: run.wall_time_s,
            particle_steps_per_s: Some(run.particle_steps_per_s),
            metrics,
        });
        if let Some(exe) = &plugin {
            let lrun = runner::run_liggghts(exe, die.deck, &m.vars(0.0))?;
            let lcurve = curve_of(&lrun, die.side)?;
            let diff = curve_difference(&curve, &lcurve);
            let name = format!("liggghts_{}", m.name);
            push_curve(&mut rows, die.case, &name, &m.params(), &lcurve);
            let (lp, ls) = errors(&lcurve, &primary.1);
            let _ = writeln!(
                md,
                "| liggghts | {} | {} | {:.3} | {:.3e} | {:.2} % | {:.2} % |{}",
                m.name,
                m.params(),
                lrun.wall_time_s,
                lrun.particle_steps_per_s,
                100.0 * lp,
                100.0 * ls,
                " |".repeat(2 * refs.len() - 2)
            );
            // Law 2 is stock LIGGGHTS `surface multicontact`, which the engine emulates (its radius
            // convention and growth detection) rather than shares code with: a looser bound.
            let tol = if m.law == "2" { STOCK_TOLERANCE } else { ENGINE_TOLERANCE };
            notes.push(format!(
                "{}: Rust DEM vs LIGGGHTS{}, largest difference {diff:.2e} of the curve scale (tolerance {tol:.0e}).",
                m.name,
                if m.law == "2" { " stock `surface multicontact`" } else { " plugin" }
            ));
            ok &= diff <= tol;
            models.push(ModelSummary {
                model: name.into(),
                nrmse: Some(lp.max(ls)),
                wall_time_s: lrun.wall_time_s,
                particle_steps_per_s: Some(lrun.particle_steps_per_s),
                metrics: Default::default(),
            });
        }
        // The paper's runs have wall and particle friction μ = 0.03; the reference has none.
        let frun = runner::run_rust(die.deck, &m.vars(MU_PAPER))?;
        let fcurve = curve_of(&frun, die.side)?;
        let fname = format!("{}_mu{MU_PAPER}", m.name);
        push_curve(&mut rows, die.case, &fname, &m.params(), &fcurve);
        let (fp, fs) = errors(&fcurve, &primary.1);
        let _ = writeln!(
            md,
            "| rust | {fname} | {} | {:.3} | {:.3e} | {:.2} % | {:.2} % |{}",
            m.params(),
            frun.wall_time_s,
            frun.particle_steps_per_s,
            100.0 * fp,
            100.0 * fs,
            " |".repeat(2 * refs.len() - 2)
        );
        models.push(ModelSummary {
            model: fname.into(),
            nrmse: Some(fp.max(fs)),
            wall_time_s: frun.wall_time_s,
            particle_steps_per_s: Some(frun.particle_steps_per_s),
            metrics: Default::default(),
        });
        curves.push((m.name.name(), curve));
    }

    // Physics checks that hold whatever the reference kernel.
    let hertz = &curves[0].1;
    let (hp, _) = errors(hertz, &hertz_qs);
    let hertz_ok = hp <= 0.02;
    ok &= hertz_ok;
    notes.push(format!(
        "DEM Hertz vs quasi-static Hertz (nonlocal, kernel `none`): plate NRMSE {:.3} % (limit 2 %: the DEM runs at finite speed with e = 0.95).",
        100.0 * hp
    ));
    let (sp, ss) = errors(&curves[1].1, &mc_qs);
    notes.push(format!(
        "DEM standard MC (γ = {GAMMA_STANDARD}) vs its static fixed point (nonlocal `boussinesq` × {GAMMA_STANDARD}): plate {:.2} %, side {:.2} %.",
        100.0 * sp,
        100.0 * ss
    ));
    if die.case == "single_particle" {
        let lateral = hertz.iter().map(|p| p.2.abs()).fold(0.0, f64::max);
        let plate = hertz.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
        // Round-off only: the sphere touches the side walls at zero overlap and its centre may
        // drift by a few ulps; 1e-9 of the plate stress is far below any physical lateral stress.
        let zero = lateral <= 1e-9 * plate;
        ok &= zero;
        notes.push(format!(
            "Hertz lateral stress of the single particle: max |σ_side| = {lateral:.2e} Pa = {:.1e} of the plate stress ({}).",
            lateral / plate.max(1e-300),
            if zero { "zero to round-off, as it must be: nothing couples the plate to the side walls" } else { "NOT zero" }
        ));
    }
    if die.case == "single_particle" {
        let statics = [
            ("nonlocal_none (static Hertz)".to_string(), &hertz_qs),
            (format!("nonlocal_boussinesq × {GAMMA_STANDARD} (standard MC's static fixed point)"), &mc_qs),
        ];
        continuum_section(&refs, &curves, &statics, &mut models, &mut rows, &mut md)?;
        let bous = refs.iter().find(|(k, _)| *k == KernelKind::Boussinesq).map(|(_, c)| c);
        if let Some(bous) = bous {
            let (met, text) = die_table_check(bous, &hertz_qs, die.side * die.side)?;
            ok &= met;
            md.push_str(&text);
        }
    }
    md.push('\n');
    for n in &notes {
        let _ = writeln!(md, "- {n}");
    }
    let (best, scan_png) = gamma_scan(&die, &refs, &mut rows, &mut md, &opts.out)?;
    if die.case == "bcc" {
        // docs/spec.md §4 consequence (b): standard MC relaxed by the DEM is a lagged iteration of the
        // nonlocal relation with kernel γG, so against the γ = 1 kernel (`boussinesq`) the scan must
        // find its best at γ = 1 (one scan step either side). The bcc contacts stay small enough
        // for the second-order geometric terms not to move it; the single particle's do (report).
        if let Some(&(_, gamma, e)) = best.iter().find(|b| b.0 == KernelKind::Boussinesq) {
            let held = (gamma - 1.0).abs() <= 0.05 + 1e-9;
            ok &= held;
            let _ = writeln!(
                md,
                "- Parity with the static solver: against `boussinesq` (γ = 1) the scan is best at γ = {gamma:.2} \
                 (NRMSE {:.1} %); it must be 1 ± 0.05 ({}).",
                100.0 * e,
                if held { "holds" } else { "FAILS" }
            );
        }
    }
    let _ = writeln!(md, "\n![{} γ scan]({scan_png})", die.case);
    if let Some(m) = models.iter_mut().find(|m| m.model == ModelKind::StandardMc) {
        for (k, gamma, e) in &best {
            m.metrics.insert(format!("gamma_scan_best_gamma_{}", k.name()), *gamma);
            m.metrics.insert(format!("gamma_scan_best_nrmse_{}", k.name()), *e);
        }
    }

    // Fig. B.2 analogue.
    let file = format!("{}_stress.png", die.case);
    let mut series = Vec::new();
    let mut add = |label: &str, c: &Curve, markers: bool| {
        series.push(crate::harness::plot::Series {
            label: format!("{label} plate"),
            points: c.iter().map(|p| (p.0, p.1)).collect(),
            markers,
            thin: false,
        });
        series.push(crate::harness::plot::Series {
            label: format!("{label} side"),
            points: c.iter().map(|p| (p.0, p.2)).collect(),
            markers,
            thin: true,
        });
    };
    for (k, c) in &refs {
        add(&format!("nonlocal {}", k.name()), c, true);
    }
    if die.case == "single_particle" {
        let cref = super::continuum::closest(NU_PARTICLE)?;
        add(&format!("FEM {} nu {}", cref.law, cref.nu), &cref.curve(), true);
    }
    for (name, c) in &curves {
        add(name, c, false);
    }
    crate::harness::plot::draw(
        &opts.out.join(&file),
        &crate::harness::plot::Chart {
            title: die.title,
            x_label: "plate displacement / r",
            y_label: "stress [Pa]",
            log_x: false,
            log_y: false,
            series,
        },
    )?;
    let _ = writeln!(md, "\n![{} stresses]({file})", die.case);
    Ok(CaseResult {
        name: die.case,
        title: die.title.into(),
        passed: ok,
        targets,
        rows,
        models,
        markdown: md,
        wall_time_s: 0.0,
    })
}

/// Per reference kernel: the γ of the scan whose worse NRMSE (plate or side) is smallest, and that NRMSE.
type ScanBest = Vec<(KernelKind, f64, f64)>;

/// The standard-MC prefactors of the γ scan: 0.50, 0.55, … 1.25 (App. B's 0.82 lies inside).
fn scan_gammas() -> impl Iterator<Item = f64> {
    (0..=15).map(|k| f64::from(50 + 5 * k) / 100.0)
}

/// The die under standard MC for every γ of [`scan_gammas`], frictionless, against each reference:
/// which γ each stress would need, and whether any γ brings both within the target. This separates
/// the calibration (γ) from the form of Eq. 2: a miss at App. B's γ that no γ removes is the model's.
/// Rows go to the case's CSV (x = γ); a run that stops (large γ drives the lagged iteration
/// unstable) is listed with its cause. Returns the best γ and its worst-of-two NRMSE per reference,
/// and the file name of the NRMSE-against-γ plot written to `out`.
fn gamma_scan(
    die: &Die,
    refs: &[(KernelKind, Curve)],
    rows: &mut Vec<Row>,
    md: &mut String,
    out: &std::path::Path,
) -> Result<(ScanBest, String), String> {
    let mut header = String::from("| γ |");
    for (k, _) in refs {
        let _ = write!(header, " plate vs {0} | side vs {0} |", k.name());
    }
    let _ = writeln!(
        md,
        "\nStandard MC across γ (frictionless Rust DEM, NRMSE over the same range):\n\n{header}\n|---|{}",
        "---|".repeat(2 * refs.len())
    );
    // Per reference: every (γ, plate, side) that ran.
    let mut found: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); refs.len()];
    for gamma in scan_gammas() {
        let m = DemModel { name: ModelKind::StandardMc, law: "2", gamma, mpr: 0.0 };
        let curve = match runner::run_rust(die.deck, &m.vars(0.0)) {
            Ok(run) => curve_of(&run, die.side)?,
            Err(f) => match f.instability {
                Some(stop) => {
                    let _ = writeln!(
                        md,
                        "| {gamma:.2} | stopped at step {}: {}{}",
                        stop.step,
                        stop.cause,
                        " |".repeat(2 * refs.len())
                    );
                    continue;
                }
                None => return Err(f.message),
            },
        };
        let mut line = format!("| {gamma:.2} |");
        for (r, (k, rc)) in refs.iter().enumerate() {
            let (p, s) = errors(&curve, rc);
            let _ = write!(line, " {:.1} % | {:.1} % |", 100.0 * p, 100.0 * s);
            for (q, v) in [("plate", p), ("side", s)] {
                rows.push(Row {
                    case: die.case,
                    model: "standard_mc_gamma_scan".into(),
                    params: format!("gamma={gamma}"),
                    x_name: "gamma".into(),
                    x: gamma,
                    quantity: format!("nrmse_{q}_{}", k.name()),
                    value: v,
                });
            }
            found[r].push((gamma, p, s));
        }
        let _ = writeln!(md, "{line}");
    }
    let mut best = Vec::new();
    md.push('\n');
    for ((k, _), runs) in refs.iter().zip(&found) {
        let pick = |key: &dyn Fn(&(f64, f64, f64)) -> f64| {
            runs.iter().copied().filter(|r| key(r).is_finite()).min_by(|a, b| key(a).total_cmp(&key(b)))
        };
        let (Some(plate), Some(side), Some(both)) = (pick(&|r| r.1), pick(&|r| r.2), pick(&|r| r.1.max(r.2)))
        else {
            let _ = writeln!(md, "- vs `{}`: no γ of the scan ran to the end.", k.name());
            continue;
        };
        let within: Vec<String> =
            runs.iter().filter(|r| r.1.max(r.2) <= TARGET_NRMSE).map(|r| format!("{:.2}", r.0)).collect();
        let _ = writeln!(
            md,
            "- vs `{}`: the plate is closest at γ = {:.2} ({:.1} %), the side wall at γ = {:.2} ({:.1} %); \
             the worse of the two is smallest at γ = {:.2} ({:.1} %). {}",
            k.name(),
            plate.0,
            100.0 * plate.1,
            side.0,
            100.0 * side.2,
            both.0,
            100.0 * both.1.max(both.2),
            if within.is_empty() {
                format!("No γ meets {:.0} % on both.", 100.0 * TARGET_NRMSE)
            } else {
                format!("Within {:.0} % on both: γ = {}.", 100.0 * TARGET_NRMSE, within.join(", "))
            }
        );
        best.push((*k, both.0, both.1.max(both.2)));
    }
    let file = format!("{}_gamma_scan.png", die.case);
    let mut series = Vec::new();
    for ((k, _), runs) in refs.iter().zip(&found) {
        for (q, thin) in [("plate", false), ("side", true)] {
            series.push(crate::harness::plot::Series {
                label: format!("{q} vs nonlocal {}", k.name()),
                points: runs.iter().map(|r| (r.0, 100.0 * if thin { r.2 } else { r.1 })).collect(),
                markers: false,
                thin,
            });
        }
    }
    let title = format!("{}: standard MC NRMSE against γ", die.case);
    crate::harness::plot::draw(
        &out.join(&file),
        &crate::harness::plot::Chart {
            title: &title,
            x_label: "γ (Eq. 2 prefactor)",
            y_label: "NRMSE [%]",
            log_x: false,
            log_y: true,
            series,
        },
    )?;
    Ok((best, file))
}

pub fn run_single(opts: &Options) -> Result<CaseResult, String> {
    run_die(single(), opts)
}

pub fn run_bcc(opts: &Options) -> Result<CaseResult, String> {
    run_die(bcc(), opts)
}

/// The docs/spec.md §4 die table (validation/reference/die_single_boussinesq.csv), derived by the
/// independent script `die_single_boussinesq.py` beside it: the solver's boussinesq and `none` curves must reproduce it, P_v to 1e-3
/// relative and P_h to its three printed digits (5e-3).
const DIE_TABLE: &str = include_str!("../../validation/reference/die_single_boussinesq.csv");

fn die_table_check(bous: &Curve, hertz: &Curve, area: f64) -> Result<(bool, String), String> {
    let mut ok = true;
    let mut md = String::from(
        "\nNonlocal solver against the reference die table (`validation/reference/die_single_boussinesq.csv`):\n\n\
         | Δ/r | P_v Hertz [N] (table) | P_v nonlocal [N] (table) | P_h nonlocal [N] (table) | worst rel. diff |\n|---|---|---|---|---|\n",
    );
    for line in DIE_TABLE.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse::<f64>().map_err(|_| format!("die table: bad line '{line}'")))
            .collect::<Result<_, _>>()?;
        let [x, pvh, pv, ph] = v[..] else { return Err(format!("die table: bad line '{line}'")) };
        let at = |c: &Curve| c.iter().find(|p| (p.0 - x).abs() < 1e-9).map(|p| (p.1 * area, p.2 * area));
        let (Some((h, _)), Some((v_n, h_n))) = (at(hertz), at(bous)) else {
            return Err(format!("die table: no nonlocal load step at delta/r = {x}"));
        };
        let d = [(h - pvh).abs() / pvh, (v_n - pv).abs() / pv, (h_n - ph).abs() / ph];
        let met = d[0] <= 1e-3 && d[1] <= 1e-3 && d[2] <= 5e-3;
        ok &= met;
        let _ = writeln!(
            md,
            "| {x} | {h:.4e} ({pvh:.4e}) | {v_n:.4e} ({pv:.4e}) | {h_n:.3e} ({ph:.3e}) | {:.1e} {} |",
            d.iter().cloned().fold(0.0, f64::max),
            if met { "" } else { "NOT MET" }
        );
    }
    Ok((ok, md))
}

/// The single particle against the finite-element continuum (`super::continuum`): Hertz, standard
/// and advanced MC (the frictionless Rust DEM at the paper's γ and MPR) and both nonlocal kernels,
/// with the static partners (kernel `none`, boussinesq × γ) that split a law's gap into the
/// relation it solves and the DEM's evaluation of it, as a report table, per-model metrics (`nrmse_{plate,side,side_platemean}_continuum`), the
/// curve's rows and a summary entry carrying the reference's own error bars.
fn continuum_section(
    refs: &[(KernelKind, Curve)],
    curves: &[(&str, Curve)],
    statics: &[(String, &Curve)],
    models: &mut Vec<ModelSummary>,
    rows: &mut Vec<Row>,
    md: &mut String,
) -> Result<(), String> {
    let cref = super::continuum::closest(NU_PARTICLE)?;
    let mut table = Vec::new();
    let named = curves
        .iter()
        .map(|(n, c)| (n.to_string(), c))
        .chain(refs.iter().map(|(k, c)| (format!("nonlocal_{}", k.name()), c)))
        .chain(statics.iter().map(|(n, c)| (n.clone(), *c)));
    for (name, c) in named {
        let e = cref.errors(c);
        if let Some(m) = models.iter_mut().find(|m| m.model.as_str() == name) {
            m.metrics.insert("nrmse_plate_continuum".into(), e.plate);
            m.metrics.insert("nrmse_side_continuum".into(), e.side);
            m.metrics.insert("nrmse_side_platemean_continuum".into(), e.side_plate_mean);
        }
        table.push((name, e));
    }
    md.push_str(&cref.markdown(NU_PARTICLE, &table));
    let name = cref.name();
    push_curve(rows, "single_particle", &name, "fem_finest_mesh", &cref.curve());
    for p in &cref.points {
        for (q, v) in [("plate_err_pa", p[2]), ("side_err_pa", p[4])] {
            rows.push(Row {
                case: "single_particle",
                model: name.clone().into(),
                params: "fem_finest_mesh".into(),
                x_name: "plate_disp_over_r".into(),
                x: p[0],
                quantity: q.into(),
                value: v,
            });
        }
    }
    let u = cref.own_uncertainty();
    models.push(ModelSummary {
        model: name.into(),
        nrmse: None,
        wall_time_s: 0.0,
        particle_steps_per_s: None,
        metrics: [
            ("nu".to_string(), cref.nu),
            ("error_bar_plate".to_string(), u.plate),
            ("error_bar_side".to_string(), u.side),
            ("error_bar_side_platemean".to_string(), u.side_plate_mean),
        ]
        .into_iter()
        .collect(),
    });
    Ok(())
}

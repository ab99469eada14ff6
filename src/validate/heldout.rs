//! `mcdem calibrate --heldout`: the per-ν advanced-MC calibration (`mcdem calibrate`, recorded in
//! `validation/reference/calibration_mcdem.csv`) measured on curves it was NOT fitted on, next to
//! its fit residual, against the same kind of reference (the nonlocal solution, the calibration's
//! kernel) with the same measure.
//!
//! The calibration fits γ, MPR (and E) to the second compression of the 514-sphere packing, so the
//! NRMSE the `uniaxial` case reports for the calibrated law is a fit residual. Per ν this module
//! runs the calibrated law, Hertz and (full mode) standard MC on:
//! - `fit`: that same second compression (the fit residual, recomputed; the file's own `nrmse` is
//!   printed beside it);
//! - `decompression`: the stroke back up after it. The nonlocal relation is elastic and
//!   frictionless and carries no history, so its unloading curve is its loading curve: the
//!   reference is the loading reference at the same φ;
//! - `first_compression`: the packing as read (before any cycle), against the nonlocal solution
//!   from that packing;
//! - `other_packing`: the second compression of another packing of the same particle population
//!   (`mcdem packing hydrogel`, seed 1, committed as `validation/cases/uniaxial/packing_514.data`;
//!   seed 2 is made when that is the packing the calibration ran on), from its own Hertz cycle;
//! - `bcc`, `single`: the App. B die scenes at the same ν (die_common.inc's `nu`, `E`), against the
//!   nonlocal die solution, with App. B's own values beside the calibrated ones;
//! - `single_fem`: the single sphere against the finite-element continuum, where an embedded
//!   curve has this ν (0.45; 0.499 for ν = 0.5).
//!
//! Uniaxial NRMSE as [`uniaxial::error`] (φ ≥ 0.66); die NRMSE as the die cases (plate and side,
//! the larger one in `nrmse`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::die;
use super::uniaxial::{self, Curve, Setup, GAMMA_LADDER};
use crate::harness::calibration::{parse_calibration, recorded, Fitted, Law};
use crate::harness::runner;
use crate::nonlocal::KernelKind;

#[derive(Debug, Clone)]
pub struct Options {
    pub quick: bool,
    /// Poisson ratios; empty: every ν of the calibration (quick: 0.5).
    pub nus: Vec<f64>,
    pub out: PathBuf,
    /// A calibration file in `calibration.csv`'s format; `None`: the built-in recorded one.
    pub calibration: Option<PathBuf>,
    /// Measure the other packing (`false`: its second compression is the `uniaxial` case on that
    /// packing, e.g. `validation/recorded/uniaxial_own_packing/`).
    pub other_packing: bool,
    /// A `validate` output's `uniaxial.csv` to take the fitted curve's nonlocal reference from
    /// instead of solving it again (same start state, same function).
    pub fit_reference: Option<PathBuf>,
}

/// App. B's advanced-MC and standard-MC values (single particle and bcc, ν = 0.5), the die
/// scenes' comparison rows.
const GAMMA_APP_B: f64 = 0.81;
const MPR_APP_B: f64 = 0.11;
const GAMMA_STANDARD_APP_B: f64 = 0.82;
/// The seed of the generator's packing used when the calibration ran on the seed-1 packing.
const OTHER_SEED: u64 = 2;
/// Largest |ν_FEM − ν| for which an embedded continuum curve stands for ν (0.499 for 0.5: the
/// element formulation needs ν < 0.5).
const FEM_NU_MATCH: f64 = 0.0015;

/// One NRMSE of the report.
#[derive(Debug, Clone, Serialize)]
pub struct Entry {
    pub nu: f64,
    /// `fit`, `decompression`, `hysteresis` (the decompression against the model's own loading
    /// curve), `first_compression`, `other_packing`, `bcc`, `single`, `single_fem`.
    pub curve: &'static str,
    /// The law was fitted on this curve.
    pub fitted: bool,
    /// `hertz`, `standard_mc`, `mc_advanced_calibrated`, `mc_advanced_app_b`.
    pub model: &'static str,
    pub params: String,
    /// NRMSE (die scenes: the larger of plate and side); NaN (JSON null) if the run stopped unstable.
    pub nrmse: f64,
    pub nrmse_plate: Option<f64>,
    pub nrmse_side: Option<f64>,
    /// Mean of the reference values the NRMSE was taken over (die scenes: the plate stress) [Pa].
    pub reference_mean: f64,
    /// Mean of the model's values at the same points [Pa]; with `reference_mean`, tells the
    /// curves apart (the decompression shares its reference with the fitted curve, not its model curve).
    pub model_mean: f64,
    /// Points compared.
    pub points: usize,
    /// Why a run gave no NRMSE (unstable), else empty.
    pub note: String,
}

/// The whole report: entries and the calibration's own residuals.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub calibration: String,
    pub quick: bool,
    pub kernel: String,
    pub packing: String,
    pub other_packing: String,
    /// Where the fitted curve's reference was read from (`None`: solved by this run).
    pub fit_reference: Option<String>,
    pub recorded: Vec<(f64, f64)>,
    pub entries: Vec<Entry>,
    pub wall_time_s: f64,
}

impl Report {
    pub fn get(&self, nu: f64, curve: &str, model: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| (e.nu - nu).abs() < 1e-12 && e.curve == curve && e.model == model)
    }
}

/// (NRMSE, mean of the reference, mean of the model, points) of a uniaxial model curve against
/// `reference`, at the points of [`uniaxial::error`], whose NRMSE it returns.
fn measured(model: &Curve, reference: &Curve) -> (f64, f64, f64, usize) {
    let used: Vec<(f64, f64)> = reference
        .iter()
        .filter(|p| p.0 >= uniaxial::PHI_MIN)
        .filter_map(|p| runner::interpolate(model, p.0).map(|m| (p.1, m)))
        .collect();
    let n = used.len().max(1) as f64;
    let (r, m) = used.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    (uniaxial::error(model, reference), r / n, m / n, used.len())
}

/// Everything one ν needs from the outside.
struct Ctx<'a> {
    s: &'a Setup,
    kind: KernelKind,
    dir: PathBuf,
    packing: &'a Path,
    say: &'a (dyn Fn(&str) + Sync),
    /// Run standard MC's γ ladder (full mode; several DEM runs per curve).
    standard: bool,
    /// The other packing's data file (`None`: that curve is not run).
    other: Option<&'a Path>,
    /// A `validate` `uniaxial.csv` holding the fitted curve's nonlocal reference.
    fit_reference: Option<&'a Path>,
    /// `heldout_entries.jsonl`: every entry as its stage ends, so a stopped run keeps them.
    journal: &'a std::sync::Mutex<std::fs::File>,
}

impl Ctx<'_> {
    fn journal(&self, out: &[Entry], from: usize) -> Result<(), String> {
        use std::io::Write;
        let mut text = String::new();
        for e in &out[from..] {
            text += &(serde_json::to_string(e).map_err(|e| e.to_string())? + "\n");
        }
        let mut f = self.journal.lock().map_err(|_| "journal lock poisoned".to_string())?;
        f.write_all(text.as_bytes()).map_err(|e| format!("cannot write heldout_entries.jsonl: {e}"))
    }
}

fn uniaxial_entry(
    nu: f64,
    curve: &'static str,
    model: &'static str,
    params: String,
    c: &Curve,
    refc: &Curve,
) -> Entry {
    let (nrmse, reference_mean, model_mean, points) = measured(c, refc);
    Entry { nrmse, reference_mean, model_mean, points, ..unstable(nu, curve, model, params, String::new()) }
}

/// An entry without a measurement (NaN NRMSE, no points): a run that went unstable, with `why`.
fn unstable(nu: f64, curve: &'static str, model: &'static str, params: String, why: String) -> Entry {
    Entry {
        nu,
        curve,
        fitted: curve == "fit",
        model,
        params,
        nrmse: f64::NAN,
        nrmse_plate: None,
        nrmse_side: None,
        reference_mean: f64::NAN,
        model_mean: f64::NAN,
        points: 0,
        note: why,
    }
}

/// Runs `law` from `data` (one stroke, or two when `refs` has a decompression entry) and adds its
/// entries; an unstable run is an entry with its cause, any other failure an error.
#[allow(clippy::too_many_arguments)]
fn run_law(
    nu: f64,
    ctx: &Ctx,
    law: Law,
    model: &'static str,
    params: String,
    data: &Path,
    compression: (&'static str, &Curve),
    decompression: Option<&'static str>,
    out: &mut Vec<Entry>,
) -> Result<bool, String> {
    (ctx.say)(&format!("ν = {nu}: {} {model} {params}", compression.0));
    let r = match decompression {
        Some(_) => uniaxial::cycle(law, nu, ctx.s, data).map(|(c, d, _)| (c, Some(d))),
        None => uniaxial::compress(law, nu, ctx.s, data).map(|(c, _)| (c, None)),
    };
    match r {
        Ok((c, d)) => {
            out.push(uniaxial_entry(nu, compression.0, model, params.clone(), &c, compression.1));
            if let (Some(name), Some(d)) = (decompression, d) {
                out.push(uniaxial_entry(nu, name, model, params.clone(), &d, compression.1));
                // The model's own hysteresis: its unloading against its loading. The elastic
                // reference has none, so this much of the decompression error is path
                // dissipation (damping, friction, rearrangement), not the law's elastic response.
                out.push(uniaxial_entry(nu, "hysteresis", model, params, &d, &c));
            }
            Ok(true)
        }
        Err(f) if f.instability.is_some() => {
            out.push(unstable(nu, compression.0, model, params, f.message));
            Ok(false)
        }
        Err(f) => Err(f.message),
    }
}

/// The models of one uniaxial curve: the calibrated law and Hertz, or (`standard`) standard MC at
/// the highest γ of the `uniaxial` case's ladder that runs stable on this curve (tried from the
/// top; the case climbs from the bottom to the same rung where stability is monotone in γ).
#[allow(clippy::too_many_arguments)]
fn uniaxial_curve(
    nu: f64,
    ctx: &Ctx,
    fitted: &Fitted,
    data: &Path,
    compression: (&'static str, &Curve),
    decompression: Option<&'static str>,
    standard: bool,
    out: &mut Vec<Entry>,
) -> Result<(), String> {
    if !standard {
        let l = fitted.law;
        let p = format!("gamma={} mpr={} E={}", l.gamma, l.mpr, l.youngs_modulus);
        run_law(nu, ctx, l, "mc_advanced_calibrated", p, data, compression, decompression, out)?;
        run_law(nu, ctx, Law::HERTZ, "hertz", String::new(), data, compression, decompression, out)?;
        return Ok(());
    }
    for g in GAMMA_LADDER.iter().rev() {
        let mut tried = Vec::new();
        let p = format!("gamma={g}");
        let law = Law::standard(*g);
        if run_law(nu, ctx, law, "standard_mc", p, data, compression, decompression, &mut tried)? {
            out.extend(tried);
            return Ok(());
        }
    }
    out.push(unstable(
        nu,
        compression.0,
        "standard_mc",
        String::new(),
        "no γ of the ladder ran stable".into(),
    ));
    Ok(())
}

/// The die scenes at ν: Hertz, standard MC and advanced MC at App. B's values, and the calibrated law,
/// against the nonlocal die solution (kernel of the calibration) and, for the single sphere, the
/// finite-element continuum where a curve of this ν is embedded.
fn die_curves(nu: f64, ctx: &Ctx, fitted: &Fitted, out: &mut Vec<Entry>) -> Result<(), String> {
    let fem = super::continuum::closest(nu)?;
    let fem = ((fem.nu - nu).abs() <= FEM_NU_MATCH).then_some(fem);
    let l = fitted.law;
    let laws: [(&'static str, Law, String); 4] = [
        ("hertz", Law::HERTZ, String::new()),
        ("standard_mc", Law::standard(GAMMA_STANDARD_APP_B), format!("gamma={GAMMA_STANDARD_APP_B}")),
        (
            "mc_advanced_app_b",
            Law::advanced(GAMMA_APP_B, MPR_APP_B),
            format!("gamma={GAMMA_APP_B} mpr={MPR_APP_B}"),
        ),
        ("mc_advanced_calibrated", l, format!("gamma={} mpr={} E={}", l.gamma, l.mpr, l.youngs_modulus)),
    ];
    for (curve, scene) in [("bcc", die::bcc()), ("single", die::single())] {
        (ctx.say)(&format!("ν = {nu}: {curve} die"));
        let (refc, _) = die::nonlocal_nu(&scene, ctx.kind, 1.0, nu)?;
        for (model, law, params) in &laws {
            let run = match runner::run_rust(scene.deck, &die::law_vars(*law, nu)) {
                Ok(r) => r,
                Err(f) if f.instability.is_some() => {
                    out.push(unstable(nu, curve, model, params.clone(), f.message));
                    continue;
                }
                Err(f) => return Err(f.message),
            };
            let c = die::curve_of(&run, scene.side)?;
            // Plate stresses of the reference and the model where `die::errors` compares them.
            let plate: Curve = c.iter().map(|p| (p.0, p.1)).collect();
            let (r, m) = refc
                .iter()
                .filter(|p| p.0 > 1e-9)
                .filter_map(|p| runner::interpolate(&plate, p.0).map(|m| (p.1, m)))
                .fold((Vec::new(), Vec::new()), |mut a, p| {
                    a.0.push(p.0);
                    a.1.push(p.1);
                    a
                });
            let n = r.len();
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
            let (pl, sd) = die::errors(&c, &refc);
            out.push(Entry {
                nu,
                curve,
                fitted: false,
                model,
                params: params.clone(),
                nrmse: pl.max(sd),
                nrmse_plate: Some(pl),
                nrmse_side: Some(sd),
                reference_mean: mean(&r),
                model_mean: mean(&m),
                points: n,
                note: String::new(),
            });
            if let (Some(fem), "single") = (&fem, curve) {
                let e = fem.errors(&c);
                let at: Vec<f64> =
                    fem.points.iter().filter_map(|p| runner::interpolate(&plate, p[0])).collect();
                out.push(Entry {
                    nu,
                    curve: "single_fem",
                    fitted: false,
                    model,
                    params: params.clone(),
                    nrmse: e.plate.max(e.side),
                    nrmse_plate: Some(e.plate),
                    nrmse_side: Some(e.side),
                    reference_mean: fem.points.iter().map(|p| p[1]).sum::<f64>() / fem.points.len() as f64,
                    model_mean: mean(&at),
                    points: fem.points.len(),
                    note: format!("{} nu {}", fem.law, fem.nu),
                });
            }
        }
    }
    Ok(())
}

fn per_nu(nu: f64, ctx: &Ctx, fitted: &Fitted) -> Result<Vec<Entry>, String> {
    let mut out = Vec::new();
    let (s, kind) = (ctx.s, ctx.kind);
    // Cheapest first, each stage's entries to the journal as it ends: the fitted curve and the
    // stroke back up (the calibration's start state and reference), the die scenes, the first
    // compression, the other packing, then standard MC's γ ladders (several runs per curve).
    let (dump, data) = uniaxial::start_state(nu, s, &ctx.dir.join("fit"))?;
    let refc = match ctx.fit_reference {
        Some(file) => recorded_reference(file, nu, kind)?,
        None => {
            (ctx.say)(&format!("ν = {nu}: nonlocal reference of the fitted curve"));
            uniaxial::reference(&dump, nu, kind, s.nonlocal_steps, &mut |_| {})?.0
        }
    };
    uniaxial_curve(nu, ctx, fitted, &data, ("fit", &refc), Some("decompression"), false, &mut out)?;
    ctx.journal(&out, 0)?;
    let done = out.len();
    die_curves(nu, ctx, fitted, &mut out)?;
    ctx.journal(&out, done)?;
    let done = out.len();
    // The first compression: the packing as read, and the nonlocal solution from it.
    (ctx.say)(&format!("ν = {nu}: nonlocal reference of the first compression"));
    let (ref1, _) = uniaxial::reference_from_data(ctx.packing, nu, kind, s.nonlocal_steps, &mut |_| {})?;
    let first = ("first_compression", &ref1);
    uniaxial_curve(nu, ctx, fitted, ctx.packing, first, None, false, &mut out)?;
    ctx.journal(&out, done)?;
    let done = out.len();
    // Another packing, second compression from its own Hertz cycle.
    let other = match ctx.other {
        Some(p) => {
            let (dump2, data2) = uniaxial::start_state_from(nu, s, &ctx.dir.join("other"), p)?;
            (ctx.say)(&format!("ν = {nu}: nonlocal reference of the other packing"));
            let (ref2, _) = uniaxial::reference(&dump2, nu, kind, s.nonlocal_steps, &mut |_| {})?;
            uniaxial_curve(nu, ctx, fitted, &data2, ("other_packing", &ref2), None, false, &mut out)?;
            ctx.journal(&out, done)?;
            Some((data2, ref2))
        }
        None => None,
    };
    if ctx.standard {
        let done = out.len();
        uniaxial_curve(nu, ctx, fitted, &data, ("fit", &refc), Some("decompression"), true, &mut out)?;
        uniaxial_curve(nu, ctx, fitted, ctx.packing, first, None, true, &mut out)?;
        if let Some((data2, ref2)) = &other {
            uniaxial_curve(nu, ctx, fitted, data2, ("other_packing", ref2), None, true, &mut out)?;
        }
        ctx.journal(&out, done)?;
    }
    Ok(out)
}

/// The nonlocal curve of ν (kernel `kind`) from a `validate` output's `uniaxial.csv`: the
/// `uniaxial` case's reference of the same start state, computed by the same function.
fn recorded_reference(file: &Path, nu: f64, kind: KernelKind) -> Result<Curve, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    let (model, params) = (format!("nonlocal_{}", kind.name()), format!("nu={nu}"));
    let mut c = Curve::new();
    for (i, l) in text.lines().enumerate() {
        let f: Vec<&str> = l.split(',').collect();
        if f.len() == 7 && f[1] == model && f[2] == params && f[3] == "phi" {
            let num = |k: usize| {
                f[k].parse::<f64>().ok().filter(|v| v.is_finite()).ok_or(format!(
                    "{}:{}: '{}' is not a number",
                    file.display(),
                    i + 1,
                    f[k]
                ))
            };
            c.push((num(4)?, num(6)?));
        }
    }
    if c.len() < 2 {
        return Err(format!("{}: no {model} curve for {params}", file.display()));
    }
    Ok(c)
}

/// Runs the held-out check for every ν of `opts` (two at a time, one per core) and writes
/// `heldout.csv`, `heldout.json` and `heldout.md` into `opts.out`.
pub fn run(opts: &Options) -> Result<Report, String> {
    let t = Instant::now();
    let (fits, source) = match &opts.calibration {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| format!("cannot read {}: {e}", p.display()))?;
            (parse_calibration(&text, &p.display().to_string())?, p.display().to_string())
        }
        None => (recorded(), "validation/reference/calibration_mcdem.csv (built in)".to_string()),
    };
    let s = uniaxial::setup(opts.quick);
    let nus: Vec<f64> = if !opts.nus.is_empty() {
        opts.nus.clone()
    } else if opts.quick {
        vec![0.5]
    } else {
        fits.iter().map(|f| f.nu).collect()
    };
    let mut chosen = Vec::new();
    for &nu in &nus {
        let f = fits
            .iter()
            .find(|f| (f.nu - nu).abs() < 1e-9)
            .ok_or(format!("{source}: no row for nu = {nu}"))?;
        chosen.push(*f);
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| format!("cannot create {}: {e}", opts.out.display()))?;
    let scratch = runner::Scratch::new()?;
    let (packing, which) = uniaxial::packing();
    let shipped = super::packing::shipped();
    let other = if packing != shipped {
        (shipped.clone(), format!("{} (mcdem packing hydrogel --seed 1)", shipped.display()))
    } else {
        let p = scratch.0.join(format!("packing_seed{OTHER_SEED}.data"));
        super::packing::make(OTHER_SEED, &p)?;
        (p, format!("mcdem packing hydrogel --seed {OTHER_SEED} (made by this run)"))
    };
    let say = |l: &str| eprintln!("heldout: {l}");
    let jp = opts.out.join("heldout_entries.jsonl");
    let journal = std::sync::Mutex::new(
        std::fs::File::create(&jp).map_err(|e| format!("cannot create {}: {e}", jp.display()))?,
    );
    let results: Vec<Result<Vec<Entry>, String>> = chosen
        .par_iter()
        .map(|f| {
            let ctx = Ctx {
                s: &s,
                kind: s.kernel,
                dir: scratch.0.join(format!("nu{}", f.nu)),
                packing: &packing,
                other: opts.other_packing.then_some(other.0.as_path()),
                fit_reference: opts.fit_reference.as_deref(),
                journal: &journal,
                say: &say,
                standard: !opts.quick,
            };
            per_nu(f.nu, &ctx, f)
        })
        .collect();
    let mut entries = Vec::new();
    for r in results {
        entries.extend(r?);
    }
    let report = Report {
        calibration: source,
        quick: opts.quick,
        kernel: s.kernel.name().to_string(),
        packing: which.to_string(),
        other_packing: if opts.other_packing { other.1 } else { format!("not measured here ({})", other.1) },
        fit_reference: opts.fit_reference.as_ref().map(|p| p.display().to_string()),
        recorded: chosen.iter().map(|f| (f.nu, f.nrmse)).collect(),
        entries,
        wall_time_s: t.elapsed().as_secs_f64(),
    };
    super::heldout_report::write(&report, &chosen, &opts.out)?;
    Ok(report)
}

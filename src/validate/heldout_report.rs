//! The files of `mcdem calibrate --heldout` (module `heldout`): `heldout.csv` (one NRMSE per
//! line), `heldout.json` (the whole report) and `heldout.md` (the tables).

use std::fmt::Write as _;
use std::path::Path;

use super::heldout::{Entry, Report};
use crate::harness::calibration::Fitted;

/// The uniaxial curves, fitted one first, with the phrase the report uses.
const UNIAXIAL: [(&str, &str); 5] = [
    ("fit", "second compression (fitted)"),
    ("decompression", "decompression after it (reference: the loading curve)"),
    ("hysteresis", "decompression vs the model's own loading curve"),
    ("first_compression", "first compression of the packing as read"),
    ("other_packing", "second compression of the other packing"),
];
const DIES: [(&str, &str); 3] = [
    ("bcc", "bcc die vs nonlocal"),
    ("single", "single sphere vs nonlocal"),
    ("single_fem", "single sphere vs finite elements"),
];

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.2} %", 100.0 * x)
    } else {
        "unstable".into()
    }
}

fn plate_side(e: &Entry) -> String {
    match (e.nrmse_plate, e.nrmse_side) {
        (Some(p), Some(s)) => format!("{} / {}", pct(p), pct(s)),
        _ => pct(e.nrmse),
    }
}

pub(super) fn write(r: &Report, fits: &[Fitted], out: &Path) -> Result<(), String> {
    let io = |p: &Path, e: std::io::Error| format!("cannot write {}: {e}", p.display());
    let mut csv = String::from(
        "nu,curve,fitted,model,params,nrmse,nrmse_plate,nrmse_side,reference_mean,model_mean,points,note\n",
    );
    let opt = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6e}"));
    for e in &r.entries {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:.6e},{},{},{:.6e},{:.6e},{},{}",
            e.nu,
            e.curve,
            e.fitted,
            e.model,
            e.params,
            e.nrmse,
            opt(e.nrmse_plate),
            opt(e.nrmse_side),
            e.reference_mean,
            e.model_mean,
            e.points,
            e.note.replace([',', '\n'], ";")
        );
    }
    let p = out.join("heldout.csv");
    std::fs::write(&p, csv).map_err(|e| io(&p, e))?;
    let p = out.join("heldout.json");
    std::fs::write(&p, serde_json::to_string_pretty(r).map_err(|e| e.to_string())?).map_err(|e| io(&p, e))?;
    let p = out.join("heldout.md");
    std::fs::write(&p, markdown(r, fits)).map_err(|e| io(&p, e))
}

fn markdown(r: &Report, fits: &[Fitted]) -> String {
    let mut md = format!(
        "# Held-out check of the advanced-MC calibration\n\n\
         Calibration: {}. {} mode, reference kernel `{}`. Packing the calibration was fitted on: {}; other \
         packing: {}. Fitted curve's reference: {}. Wall time {:.0} s.\n\n\
         NRMSE of the calibrated law against the nonlocal reference (uniaxial: over φ ≥ 0.66; die scenes: \
         plate / side wall over Δ/r = 0.01 … 0.3). The decompression's reference is the loading reference \
         (the nonlocal relation is elastic, frictionless and history-free).\n\n\
         | ν | γ, MPR, E [Pa] | fit residual: recorded / now |",
        r.calibration,
        if r.quick { "Quick (4× piston speed, a smoke test)" } else { "Full" },
        r.kernel,
        r.packing,
        r.other_packing,
        r.fit_reference.as_deref().map_or("solved by this run".to_string(), |f| format!("read from {f}")),
        r.wall_time_s
    );
    for (_, t) in UNIAXIAL.iter().skip(1).chain(&DIES) {
        let _ = write!(md, " {t} |");
    }
    let _ = writeln!(md, " largest held-out uniaxial / fit |\n|{}", "---|".repeat(11));
    for f in fits {
        let get = |c: &str| r.get(f.nu, c, "mc_advanced_calibrated");
        let fit = get("fit").map_or(f64::NAN, |e| e.nrmse);
        let _ = write!(
            md,
            "| {} | {:.3}, {:.3}, {:.4e} | {} / {} |",
            f.nu,
            f.law.gamma,
            f.law.mpr,
            f.law.youngs_modulus,
            pct(f.nrmse),
            pct(fit)
        );
        let mut worst = f64::NEG_INFINITY;
        for (c, _) in UNIAXIAL.iter().skip(1) {
            // A curve not measured (e.g. --skip-other-packing) is a dash, not an instability.
            let Some(v) = get(c).map(|e| e.nrmse) else {
                md.push_str(" — |");
                continue;
            };
            // The hysteresis is the model against itself, not a held-out error.
            if *c != "hysteresis" {
                worst = worst.max(if v.is_finite() { v } else { f64::INFINITY });
            }
            let _ = write!(md, " {} |", pct(v));
        }
        for (c, _) in DIES {
            let _ = write!(md, " {} |", get(c).map_or("—".into(), plate_side));
        }
        let _ = writeln!(md, " {:.2} |", worst / fit);
    }
    let _ = writeln!(
        md,
        "\nThe ordering advanced MC (calibrated) < standard MC < Hertz on every curve (uniaxial: standard MC at \
         the highest stable γ of the ladder on that curve; die scenes: App. B's γ = 0.82, with App. B's \
         advanced-MC values γ = 0.81, MPR = 0.11 beside):\n\n\
         | ν | curve | Hertz | standard MC | advanced MC, App. B | advanced MC, calibrated | ordering |\n|---|---|---|---|---|---|---|"
    );
    for f in fits {
        for (c, t) in UNIAXIAL.iter().chain(&DIES) {
            let get = |m: &str| r.get(f.nu, c, m);
            let Some(cal) = get("mc_advanced_calibrated") else { continue };
            let (h, st, b) = (get("hertz"), get("standard_mc"), get("mc_advanced_app_b"));
            let v = |e: Option<&Entry>| e.map_or(f64::NAN, |e| e.nrmse);
            let ordering = match st {
                _ if *c == "hysteresis" => "— (each model against itself)",
                Some(st) => {
                    if cal.nrmse < st.nrmse && st.nrmse < v(h) {
                        "yes"
                    } else {
                        "NO"
                    }
                }
                None => "— (no standard MC run)",
            };
            let _ = writeln!(
                md,
                "| {} | {t} | {} | {} | {} | {} | {ordering} |",
                f.nu,
                h.map_or("—".into(), plate_side),
                st.map_or("—".into(), |e| format!("{} ({})", plate_side(e), e.params)),
                b.map_or("—".into(), plate_side),
                plate_side(cal)
            );
        }
    }
    let notes: Vec<&Entry> =
        r.entries.iter().filter(|e| !e.note.is_empty() && !e.nrmse.is_finite()).collect();
    for e in notes {
        let _ = writeln!(md, "- unstable: ν = {}, {} {} {}: {}", e.nu, e.curve, e.model, e.params, e.note);
    }
    md
}

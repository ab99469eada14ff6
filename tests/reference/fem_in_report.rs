//! `mcdem validate --case single_particle --quick`: the finite-element continuum reference of the
//! single sphere in the die is embedded and reported next to the nonlocal one.

use assert_cmd::Command;
use serde_json::Value;

/// Best plate NRMSE against the continuum that some model must reach. Measured: nonlocal `sphere`
/// 0.81 % against the ν = 0.499 curve the case uses (its 12-interval file; 1.89 % against the
/// earlier 9-interval file, 1.61 % against ν = 0.49); the next best model, standard MC's static
/// fixed point, 6.4 %, and the DEM laws 12.6–19.2 %. 3 % lies above the measured value plus the
/// curve's own RMS error bar (0.8 + 1.9 %) and below half the next best model: the kernel that
/// matches the continuum passes, a regression to the laws' level does not.
const BEST_PLATE_NRMSE: f64 = 0.03;

#[test]
fn single_particle_reports_the_continuum_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    Command::cargo_bin("mcdem")
        .unwrap()
        .args(["validate", "--quick", "--case", "single_particle", "--out"])
        .arg(&out)
        .assert()
        .success();
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let case = summary["cases"].as_array().unwrap().iter().find(|c| c["name"] == "single_particle").unwrap();
    let models = case["models"].as_array().unwrap();
    // The reference itself: a summary entry with its ν and finite error bars.
    let reference = models.iter().find(|m| m["model"].as_str().unwrap().starts_with("continuum_")).unwrap();
    let nu = reference["metrics"]["nu"].as_f64().unwrap();
    assert!((0.45..=0.5).contains(&nu), "{reference}");
    for k in ["error_bar_plate", "error_bar_side", "error_bar_side_platemean"] {
        let v = reference["metrics"][k].as_f64().unwrap();
        assert!(v.is_finite() && v >= 0.0, "{k}: {reference}");
    }
    // Every model against it, plate and side with both normalisations, finite.
    let mut best = f64::INFINITY;
    for name in ["hertz", "standard_mc", "mc_advanced", "nonlocal_sphere", "nonlocal_boussinesq"] {
        let m = models.iter().find(|m| m["model"] == name).unwrap_or_else(|| panic!("{name} missing"));
        for k in ["nrmse_plate_continuum", "nrmse_side_continuum", "nrmse_side_platemean_continuum"] {
            let v = m["metrics"][k].as_f64().unwrap_or_else(|| panic!("{name}: no {k}"));
            assert!(v.is_finite() && v >= 0.0, "{name} {k}: {v}");
        }
        best = best.min(m["metrics"]["nrmse_plate_continuum"].as_f64().unwrap());
    }
    assert!(best <= BEST_PLATE_NRMSE, "best plate NRMSE vs the continuum {best} > {BEST_PLATE_NRMSE}");
    // Its curve and error bars are rows of the case's CSV, and a table in the report.
    let csv = std::fs::read_to_string(out.join("single_particle.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().filter(|l| l.contains(",continuum_")).collect();
    for q in ["plate_stress_pa", "side_stress_pa", "plate_err_pa", "side_err_pa"] {
        let vals: Vec<f64> = rows
            .iter()
            .filter(|l| l.contains(&format!(",{q},")))
            .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
            .collect();
        assert!(vals.len() >= 10 && vals.iter().all(|v| v.is_finite()), "{q}: {vals:?}");
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("Against the finite-element continuum"), "no continuum table in the report");
}

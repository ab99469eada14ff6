//! `mcdem contacts`: what a user sees. The output schema, values checked against the closed form
//! on a sphere (not against the code under test), and one-line errors with exit code 2.

use assert_cmd::Command;
use serde_json::Value;

fn mcdem() -> Command {
    Command::cargo_bin("mcdem").unwrap()
}

fn run_ok(input: &str) -> Value {
    let out = mcdem().args(["contacts", "-"]).write_stdin(input).assert().success().get_output().clone();
    serde_json::from_slice(&out.stdout).unwrap()
}

fn run_err(input: &str) -> String {
    let out = mcdem().args(["contacts", "-"]).write_stdin(input).assert().code(2).get_output().clone();
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one-line error expected, got:\n{err}");
    assert!(out.stdout.is_empty());
    err
}

const TWO_ANTIPODAL: &str = r#"{"radius": 0.001, "youngs_modulus": 23300.0, "poisson_ratio": 0.5, "gamma": 0.81,
  "contacts": [{"point": [0.0, 0.0, -0.00095], "force": 0.0012}, {"point": [0.0, 0.0, 0.00095], "force": 0.0012},
               {"point": [0.00095, 0.0, 0.0], "force": 0.0}]}"#;

#[test]
fn standard_mc_matches_closed_form_on_a_sphere() {
    let v = run_ok(TWO_ANTIPODAL);
    let delta: Vec<f64> = v["delta"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let fb: Vec<bool> =
        v["hertz_fallback"].as_array().unwrap().iter().map(|x| x.as_bool().unwrap()).collect();
    assert_eq!(fb, vec![false; 3]);
    // Antipodal pair: s = 1, d = 2·0.95 mm, B = 2ν − 3 = −2 → δ = +γ(1+ν)F·2/(2πE d).
    let (g, nu, e, f, d) = (0.81, 0.5, 23300.0, 0.0012, 0.0019);
    let antipodal = -g * (1.0 + nu) * f / (2.0 * std::f64::consts::PI * e * d) * (2.0 * nu - 3.0);
    for x in &delta[..2] {
        assert!((x - antipodal).abs() <= 1e-12 * antipodal, "{x} vs {antipodal}");
    }
    // Contact at 90° from both: s = sin 45°, d = √2·0.95 mm, B(s) = 2(1−ν) + 2(1−2ν)s − (7−8ν)s² = 1 − 1.5 = −0.5.
    let d90 = 2f64.sqrt() * 0.00095;
    let side = 2.0 * (-g * (1.0 + nu) * f / (2.0 * std::f64::consts::PI * e * d90) * -0.5);
    assert!((delta[2] - side).abs() <= 1e-12 * side.abs(), "{} vs {side}", delta[2]);
}

#[test]
fn advanced_mc_cap_switches_contacts_to_hertz() {
    // Terms (see the closed forms above): antipodal +1.05e-5 m = 0.0105 r each way; the side
    // contact receives +3.7e-6 m = 0.0037 r from each of the two loaded contacts (B = −0.5 at 90°).
    let with_mpr = |mpr: f64, test: &str| {
        TWO_ANTIPODAL.replace(
            "\"gamma\": 0.81,",
            &format!("\"gamma\": 0.81, \"mpr\": {mpr}, \"mpr_test\": \"{test}\","),
        )
    };
    let flags = |mpr: f64, test: &str| run_ok(&with_mpr(mpr, test))["hertz_fallback"].clone();
    assert_eq!(flags(0.003, "abs"), serde_json::json!([true, true, true]));
    assert_eq!(flags(0.005, "abs"), serde_json::json!([true, true, false]));
    assert_eq!(flags(0.02, "abs"), serde_json::json!([false, false, false]));
    // Every term here is growth, so `signed` trips like `abs`.
    assert_eq!(flags(0.003, "signed"), serde_json::json!([true, true, true]));
    // Two loaded contacts 20° apart shrink each other (B > 0): `abs` trips, `signed` never does.
    let near = r#"{"radius": 0.001, "youngs_modulus": 23300.0, "poisson_ratio": 0.5, "gamma": 0.81, "mpr": 0.001,
      "mpr_test": "TEST", "contacts": [{"point": [0.0, 0.0, -0.00095], "force": 0.0012},
      {"point": [0.000324919, 0.0, -0.000892708], "force": 0.0012}]}"#;
    let abs = run_ok(&near.replace("TEST", "abs"));
    assert_eq!(abs["hertz_fallback"], serde_json::json!([true, true]));
    let signed = run_ok(&near.replace("TEST", "signed"));
    assert_eq!(signed["hertz_fallback"], serde_json::json!([false, false]));
    assert!(
        signed["delta"][0].as_f64().unwrap() < -0.001 * 0.001,
        "shrinkage beyond MPR·r is kept by `signed`"
    );
    let tripped = run_ok(&with_mpr(0.005, "abs"));
    assert_eq!(tripped["delta"][0], serde_json::json!(0.0));
    // The side contact keeps its full correction (both terms), not a partial sum.
    assert_eq!(tripped["delta"][2], run_ok(TWO_ANTIPODAL)["delta"][2]);
    assert_eq!(run_ok(&with_mpr(0.02, "abs"))["delta"], run_ok(TWO_ANTIPODAL)["delta"]);
}

#[test]
fn reads_a_file_argument() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.json");
    std::fs::write(&path, TWO_ANTIPODAL).unwrap();
    let out = mcdem().arg("contacts").arg(&path).assert().success().get_output().stdout.clone();
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v, run_ok(TWO_ANTIPODAL));
    let missing =
        mcdem().args(["contacts", "/nonexistent/p.json"]).assert().code(2).get_output().stderr.clone();
    assert!(String::from_utf8(missing).unwrap().contains("cannot read /nonexistent/p.json"));
}

#[test]
fn bad_input_gives_one_line_errors_naming_the_problem() {
    assert!(run_err("{not json").contains("invalid input JSON"));
    assert!(run_err(r#"{"radius": 0.001, "youngs_modulus": 1e4, "gamma": 1.0, "contacts": []}"#)
        .contains("poisson_ratio"));
    let base = TWO_ANTIPODAL;
    assert!(
        run_err(&base.replace("\"poisson_ratio\": 0.5", "\"poisson_ratio\": 0.6")).contains("poisson_ratio")
    );
    assert!(run_err(&base.replace("\"gamma\": 0.81", "\"gamma\": -0.81")).contains("gamma"));
    assert!(run_err(&base.replace("\"gamma\": 0.81", "\"gamma\": 0.81, \"mpr\": -0.1")).contains("mpr"));
    assert!(run_err(
        &base.replace("\"gamma\": 0.81", "\"gamma\": 0.81, \"mpr\": 0.1, \"mpr_test\": \"both\"")
    )
    .contains("mprTest"));
    assert!(run_err(&base.replace("\"radius\": 0.001", "\"radius\": 0.0")).contains("radius"));
    assert!(run_err(&base.replace("\"radius\": 0.001", "\"radius\": 1e999")).contains("invalid input JSON"));
    assert!(run_err(&base.replace("\"force\": 0.0}", "\"force\": -1.0}")).contains("contacts[2].force"));
    assert!(run_err(&base.replace("\"gamma\"", "\"gama\"")).contains("gama"));
}

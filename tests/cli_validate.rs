//! `mcdem validate --quick`: the README's main job runs and writes its report contract.

use assert_cmd::Command;
use serde_json::Value;

#[test]
fn quick_validation_writes_the_report_contract() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    Command::cargo_bin("mcdem").unwrap().args(["validate", "--quick", "--out"]).arg(&out).assert().success();
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let cases = summary["cases"].as_array().unwrap();
    let names: Vec<&str> = cases.iter().map(|c| c["name"].as_str().unwrap()).collect();
    for expected in ["physics_checks", "hard_cases"] {
        assert!(names.contains(&expected), "{expected} missing from {names:?}");
    }
    for c in cases {
        assert_eq!(c["passed"], Value::Bool(true), "{c}");
        assert!(c["wall_time_s"].as_f64().unwrap().is_finite());
        let name = c["name"].as_str().unwrap();
        let csv = std::fs::read_to_string(out.join(format!("{name}.csv"))).unwrap();
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some("case,model,params,x_name,x,quantity,value"));
        assert!(lines.next().is_some(), "{name}.csv has no rows");
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## hard_cases"));
}

#[test]
fn unknown_case_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("mcdem")
        .unwrap()
        .args(["validate", "--case", "nope", "--out"])
        .arg(dir.path())
        .assert()
        .code(2)
        .get_output()
        .stderr
        .clone();
    let err = String::from_utf8(out).unwrap();
    assert!(err.contains("unknown case 'nope'") && err.contains("hard_cases"), "{err}");
}

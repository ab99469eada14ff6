//! Progress of long commands on standard error when it is not a terminal (here a pipe): plain
//! lines `validate: i/n done, running CASE, …` at most once per interval (10 s by default,
//! `MCDEM_PROGRESS_INTERVAL` seconds otherwise).

use std::time::Instant;

use assert_cmd::Command;

/// Runs `mcdem validate --quick --case CASE` with `interval` as MCDEM_PROGRESS_INTERVAL (unset
/// for `None`); returns its standard error and its wall time [s].
fn validate(case: &str, interval: Option<&str>) -> (String, f64) {
    let dir = tempfile::tempdir().unwrap();
    let mut c = Command::cargo_bin("mcdem").unwrap();
    c.args(["validate", "--quick", "--case", case, "--out"]).arg(dir.path().join("report"));
    match interval {
        Some(v) => c.env("MCDEM_PROGRESS_INTERVAL", v),
        None => c.env_remove("MCDEM_PROGRESS_INTERVAL"),
    };
    let t = Instant::now();
    let out = c.output().unwrap();
    let secs = t.elapsed().as_secs_f64();
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(out.status.success(), "{err}");
    (err, secs)
}

/// The periodic progress lines of a standard error.
fn progress_lines(err: &str) -> Vec<&str> {
    err.lines().filter(|l| l.starts_with("validate: ") && l.contains(" s elapsed")).collect()
}

#[test]
fn short_interval_gives_periodic_lines_with_case_and_count() {
    // single_particle takes about 2 s in quick mode: several lines at 0.3 s.
    let (err, secs) = validate("single_particle", Some("0.3"));
    let lines = progress_lines(&err);
    let named: Vec<&&str> =
        lines.iter().filter(|l| l.contains("0/1 done") && l.contains("running single_particle")).collect();
    assert!(named.len() >= 2, "{secs:.1} s, lines {lines:?} in\n{err}");
}

#[test]
fn default_interval_limits_the_rate() {
    // At most one line per 10 s: none in a run shorter than that.
    let (err, secs) = validate("single_particle", None);
    let lines = progress_lines(&err);
    assert!(lines.len() <= (secs / 10.0) as usize, "{secs:.1} s, lines {lines:?}");
}

#[test]
fn bad_interval_is_ignored_with_a_warning() {
    let (err, _) = validate("physics_checks", Some("soon"));
    assert!(
        err.contains("warning: MCDEM_PROGRESS_INTERVAL='soon' is not a number of seconds > 0; using 10 s"),
        "{err}"
    );
}

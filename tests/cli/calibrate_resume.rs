//! `mcdem calibrate` resumes from its journal: a run stopped after some ν were fitted and started
//! again fits only the missing ν and returns the same fits, bit for bit, as an uninterrupted run.
//!
//! The per-ν fit is a stand-in here: the smallest real setting (`--quick`, one ν) runs tens of
//! 514-particle compressions and a nonlocal reference, minutes of machine time, while the resume
//! logic (journal, what is taken from it, what is fitted, the order of the result) does not depend
//! on what the fit computes. The stand-in returns values with full 17-digit mantissas, so that a
//! journal that did not round-trip f64 exactly would show.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use mcdem::validate::calibrate::{fit_resumable, Fit};

const NUS: [f64; 3] = [0.25, 0.3, 0.5];

/// A deterministic fit of ν whose fields use every digit of an f64.
fn stand_in(nu: f64) -> Fit {
    Fit {
        nu,
        gamma: (7.3 * nu).sin().abs() + 0.1,
        mpr: (nu / 3.0).sqrt() * 0.123_456_789,
        youngs_modulus_pa: 23.3e3 * (1.0 + nu).ln().exp2(),
        nrmse: 1.0 / (3.0 + nu * 17.0),
        hertz_nrmse: (nu * 1e-3).atan() + 1e-300,
        evaluations: (nu * 100.0) as usize,
        wall_time_s: 0.1 + 0.2 * nu,
    }
}

fn bits(f: &Fit) -> [u64; 8] {
    [
        f.nu.to_bits(),
        f.gamma.to_bits(),
        f.mpr.to_bits(),
        f.youngs_modulus_pa.to_bits(),
        f.nrmse.to_bits(),
        f.hertz_nrmse.to_bits(),
        f.evaluations as u64,
        f.wall_time_s.to_bits(),
    ]
}

/// `fit_resumable` over [`NUS`] with the stand-in, failing for the ν in `fail` (a run stopped
/// while fitting them); returns the result and the ν fitted.
fn run(journal: &Path, fail: &[f64]) -> (Result<Vec<Fit>, String>, Vec<f64>) {
    let fitted = Mutex::new(Vec::new());
    let calls = AtomicUsize::new(0);
    let fit = |nu: f64| {
        calls.fetch_add(1, Ordering::Relaxed);
        fitted.lock().unwrap().push(nu);
        if fail.contains(&nu) {
            Err(format!("ν = {nu}: stopped"))
        } else {
            Ok(stand_in(nu))
        }
    };
    let r = fit_resumable(&NUS, journal, &fit, &|_| {});
    let mut f = fitted.into_inner().unwrap();
    f.sort_by(f64::total_cmp);
    assert_eq!(calls.load(Ordering::Relaxed), f.len());
    (r, f)
}

#[test]
fn a_resumed_calibration_equals_an_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, fitted) = run(&dir.path().join("whole.jsonl"), &[]);
    let whole = whole.unwrap();
    assert_eq!(fitted, NUS);
    let journal = dir.path().join("resumed.jsonl");
    // Stopped while fitting ν = 0.5: the error reaches the caller, ν = 0.25 and 0.3 are journaled.
    let (first, fitted) = run(&journal, &[0.5]);
    assert!(first.unwrap_err().contains("ν = 0.5"));
    assert_eq!(fitted, NUS);
    assert_eq!(std::fs::read_to_string(&journal).unwrap().lines().count(), 2);
    // Started again: only ν = 0.5 is fitted, and the result is the uninterrupted one.
    let (resumed, fitted) = run(&journal, &[]);
    let resumed = resumed.unwrap();
    assert_eq!(fitted, [0.5], "the journaled ν must not be fitted again");
    assert_eq!(resumed.iter().map(|f| f.nu).collect::<Vec<_>>(), NUS, "sorted by ν");
    for (a, b) in whole.iter().zip(&resumed) {
        assert_eq!(bits(a), bits(b), "ν = {}: {a:?} vs {b:?}", a.nu);
    }
    // A third start finds everything in the journal and fits nothing.
    let (again, fitted) = run(&journal, &[]);
    assert!(fitted.is_empty());
    for (a, b) in whole.iter().zip(&again.unwrap()) {
        assert_eq!(bits(a), bits(b), "ν = {}: {a:?} vs {b:?}", a.nu);
    }
}

// ---- The same through the binary -------------------------------------------------------------
//
// A real fit takes minutes, so these runs give `mcdem calibrate` a journal that already holds every
// requested ν: it must then fit nothing (the journal is not appended to) and write its outputs from
// the journal's values, bit for bit. If the binary ignored its journal it would start the 514-particle
// fits; the 120 s timeout (a fit takes minutes, reading a journal milliseconds) turns that into a
// failure instead of a slow pass.

use assert_cmd::Command;

fn journal_line(f: &Fit) -> String {
    serde_json::to_string(f).unwrap() + "\n"
}

fn calibrate(dir: &Path, nus: &str) -> assert_cmd::assert::Assert {
    Command::cargo_bin("mcdem")
        .unwrap()
        .args(["calibrate", "--quick", "--nu", nus, "--out"])
        .arg(dir)
        .env("MCDEM_PROGRESS_INTERVAL", "1")
        .timeout(std::time::Duration::from_secs(120))
        .assert()
}

fn outputs(dir: &Path) -> Vec<Fit> {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("calibration.json")).unwrap()).unwrap();
    serde_json::from_value(json["fits"].clone()).unwrap()
}

#[test]
fn the_binary_resumes_from_its_journal_without_fitting_again() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("calibration_done_quick.jsonl");
    // ν = 0.4 is journaled but not asked for: it must not appear in the outputs.
    let text: String = [0.5, 0.4, 0.3].iter().map(|&nu| journal_line(&stand_in(nu))).collect();
    std::fs::write(&journal, &text).unwrap();
    let out = calibrate(dir.path(), "0.3,0.5").success();
    let stdout = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert_eq!((stdout.clone() + &stderr).matches("taken from").count(), 2, "{stdout}{stderr}");
    assert_eq!(std::fs::read_to_string(&journal).unwrap(), text, "nothing was fitted, so nothing appended");
    let fits = outputs(dir.path());
    assert_eq!(fits.iter().map(|f| f.nu).collect::<Vec<_>>(), [0.3, 0.5]);
    for f in &fits {
        assert_eq!(bits(f), bits(&stand_in(f.nu)), "ν = {}", f.nu);
    }
    let csv = std::fs::read_to_string(dir.path().join("calibration.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "header and two ν:\n{csv}");
    assert!(dir.path().join("calibration.md").exists() && dir.path().join("calibration.png").exists());
}

#[test]
fn a_damaged_journal_line_is_an_error_naming_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("calibration_done_quick.jsonl");
    std::fs::write(&journal, journal_line(&stand_in(0.5)) + "{\"nu\": 0.3, \"gamma\": oops}\n").unwrap();
    let out = calibrate(dir.path(), "0.5").failure();
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(stderr.contains("calibration_done_quick.jsonl:2: not a calibration fit"), "{stderr}");
    assert!(!dir.path().join("calibration.json").exists());
}

#[test]
fn a_torn_last_line_from_a_killed_run_is_dropped_and_the_rest_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("calibration_done_quick.jsonl");
    let whole = journal_line(&stand_in(0.5));
    let torn = &journal_line(&stand_in(0.3))[..40];
    std::fs::write(&journal, whole.clone() + torn).unwrap();
    let out = calibrate(dir.path(), "0.5").success();
    let all = String::from_utf8_lossy(&out.get_output().stdout).to_string()
        + &String::from_utf8_lossy(&out.get_output().stderr);
    assert!(all.contains("calibration_done_quick.jsonl:2: an unfinished last line"), "{all}");
    assert_eq!(std::fs::read_to_string(&journal).unwrap(), whole, "the torn line is cut, the fit kept");
    assert_eq!(bits(&outputs(dir.path())[0]), bits(&stand_in(0.5)));
}

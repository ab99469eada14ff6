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

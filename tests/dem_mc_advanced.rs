//! `mc_advanced` limits through the whole engine (SPEC §3): MPR = 0 is Hertz bit for bit and a huge
//! MPR is standard MC bit for bit, on the moving-plates deck.

use std::path::{Path, PathBuf};
use std::process::Command;

fn run(deck: &str, vars: &[(&str, &str)]) -> String {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let mut c = Command::new(env!("CARGO_BIN_EXE_mcdem"));
    c.current_dir(dir.path()).arg("run").arg(repo.join("liggghts_inputs").join(deck)).args(["-log", "none"]);
    for (k, v) in vars {
        c.args(["-var", k, v]);
    }
    let o = c.output().unwrap();
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read_to_string(Path::new(dir.path()).join("post/plates.dump")).unwrap()
}

#[test]
fn mpr_zero_is_hertz_bit_for_bit() {
    let hertz = run("particle_between_plates.in", &[]);
    let adv = run("particle_between_plates_mc_advanced.in", &[("mpr", "0")]);
    assert!(hertz == adv, "mc_advanced with MPR = 0 differs from Hertz");
}

#[test]
fn huge_mpr_is_standard_mc_bit_for_bit() {
    let mc = run("particle_between_plates_mc.in", &[]);
    let adv = run("particle_between_plates_mc_advanced.in", &[("mpr", "1000")]);
    assert!(mc == adv, "mc_advanced with a huge MPR differs from standard MC");
    let hertz = run("particle_between_plates.in", &[]);
    assert!(hertz != mc, "the multi-contact correction must change this deck");
}

#[test]
fn paper_mpr_lies_between_the_limits() {
    // With MPR = 0.11 the run completes and differs from at least one limit.
    let adv = run("particle_between_plates_mc_advanced.in", &[("mpr", "0.11")]);
    let hertz = run("particle_between_plates.in", &[]);
    let mc = run("particle_between_plates_mc.in", &[]);
    assert!(adv != hertz || adv != mc);
}

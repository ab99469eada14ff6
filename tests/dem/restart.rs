//! `write_restart` / `read_restart`: a run of N steps, a restart file, and a second deck that reads
//! it and runs N more steps ends in the same state, bit for bit, as one deck running `run N` twice.
//! (Not as one `run 2N`: every run starts with a set-up force pass that does not advance the contact
//! history, in mcdem as in LIGGGHTS, so a run boundary changes the trajectory whether or not a
//! restart file lies between the runs.) Decks: liggghts_inputs/periodic_bcc_bed.in and
//! periodic_bcc_bed_restart.in (54 frictional spheres in contact, periodic in x and y, on a floor).

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mcdem(dir: &Path, deck: &str, vars: &[(&str, &str)]) -> String {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mcdem"));
    c.current_dir(dir).args(["run", deck, "--log", "none", "--no-progress"]);
    for (k, v) in vars {
        c.args(["-var", k, v]);
    }
    let o = c.output().unwrap();
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{deck}: {all}");
    all
}

/// Runs the bed with `law` and `meshfloor` as N + N steps in one deck and as N steps, restart,
/// N steps; returns both final restart files.
fn both_ways(law: &str, meshfloor: &str, n: &str) -> (String, String) {
    let dir = tempfile::tempdir().unwrap();
    let src = repo().join("liggghts_inputs");
    for f in ["periodic_bcc_bed.in", "periodic_bcc_bed_restart.in", "select_law.inc"] {
        std::fs::copy(src.join(f), dir.path().join(f)).unwrap();
    }
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    std::fs::copy(src.join("meshes/plate_10mm.stl"), dir.path().join("meshes/plate_10mm.stl")).unwrap();
    let deck = std::fs::read_to_string(src.join("periodic_bcc_bed.in")).unwrap();
    let last = deck.lines().last().unwrap();
    assert!(last.starts_with("if \"${restart} > 0\""), "{last}");
    std::fs::write(
        dir.path().join("two_runs.in"),
        deck.replace(last, &format!("run {n}\nrun {n}\nwrite_restart end_two_runs.json")),
    )
    .unwrap();
    let restart = std::fs::read_to_string(src.join("periodic_bcc_bed_restart.in")).unwrap();
    std::fs::write(dir.path().join("continued.in"), restart + "write_restart end_continued.json\n").unwrap();
    let v = [("law", law), ("meshfloor", meshfloor)];
    mcdem(dir.path(), "two_runs.in", &v);
    let out = mcdem(dir.path(), "periodic_bcc_bed.in", &[v[0], v[1], ("restart", n)]);
    assert!(out.contains("INFO: write_restart: 54 particles"), "{out}");
    let out = mcdem(dir.path(), "continued.in", &[v[0], v[1], ("steps", n)]);
    assert!(out.contains("INFO: read_restart: 54 particles"), "{out}");
    let read = |f: &str| std::fs::read_to_string(dir.path().join(f)).unwrap();
    (read("end_two_runs.json"), read("end_continued.json"))
}

fn contacts(json: &str) -> (usize, usize) {
    let v: serde_json::Value = serde_json::from_str(json).unwrap();
    let e = &v["engine"];
    let sheared = e["pair_shear"].as_array().unwrap().iter().filter(|s| s[0].as_f64() != Some(0.0)).count();
    (sheared, e["wall_contacts"].as_array().unwrap().len())
}

#[test]
fn restart_continues_bit_for_bit_hertz_with_plane_and_mesh_floors() {
    for meshfloor in ["0", "1"] {
        let (a, b) = both_ways("1", meshfloor, "500");
        let (sheared, walls) = contacts(&a);
        assert!(
            sheared > 50 && walls >= 9,
            "the state carries histories: {sheared} pairs, {walls} wall contacts"
        );
        assert!(a == b, "meshfloor {meshfloor}: the continued run differs from the uninterrupted one");
        assert!(a.contains("\"step\":1000"), "ends at step 1000");
    }
}

#[test]
fn restart_continues_bit_for_bit_mc_advanced() {
    let (a, b) = both_ways("0", "0", "300");
    let v: serde_json::Value = serde_json::from_str(&a).unwrap();
    assert!(
        !v["engine"]["pair_hist"].as_array().unwrap().is_empty(),
        "the multi-contact pair records travel"
    );
    assert!(a == b, "mc_advanced: the continued run differs from the uninterrupted one");
}

#[test]
fn a_liggghts_binary_restart_is_refused_with_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    // What LIGGGHTS' write_restart begins with: binary integers and its version string.
    let mut bin = vec![0u8, 0, 0, 0, 11, 0, 0, 0];
    bin.extend_from_slice(b"Version 3.8.0\0\xff\xfe");
    std::fs::write(dir.path().join("post.restart"), bin).unwrap();
    std::fs::write(dir.path().join("in.test"), "units si\natom_style granular\nread_restart post.restart\n")
        .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .args(["run", "in.test", "--log", "none"])
        .output()
        .unwrap();
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(!o.status.success());
    assert!(
        all.contains("ERROR: in.test:3: read_restart: post.restart is not an mcdem restart file: it looks like a LIGGGHTS binary restart, which mcdem cannot read"),
        "{all}"
    );
}

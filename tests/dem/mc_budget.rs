//! The accuracy budget of the multi-contact pass (`mcAccuracy EPS`, `--mc-accuracy EPS`,
//! docs/dem.md "Accuracy budget"): EPS = 0 is the exact pass byte for byte; with EPS > 0 the
//! shadow check's measured error never exceeds the bound and the plate force moves by an amount
//! consistent with EPS; a particle with one contact costs no Eq. 2 work; bad input is named.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::deck::run_in;

fn decks() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs")
}

/// The nine-sphere body-centred cell compressed by a plate (`bcc_box.in`, mc_advanced, 3000 steps,
/// 0.3 r of travel) with `options`; returns (plate force column, dump text, standard output).
fn bcc_box(options: &[&str]) -> (Vec<f64>, String, String) {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .arg("run")
        .arg(decks().join("bcc_box.in"))
        .args(["-var", "law", "0", "-var", "every", "10", "-var", "dir"])
        .arg(decks())
        .args(["-log", "none", "--no-progress"])
        .args(options)
        .output()
        .unwrap();
    let out = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{out}");
    let force = std::fs::read_to_string(dir.path().join("bcc_box.txt"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().nth(2).unwrap().parse().unwrap())
        .collect();
    let dump = std::fs::read_to_string(dir.path().join("bcc_box.dump")).unwrap();
    (force, dump, out)
}

/// The sphere squeezed between a floor and a moving plate (two contacts: Eq. 2 acts) with
/// `setting` on its pair style and both walls; returns (ok, output, dump text).
fn plates(setting: &str, extra: &[&str]) -> (bool, String, String) {
    let text =
        std::fs::read_to_string(decks().join("particle_between_plates_mc_advanced.in")).unwrap().replace(
            "model mc_advanced tangential history",
            &format!("model mc_advanced tangential history {setting}"),
        );
    let stl = std::fs::read_to_string(decks().join("meshes/plate_10mm.stl")).unwrap();
    let files = [("meshes/", ""), ("meshes/plate_10mm.stl", stl.as_str()), ("post/", "")];
    let (ok, out, dir) = run_in("in.plates", &text, extra, &files);
    let dump = std::fs::read_to_string(dir.path().join("post/plates.dump")).unwrap_or_default();
    (ok, out, dump)
}

/// (largest measured error, its bound), both relative to the particle's scale, over the run's
/// "accuracy check" clauses; panics when no check ran.
fn checked(out: &str) -> (f64, f64) {
    let mut found = None;
    for l in out.lines().filter_map(|l| l.split("accuracy check").nth(1)) {
        let after = |key: &str| -> f64 {
            let s = &l[l.find(key).unwrap() + key.len()..];
            s.split([',', ' ']).find(|w| !w.is_empty()).unwrap().parse().unwrap()
        };
        let (m, b) = (after("measured error "), after("bound "));
        let (m0, b0) = found.unwrap_or((0.0f64, 0.0f64));
        found = Some((m0.max(m), b0.max(b)));
    }
    found.unwrap_or_else(|| panic!("no accuracy check ran:\n{out}"))
}

/// Largest |f − exact| over the largest |exact|.
fn relative(f: &[f64], exact: &[f64]) -> f64 {
    assert_eq!(f.len(), exact.len());
    let top = exact.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(top > 0.0);
    f.iter().zip(exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / top
}

#[test]
fn accuracy_zero_is_the_exact_pass_byte_for_byte() {
    let (ok, out, exact) = plates("", &[]);
    assert!(ok && exact.len() > 1000, "{out}");
    for (setting, extra) in [("mcAccuracy 0", &[][..]), ("", &["--mc-accuracy", "0"][..])] {
        let (ok, out, dump) = plates(setting, extra);
        assert!(ok, "{out}");
        assert!(dump == exact, "{setting} {extra:?}: the dump differs from the exact run's");
        assert!(!out.contains("multi-contact accuracy"), "{out}");
    }
    let (_, exact, _) = bcc_box(&[]);
    let (_, zero, _) = bcc_box(&["--mc-accuracy", "0"]);
    assert!(zero == exact, "bcc_box: --mc-accuracy 0 changed the dump");
}

/// On the compressed cell the shadow check (every 10 steps) never measures more than the bound
/// (the run would stop), and the plate force follows EPS. Measured with the loads taken exactly
/// through the kept influence matrix: at EPS = 1e-2 (10 % of the particle-steps recomputed) the
/// radius changes are off by at most 2.5e-4 of their scale (largest bound 1.0e-2) and the plate
/// force by 6.2e-6 of its peak; at 1e-3 (80 % recomputed), 2.8e-5 (bound 1.0e-3) and 2.1e-6. (The
/// first form, which reused Δ⁰ and bounded the load change too, recomputed 47 % and 99 % and was
/// off by 3.9e-3 and 1.4e-4.) The force error is far below EPS because a radius change is itself
/// a small part of a contact's overlap; the limits leave a factor of 14 and 48.
#[test]
fn the_measured_error_stays_within_the_bound() {
    let (exact, _, _) = bcc_box(&[]);
    let mut errors = Vec::new();
    for (eps, force_bound) in [(1e-2, 3e-4), (1e-3, 3e-5)] {
        let e = eps.to_string();
        let (force, _, out) = bcc_box(&["--mc-accuracy", &e, "--mc-accuracy-check", "10"]);
        let (measured, bound) = checked(&out);
        assert!(
            measured <= bound && bound <= eps * (1.0 + 1e-9),
            "EPS {e}: measured {measured:e}, bound {bound:e}"
        );
        assert!(measured > 0.0, "EPS {e}: the budget never reused a result:\n{out}");
        let rel = relative(&force, &exact);
        assert!(rel <= force_bound, "EPS {e}: plate force off by {rel:e} of its peak");
        errors.push(rel);
    }
    assert!(errors[1] <= errors[0], "the force error must not grow as EPS shrinks: {errors:?}");
    // The deck keyword runs the same check (every 10 steps).
    let (ok, out, _) = plates("mcAccuracy 1e-2 mcAccuracyCheck yes", &[]);
    assert!(ok, "{out}");
    let (measured, bound) = checked(&out);
    assert!(measured <= bound, "{out}");
}

/// A sphere resting on the floor has one contact: the sum over the other contacts is empty, so
/// neither the exact pass nor the budget evaluates Eq. 2 for it.
#[test]
fn a_particle_with_one_contact_needs_no_eq2_work() {
    let text = "units si
atom_style sphere
boundary f f f
soft_particles yes
region box block -0.01 0.01 -0.01 0.01 -0.002 0.01 units box
create_box 1 box
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype 5e5
fix m2 all property/global poissonsRatio peratomtype 0.4
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.5
fix m4 all property/global coefficientFriction peratomtypepair 1 0.3
fix m5 all property/global geometricPrefactor peratomtype 1.125
fix m6 all property/global maxPenetrationRatio peratomtype 0.11
pair_style gran model mc_advanced tangential history SETTING
pair_coeff * *
timestep 1e-6
fix floor all wall/gran model mc_advanced tangential history primitive type 1 zplane -0.001
fix gravi all gravity 9.81 vector 0 0 -1
create_atoms 1 single 0 0 -0.00001 units box
set atom 1 diameter 0.002 density 1000
fix integr all nve/sphere
run 500
";
    for setting in ["", "mcAccuracy 1e-3"] {
        let (ok, out) = super::deck::run_deck(&text.replace("SETTING", setting), &[]);
        assert!(ok, "{out}");
        // The kernel reports its evaluations whenever there was one.
        assert!(!out.contains("Multi-contact kernel:"), "{setting}: {out}");
        if !setting.is_empty() {
            assert!(
                out.contains(
                    "recomputed in 0.00 % of the particle-steps with two or more contacts (0.00 % of all)"
                ),
                "{out}"
            );
        }
    }
}

#[test]
fn bad_accuracy_settings_are_named() {
    let mc = |setting: &str| plates(setting, &[]);
    for bad in ["-1e-3", "nan", "inf", "often"] {
        let (ok, out, _) = mc(&format!("mcAccuracy {bad}"));
        let named = format!("mcAccuracy must be a finite number >= 0 (the relative error budget of the multi-contact corrections; 0 = exact), got '{bad}'");
        assert!(
            !ok && out.contains("ERROR: ") && out.contains("in.plates:") && out.contains(&named),
            "{out}"
        );
    }
    for other in ["updateEvery 10", "geometryTolerance 1e-3"] {
        let (ok, out, _) = mc(&format!("mcAccuracy 1e-3 {other}"));
        let key = other.split(' ').next().unwrap();
        let named = format!("mcAccuracy and {key} cannot be combined: the accuracy budget decides per particle and step when Eq. 2 is recomputed; drop {key}");
        assert!(!ok && out.contains(&named), "{out}");
    }
    let (ok, out, _) = mc("mcAccuracyCheck yes");
    assert!(!ok && out.contains("mcAccuracyCheck yes needs mcAccuracy EPS > 0"), "{out}");
    let (ok, out, _) = mc("mcAccuracy 1e-3 mcAccuracyCheck maybe");
    assert!(!ok && out.contains("mcAccuracyCheck must be 'yes' or 'no', got 'maybe'"), "{out}");
    // The command line: the same value checks, and no mixing with the fixed approximations.
    let (ok, out, _) = plates("", &["--mc-accuracy=-1"]);
    assert!(!ok && out.contains("--mc-accuracy must be a finite number >= 0"), "{out}");
    let (ok, out, _) = plates("", &["--mc-accuracy", "1e-3", "--mc-update-every", "10"]);
    assert!(
        !ok && out
            .contains("--mc-accuracy cannot be combined with --mc-geometry-tolerance or --mc-update-every"),
        "{out}"
    );
    let (ok, out, _) = plates("updateEvery 10", &["--mc-accuracy", "1e-3"]);
    assert!(
        !ok && out.contains(
            "mcAccuracy (or --mc-accuracy) cannot be combined with geometryTolerance or updateEvery"
        ),
        "{out}"
    );
    // Models without a multi-contact correction.
    let hertz =
        super::deck::BASE.replace("tangential history", "tangential history mcAccuracy 1e-3") + "run 1\n";
    let (ok, out) = super::deck::run_deck(&hertz, &[]);
    assert!(!ok && out.contains("mcAccuracy is a setting of model mc_advanced: model hertz has no multi-contact correction to budget"), "{out}");
    let hooke = hertz.replace("model hertz", "model hooke");
    let (ok, out) = super::deck::run_deck(&hooke, &[]);
    assert!(!ok && out.contains("model hooke has no multi-contact correction"), "{out}");
    let (ok, out) =
        super::deck::run_deck(&(super::deck::BASE.to_string() + "run 1\n"), &["--mc-accuracy", "1e-3"]);
    assert!(!ok && out.contains("--mc-accuracy and --mc-accuracy-check apply to model mc_advanced only; this pair style is model hertz"), "{out}");
}

/// The budget's decisions are per particle, so the threaded pass (particles split between the two
/// members) gives the serial run's bits: one fast stroke of the 514-particle hydrogel compression.
#[test]
fn the_budget_gives_the_same_bits_on_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let force = |mode: &str| {
        let out = dir.path().join(format!("piston_{mode}.txt"));
        let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
            .current_dir(dir.path())
            .env("RAYON_NUM_THREADS", "2")
            .arg("run")
            .arg(decks().join("hydrogel.in"))
            .args([
                "-var", "law", "0", "-var", "stroke", "3000", "-var", "strokes", "1", "-var", "every", "10",
            ])
            .args(["-var", "dir"])
            .arg(decks())
            .args(["-var", "out"])
            .arg(&out)
            .args(["-log", "none", "--no-progress", "--mc-accuracy", "1e-2", "--threads-mode", mode])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(o.status.success(), "{text}");
        (std::fs::read_to_string(out).unwrap(), text)
    };
    let ((serial, _), (parallel, text)) = (force("serial"), force("parallel"));
    assert!(text.contains("threaded in 100 %"), "{text}");
    assert!(
        serial.lines().count() > 300 && serial == parallel,
        "the piston force differs between serial and threaded runs"
    );
}

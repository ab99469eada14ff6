//! LIGGGHTS' `rolling_friction epsd` / `epsd2` in `mcdem run` (the step-by-step comparison with
//! LIGGGHTS is in against_liggghts.rs): the rocking of a sphere on a floor held by the rolling
//! and tangential springs against its closed form, the deceleration at the cap, a restart in the
//! middle of a run, and the errors of bad input.

use crate::deck::{run_deck, run_in};
use crate::rolling_friction::{deck, ROLLING};

/// A sphere (r, ρ, E, ν) resting on a floor of the same material at its static overlap, spinning
/// slowly about y (ω0): `epsd2`, restitution 1 (no damping), μ high enough that it does not slide
/// and μ_r high enough that the rolling spring stays below its cap. Returns the dump's
/// (step, ω_y) every 50 steps.
fn rocking_sphere(model: &str, friction: f64, omega0: f64, steps: u64) -> Vec<(u64, f64)> {
    let deck = format!(
        "units si
atom_style sphere
boundary f f f
region box block -0.01 0.01 -0.01 0.01 -0.001 0.01 units box
create_box 1 box
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype {E}
fix m2 all property/global poissonsRatio peratomtype {NU}
fix m3 all property/global coefficientRestitution peratomtypepair 1 1.0
fix m4 all property/global coefficientFriction peratomtypepair 1 {friction}
fix m5 all property/global coefficientRollingFriction peratomtypepair 1 0.3
fix m6 all property/global coefficientRollingViscousDamping peratomtypepair 1 0.0
pair_style gran model hertz tangential history rolling_friction {model}
pair_coeff * *
fix floor all wall/gran model hertz tangential history rolling_friction {model} primitive type 1 zplane 0.0
fix gravi all gravity {G} vector 0.0 0.0 -1.0
timestep 1e-6
create_atoms 1 single 0 0 {z} units box
set atom 1 diameter {d} density {RHO}
set atom 1 omegay {omega0}
fix integr all nve/sphere
dump d all custom 50 post/rock.dump id omegay
run {steps}
",
        z = R - static_overlap(),
        d = 2.0 * R,
    );
    let (ok, out, dir) = run_in("in.rock", &deck, &["--no-progress"], &[("post/", "")]);
    assert!(ok, "{out}");
    let frames = mcdem::outputs::read_dump(&dir.path().join("post/rock.dump")).unwrap();
    frames.iter().map(|f| (f.step, f.rows[0][1])).collect()
}

const R: f64 = 1e-3;
const RHO: f64 = 2500.0;
const E: f64 = 5e6;
const NU: f64 = 0.3;
const G: f64 = 9.81;

fn mass() -> f64 {
    RHO * 4.0 / 3.0 * std::f64::consts::PI * R.powi(3)
}

/// Hertz: m g = (4/3) E* √R δ^{3/2} with E* = E / (2 (1 − ν²)) (sphere and floor of one material).
fn static_overlap() -> f64 {
    let e_star = E / (2.0 * (1.0 - NU * NU));
    (mass() * G / (4.0 / 3.0 * e_star * R.sqrt())).powf(2.0 / 3.0)
}

/// The closed form of the rocking. With x the centre's displacement along the floor, θ the
/// rotation about y, the contact's lever c = r − δ/2 and s = x − c θ the tangential spring's
/// stretch (LIGGGHTS' relative velocity at the contact point), below the Coulomb limit and the
/// rolling cap:
///
/// m x'' = −k_t s,   I θ'' = c k_t s − M,   M' = k_r' θ',
///
/// I = (2/5) m r², k_t = 8 G* √(r δ) (G* = E / (4 (2 − ν)(1 + ν))), and k_r' = k_r c / (r − δ):
/// the spring grows by k_r Δt times LIGGGHTS' wall rolling velocity `wr` = ω c / (r − δ), with
/// k_r = k_t r² under epsd2 (k_r = 0 without rolling friction). Stiffness K = [[k_t, −k_t c],
/// [−k_t c, k_t c² + k_r']], masses diag(m, I): two modes Ω² = (B ∓ √(B² − 4 m I k_t k_r'))/(2 m I)
/// with B = k_t I + m (k_t c² + k_r'), shapes φ = (k_t c, k_t − Ω² m). From rest with spin ω0:
/// ω(t) = Σ a_k φ_k,θ cos(Ω_k t), with Σ a_k φ_k = (0, ω0). (Without the tangential spring — the
/// sphere held at its centre, or rolling without slip with an infinitely stiff contact — it would
/// be one mode, Ω² = k_r / I_eff with I_eff = (7/5) m r² about the contact point; the contact's
/// tangential compliance, as stiff as the rolling spring under epsd2, splits it into these two.)
fn closed_form(kr_factor: f64, omega0: f64) -> impl Fn(f64) -> f64 {
    let (m, d) = (mass(), static_overlap());
    let g_star = E / (4.0 * (2.0 - NU) * (1.0 + NU));
    let kt = 8.0 * g_star * (R * d).sqrt();
    let c = R - 0.5 * d;
    let krp = kr_factor * kt * R * R * c / (R - d);
    let i = 0.4 * m * R * R;
    let b = kt * i + m * (kt * c * c + krp);
    let disc = (b * b - 4.0 * m * i * kt * krp).sqrt();
    let om = [((b - disc) / (2.0 * m * i)).sqrt(), ((b + disc) / (2.0 * m * i)).sqrt()];
    let phi = om.map(|o| [kt * c, kt - o * o * m]);
    // a0 φ0 + a1 φ1 = (0, ω0).
    let det = phi[0][0] * phi[1][1] - phi[1][0] * phi[0][1];
    let a = [(-phi[1][0] * omega0) / det, (phi[0][0] * omega0) / det];
    println!("modes {:.2} and {:.2} rad/s", om[0], om[1]);
    move |t: f64| a[0] * phi[0][1] * (om[0] * t).cos() + a[1] * phi[1][1] * (om[1] * t).cos()
}

/// `epsd2` below its cap: the sphere rocks as the two-mode closed form above says, over 6 ms
/// (2.3 periods of the slow mode, 2432.8 rad/s; fast mode 8534.3 rad/s). ω is compared every 50
/// steps to 0.1 % of ω0 (measured 0.013 %: the discrete spring update, Δt Ω ≈ 0.009, and the ~1e-7
/// relative wobble of δ are below; the δ/r ≈ 1e-3 terms are in the closed form). And without
/// rolling friction the same sphere follows the closed form with k_r = 0 (one mode, the
/// tangential spring alone), which differs from the epsd2 run by 70 % of ω0: the check can fail.
#[test]
fn a_sphere_rocking_on_a_floor_follows_the_two_mode_closed_form() {
    let omega0 = 0.05;
    for (model, kr) in [("epsd2", 1.0), ("off", 0.0)] {
        let run = rocking_sphere(model, 0.5, omega0, 6000);
        let w = closed_form(kr, omega0);
        let err = run.iter().map(|&(s, o)| (o - w(s as f64 * 1e-6)).abs()).fold(0.0, f64::max);
        println!("{model}: max |ω − closed form| = {:.3e} of ω0", err / omega0);
        assert!(err < 1e-3 * omega0, "{model}: {err:e}");
        if model == "epsd2" {
            let other = closed_form(0.0, omega0);
            let apart = run.iter().map(|&(s, o)| (o - other(s as f64 * 1e-6)).abs()).fold(0.0, f64::max);
            assert!(apart > 0.3 * omega0, "the rolling spring changes the motion: {apart:e}");
        }
    }
}

const DAMPING: &str = "fix m6 all property/global coefficientRollingViscousDamping peratomtypepair 1 0.3\n";

#[test]
fn rolling_friction_epsd_bad_input_stops_with_file_and_line() {
    let (epsd, epsd2) = (
        "model hertz tangential history rolling_friction epsd",
        "model hertz tangential history rolling_friction epsd2",
    );
    let both = format!("{ROLLING}{DAMPING}");
    // BASE has 10 lines before pair_style and 16 in all; each property line moves `run` down one.
    let cases: &[(String, &str)] = &[
        (deck("", epsd2), "in.test:17: fix property/global coefficientRollingFriction is missing (rolling_friction epsd2 needs"),
        (deck(ROLLING, epsd), "in.test:18: fix property/global coefficientRollingViscousDamping is missing (rolling_friction epsd needs"),
        (
            deck(&format!("{ROLLING}{}", DAMPING.replace("1 0.3", "1 -0.3")), epsd),
            "in.test:19: types 1 and 1: invalid coefficientRollingViscousDamping = -0.3: must be finite and >= 0",
        ),
        (
            deck(&both.replace("1 0.1", "1 -0.1"), epsd2),
            "in.test:19: types 1 and 1: invalid coefficientRollingFriction = -0.1: must be finite and >= 0",
        ),
        (
            deck(&both, "model hertz tangential history rolling_friction epsd torsionTorque on"),
            "in.test:13: unsupported pair_style gran keyword torsionTorque",
        ),
        (
            deck(&both, "model mc_advanced tangential history rolling_friction epsd2"),
            "in.test:13: unsupported rolling_friction epsd2 with a multi-contact model",
        ),
        (
            deck(&both, "model hertz tangential history rolling_friction epsd3"),
            "in.test:13: unsupported rolling_friction epsd3 (its user-set rolling stiffness",
        ),
    ];
    for (text, want) in cases {
        let (ok, out) = run_deck(text, &[]);
        assert!(!ok && out.contains("ERROR: ") && out.contains(want), "want '{want}', got:\n{out}");
    }
}

/// A restart in the middle of an `epsd` run (liggghts_inputs/rolling_friction_epsd.in, 1000 +
/// 1000 steps, while the pair 4-5 still touches) carries the rolling springs of the pairs and the
/// wall contacts: the continued run
/// ends in the same state, bit for bit, as one deck running `run 1000` twice (not `run 2000`:
/// every run starts with a set-up pass that does not advance the histories; see restart.rs). Both
/// kinds of spring are non-zero at the restart (checked), and a continued run whose file has the
/// springs zeroed ends elsewhere (so the check can fail).
#[test]
fn restart_mid_run_carries_the_rolling_springs() {
    let text = std::fs::read_to_string(
        crate::against_liggghts::repo().join("liggghts_inputs/rolling_friction_epsd.in"),
    )
    .unwrap();
    let run = "run\t\t${nsteps}";
    assert!(text.contains(run));
    let two_runs = text.replace(run, "run 1000\nrun 1000\nwrite_restart end_two_runs.json");
    let first = text.replace(run, "run 1000\nwrite_restart mid.json");
    // The continued deck: the box and the particles come from the file, the rest is defined again.
    let mut continued = String::new();
    for line in text.lines() {
        if line.starts_with("region") || line.starts_with("create_atoms") || line.starts_with("set\t") {
            continue;
        }
        if line.starts_with("create_box") {
            continued.push_str("read_restart mid.json\n");
            continue;
        }
        continued.push_str(&line.replace(run, "run 1000\nwrite_restart end_continued.json"));
        continued.push('\n');
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("post")).unwrap();
    let mcdem = |deck: &str, text: &str| {
        std::fs::write(dir.path().join(deck), text).unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_mcdem"))
            .current_dir(dir.path())
            .args(["run", deck, "-log", "none", "--no-progress"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{deck}: {}", String::from_utf8_lossy(&o.stderr));
    };
    let read = |f: &str| std::fs::read_to_string(dir.path().join(f)).unwrap();
    mcdem("two_runs.in", &two_runs);
    mcdem("first.in", &first);
    let mid: serde_json::Value = serde_json::from_str(&read("mid.json")).unwrap();
    let e = &mid["engine"];
    let nonzero = |v: &serde_json::Value| v.as_array().unwrap().iter().any(|x| x.as_f64() != Some(0.0));
    let pair_springs = e["pair_roll"].as_array().unwrap().iter().filter(|m| nonzero(m)).count();
    let wall_springs = e["wall_contacts"].as_array().unwrap().iter().filter(|w| nonzero(&w["roll"])).count();
    assert!(pair_springs >= 1 && wall_springs >= 6, "{pair_springs} pair and {wall_springs} wall springs");
    mcdem("continued.in", &continued);
    assert!(read("end_two_runs.json") == read("end_continued.json"), "the continued run differs");
    // Without the springs the continued run ends elsewhere.
    let mut zeroed = mid.clone();
    for m in zeroed["engine"]["pair_roll"].as_array_mut().unwrap() {
        *m = serde_json::json!([0.0, 0.0, 0.0]);
    }
    for w in zeroed["engine"]["wall_contacts"].as_array_mut().unwrap() {
        w["roll"] = serde_json::json!([0.0, 0.0, 0.0]);
    }
    std::fs::write(dir.path().join("mid.json"), zeroed.to_string()).unwrap();
    mcdem("continued.in", &continued);
    assert!(read("end_two_runs.json") != read("end_continued.json"), "the springs were not read");
}

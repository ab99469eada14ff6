//! Compiles `tests/c_abi/abi_check.c` against `native/mcdem.h` with the C compiler the `cc` crate
//! finds, links it with this build's `libmcdem.a`, runs it and compares every printed value with
//! the Rust core computing the same thing. Header and library cannot drift without this failing.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use mcdem::physics::contact_set::{radius_changes, ContactLoad, McParams};
use mcdem::physics::ghods2022::{Cap, MprTest};
use mcdem::physics::hertz;
use mcdem::physics::material::{Material, PairCoeffs};
use mcdem::physics::pair::{particle_particle, particle_wall, Body, WallPoint};
use mcdem::physics::Vec3;

/// The static library cargo built for this test run: newest `libmcdem*.a` next to the test binary.
fn static_lib() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    let mut libs: Vec<PathBuf> = [deps, deps.parent().unwrap()]
        .iter()
        .flat_map(|d| std::fs::read_dir(d).into_iter().flatten().flatten())
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("libmcdem") && n.ends_with(".a"))
        })
        .collect();
    libs.sort_by_key(|p| std::fs::metadata(p).and_then(|m| m.modified()).ok());
    libs.pop().expect("libmcdem.a not found: the crate must build as a staticlib")
}

fn compile_and_run(dir: &Path) -> HashMap<String, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let target = format!("{}-unknown-{}-gnu", std::env::consts::ARCH, std::env::consts::OS);
    let compiler = cc::Build::new()
        .cargo_metadata(false)
        .cargo_warnings(false)
        .target(&target)
        .host(&target)
        .opt_level(0)
        .out_dir(dir)
        .get_compiler();
    let exe = dir.join("abi_check");
    // With the `liggghts` feature the static library also carries the C++ shim, so a C program
    // linking it needs what the shim needs: LIGGGHTS, MPI (as mpicxx links it) and libstdc++.
    let mut plugin_libs: Vec<String> = Vec::new();
    if cfg!(feature = "liggghts") {
        let out = Command::new("mpicxx").arg("--showme:link").output().expect("mpicxx runs");
        plugin_libs.push("-lliggghts".into());
        plugin_libs.extend(String::from_utf8_lossy(&out.stdout).split_whitespace().map(String::from));
        plugin_libs.push("-lstdc++".into());
    }
    let status = compiler
        .to_command()
        .args(["-std=c99", "-Wall", "-Werror", "-I"])
        .arg(root.join("native"))
        .arg(root.join("tests/c_abi/abi_check.c"))
        .arg("-o")
        .arg(&exe)
        .arg(static_lib())
        .args(&plugin_libs)
        .args(["-lpthread", "-ldl", "-lm"])
        .status()
        .expect("C compiler runs");
    assert!(status.success(), "abi_check.c failed to compile or link against native/mcdem.h");
    let out = Command::new(&exe).output().unwrap();
    assert!(out.status.success(), "abi_check crashed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_once(' ').map(|(k, v)| (k.to_string(), v.to_string())))
        .collect()
}

#[test]
fn c_program_agrees_with_the_rust_core() {
    let dir = tempfile::tempdir().unwrap();
    let v = compile_and_run(dir.path());
    let num = |k: &str| -> f64 { v[k].parse().unwrap_or_else(|_| panic!("{k} = {}", v[k])) };

    // Layouts: the C structs are the Rust #[repr(C)] structs.
    assert_eq!(num("sizeof_mc_params") as usize, std::mem::size_of::<mcdem::ffi::mcdem_mc_params>());
    assert_eq!(num("sizeof_pair_coeffs") as usize, std::mem::size_of::<mcdem::ffi::mcdem_pair_coeffs>());
    assert_eq!(num("sizeof_contact_load") as usize, std::mem::size_of::<ContactLoad>());
    assert_eq!(num("sizeof_pair_coeffs") as usize, std::mem::size_of::<mcdem::ffi::mcdem_pair_coeffs>());
    assert_eq!(num("sizeof_contact_load") as usize, std::mem::size_of::<mcdem::ffi::mcdem_contact_load>());
    assert_eq!(num("sizeof_body") as usize, std::mem::size_of::<mcdem::ffi::mcdem_body>());
    assert_eq!(num("sizeof_contact_force") as usize, std::mem::size_of::<mcdem::ffi::mcdem_contact_force>());
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));

    let m = Material::hertz(23.3e3, 0.5).unwrap();
    let c = PairCoeffs::new(&m, &m, 0.95, 0.03).unwrap();
    assert_eq!(num("coeffs_rc"), 0.0);
    assert_eq!(num("e_star"), c.e_star);
    assert_eq!(num("g_star"), c.g_star);
    assert_eq!(num("beta"), c.beta);

    let n = hertz::normal(&c, 1e-4, 5e-4, 2e-6, -0.01);
    assert_eq!(num("normal_rc"), 0.0);
    assert_eq!(num("normal_force"), n.force);
    assert_eq!(num("normal_kt"), n.kt);

    let p = McParams {
        radius: 1e-3,
        youngs_modulus: 23.3e3,
        poisson_ratio: 0.5,
        gamma: 0.81,
        cap: Some(Cap { mpr: 0.11, test: MprTest::Abs }),
    };
    let cs = [
        ContactLoad { point: Vec3::new(0.0, 0.0, -0.95e-3), force: 1.2e-3 },
        ContactLoad { point: Vec3::new(0.0, 0.0, 0.95e-3), force: 1.2e-3 },
        ContactLoad { point: Vec3::new(0.95e-3, 0.0, 0.0), force: 0.0 },
    ];
    let (mut d, mut fb) = ([0.0; 3], [false; 3]);
    let s = radius_changes(&p, &cs, &mut d, &mut fb).unwrap();
    assert_eq!(num("kernel_rc"), 0.0);
    for (i, di) in d.iter().enumerate() {
        assert_eq!(num(&format!("delta{i}")), *di);
    }
    let flags: Vec<String> = fb.iter().map(|f| u8::from(*f).to_string()).collect();
    assert_eq!(v["fb"], flags.join(" "));
    assert_eq!(num("n_fallback") as usize, s.fallbacks);
    assert!(d[0] > 0.0, "antipodal contacts make the radius grow (B(1) = 2ν − 3 < 0)");

    let bi = Body {
        x: Vec3::new(0.0, 0.0, 1.9e-3),
        v: Vec3::new(0.0, 0.01, -0.01),
        omega: Vec3::new(1.0, 2.0, 3.0),
        radius: 1e-3,
        mass: 4e-6,
    };
    let bj = Body { x: Vec3::zeros(), v: Vec3::zeros(), omega: Vec3::zeros(), radius: 1e-3, mass: 4e-6 };
    let mut shear = Vec3::zeros();
    let f = particle_particle(&c, &bi, &bj, 1e-5, -1e-5, 1e-5, &mut shear).unwrap().unwrap();
    assert_eq!(num("pair_rc"), 0.0);
    assert_eq!(num("in_contact"), 1.0);
    assert_eq!(num("force_z"), f.force_i.z);
    assert_eq!(num("force_y"), f.force_i.y);
    assert_eq!(num("torque_x"), f.torque_i.x);
    assert_eq!(num("shear_y"), shear.y);

    let bw = Body {
        x: Vec3::new(0.0, 0.0, 0.9e-3),
        v: Vec3::zeros(),
        omega: Vec3::zeros(),
        radius: 1e-3,
        mass: 4e-6,
    };
    let wall = WallPoint { point: Vec3::zeros(), velocity: Vec3::zeros() };
    let fw = particle_wall(&c, &bw, &wall, 0.0, 1e-5, &mut Vec3::zeros()).unwrap().unwrap();
    assert_eq!(num("wall_rc"), 0.0);
    assert_eq!(num("wall_force_z"), fw.force_i.z);

    // The pair batch: the library's layout, each lane the one-pair contact bit for bit (checked in
    // C, where the lanes are filled), the deep lane flagged instead of integrated.
    assert_eq!(num("sizeof_pair_batch") as usize, std::mem::size_of::<mcdem::physics::pair::PairLanes>());
    assert_eq!(num("lib_pair_batch"), num("sizeof_pair_batch"));
    assert_eq!(num("batch_rc"), 0.0);
    assert_eq!(v["batch_ok"], "1 1 0");
    assert_eq!(num("batch_mismatch"), 0.0);
    assert!(num("batch_normal0") > 0.0, "lane 0 is a loaded contact");

    // Error paths: codes from the header, messages that name the problem.
    let expect = |key: &str, code: i32, needle: &str| {
        assert_eq!(num(&format!("{key}_code")) as i32, code, "{key}");
        let msg = &v[&format!("{key}_msg")];
        assert!(msg.contains(needle), "{key}: '{msg}' should mention '{needle}'");
    };
    expect("bad_nu", mcdem::ffi::MCDEM_ERR_PARAMETER, "poisson_ratio");
    expect("hand_coeffs", mcdem::ffi::MCDEM_ERR_PARAMETER, "mcdem_pair_coeffs_new");
    expect("bad_gamma", mcdem::ffi::MCDEM_ERR_PARAMETER, "gamma");
    expect("bad_mpr", mcdem::ffi::MCDEM_ERR_PARAMETER, "mpr");
    expect("bad_cap", mcdem::ffi::MCDEM_ERR_PARAMETER, "cap");
    expect("null", mcdem::ffi::MCDEM_ERR_NULL, "contacts");
    expect("deep", mcdem::ffi::MCDEM_ERR_OVERLAP, "radius");
    expect("batch_empty", mcdem::ffi::MCDEM_ERR_PARAMETER, "lanes used = 0");
    expect("batch_hand", mcdem::ffi::MCDEM_ERR_PARAMETER, "mcdem_pair_coeffs_new");
}

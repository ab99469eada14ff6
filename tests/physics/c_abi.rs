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

    // The model settings: names and defaults from the one table, the header's indices its order,
    // and the library's messages reach a C caller.
    use mcdem::physics::mc_settings::MC_SETTINGS;
    for (k, s) in MC_SETTINGS.iter().enumerate() {
        assert_eq!(v[&format!("setting{k}")], s.name());
        assert_eq!(num(&format!("setting{k}_default")), s.default_value());
    }
    assert_eq!(v[&format!("setting{}", MC_SETTINGS.len())], "(null)");
    assert_eq!(v["setting_indices"], "0 1 2 3");
    assert_eq!((num("setting_parse_rc"), num("setting_parse_value")), (0.0, 1.0));
    assert_eq!(num("setting_bad_code") as i32, mcdem::ffi::MCDEM_ERR_PARAMETER);
    assert!(v["setting_bad_msg"].contains("updateEvery must be a whole number"), "{}", v["setting_bad_msg"]);
    assert_eq!(num("setting_wall_code") as i32, mcdem::ffi::MCDEM_ERR_PARAMETER);
    let wall = &v["setting_wall_msg"];
    assert!(wall.contains("updateEvery 5 differs from the pair style's updateEvery 10"), "{wall}");

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

/// The error codes and messages of the C ABI, called from Rust through the same symbols: a
/// non-finite input, coincident centres, an overlap beyond the radius, a null pointer; the
/// message of the last failure, truncated to the caller's buffer with its full length returned;
/// the influence-cache functions.
#[test]
fn c_abi_error_codes_and_messages() {
    use mcdem::ffi::*;
    use std::ffi::c_char;
    let last = || {
        let mut buf = [0 as c_char; 256];
        let n = unsafe { mcdem_last_error(buf.as_mut_ptr(), buf.len()) };
        let s = unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned();
        (n, s)
    };
    let mut c =
        mcdem_pair_coeffs { e_star: 0.0, g_star: 0.0, beta: 0.0, friction: 0.0, damping_ratio_t_n: 0.0 };
    assert_eq!(unsafe { mcdem_pair_coeffs_new(1e6, 0.4, 1e6, 0.4, 0.7, 0.5, &mut c) }, MCDEM_OK);
    assert_eq!(unsafe { mcdem_pair_coeffs_new(-1e6, 0.4, 1e6, 0.4, 0.7, 0.5, &mut c) }, MCDEM_ERR_PARAMETER);
    assert!(last().1.to_lowercase().contains("young"), "{}", last().1);
    assert_eq!(unsafe { mcdem_pair_coeffs_new(1e6, 0.4, 1e6, 0.4, 0.7, 0.5, &mut c) }, MCDEM_OK);
    let body =
        |x: f64| mcdem_body { x: [x, 0.0, 0.0], v: [0.0; 3], omega: [0.0; 3], radius: 1e-3, mass: 4e-6 };
    let (mut shear, mut out) = ([0.0; 3], mcdem_contact_force::default());
    let call = |bi: &mcdem_body, bj: &mcdem_body, shear: &mut [f64; 3], out: &mut mcdem_contact_force| unsafe {
        mcdem_particle_particle(&c, bi, bj, 0.0, 0.0, 1e-6, shear.as_mut_ptr(), out)
    };
    assert_eq!(call(&body(0.0), &body(1.9e-3), &mut shear, &mut out), MCDEM_OK);
    assert_eq!(out.in_contact, 1);
    assert!((out.overlap - 1e-4).abs() < 1e-12);
    // Coincident centres: no normal.
    assert_eq!(call(&body(0.0), &body(0.0), &mut shear, &mut out), MCDEM_ERR_COINCIDENT);
    assert!(!last().1.is_empty());
    // A NaN coordinate.
    assert_eq!(call(&body(0.0), &body(f64::NAN), &mut shear, &mut out), MCDEM_ERR_NON_FINITE);
    let (full, msg) = last();
    assert!(msg.contains("finite") || msg.contains("NaN"), "{msg}");
    // Truncation: a 5-byte buffer gets 4 bytes and the terminator; the return is the full length.
    let mut small = [1 as c_char; 5];
    let n = unsafe { mcdem_last_error(small.as_mut_ptr(), small.len()) };
    assert_eq!(n, full);
    assert_eq!(small[4], 0);
    assert_eq!(unsafe { std::ffi::CStr::from_ptr(small.as_ptr()) }.to_bytes(), &msg.as_bytes()[..4]);
    // Null output pointer.
    let r = unsafe {
        mcdem_particle_particle(
            &c,
            &body(0.0),
            &body(1.9e-3),
            0.0,
            0.0,
            1e-6,
            shear.as_mut_ptr(),
            std::ptr::null_mut(),
        )
    };
    assert_eq!(r, MCDEM_ERR_NULL);
    // Overlap at the radius.
    assert_eq!(mcdem_check_overlap(0.5e-3, 1e-3), MCDEM_OK);
    assert_eq!(mcdem_check_overlap(1e-3, 1e-3), MCDEM_ERR_OVERLAP);
    assert!(last().1.contains("radius"), "{}", last().1);
    // Influence cache: a negative or NaN tolerance is refused with a message, a valid one frees.
    assert!(mcdem_influence_cache_new(-1.0).is_null());
    assert!(!last().1.is_empty());
    assert!(mcdem_influence_cache_new(f64::NAN).is_null());
    let cache = mcdem_influence_cache_new(1e-3);
    assert!(!cache.is_null());
    assert_eq!(unsafe { mcdem_influence_cache_recomputed(cache) }, 0);
    unsafe { mcdem_influence_cache_free(cache) };
    unsafe { mcdem_influence_cache_free(std::ptr::null_mut()) };

    // The material table the plugin builds: the pair entries are the one-pair constructor's,
    // bit for bit, and a bad value names the LIGGGHTS property and the atom type.
    let (e, nu, g, m) = ([23.3e3, 1e6], [0.5, 0.3], [0.81, 0.0], [0.11, 0.0]);
    let (rest, fric) = ([0.9, 0.8, 0.8, 0.7], [0.03, 0.1, 0.1, 0.2]);
    let zero =
        mcdem_pair_coeffs { e_star: 0.0, g_star: 0.0, beta: 0.0, friction: 0.0, damping_ratio_t_n: 0.0 };
    let blank = mcdem_mc_params {
        radius: 0.0,
        youngs_modulus: 0.0,
        poisson_ratio: 0.0,
        gamma: 0.0,
        mpr: 0.0,
        cap: 0,
    };
    let (mut params, mut coeffs) = ([blank; 2], [zero; 4]);
    let table = |nu: &[f64; 2], params: &mut [mcdem_mc_params; 2], coeffs: &mut [mcdem_pair_coeffs; 4]| unsafe {
        mcdem_material_table(
            2,
            e.as_ptr(),
            nu.as_ptr(),
            g.as_ptr(),
            m.as_ptr(),
            MCDEM_CAP_ABS,
            rest.as_ptr(),
            fric.as_ptr(),
            params.as_mut_ptr(),
            coeffs.as_mut_ptr(),
        )
    };
    assert_eq!(table(&nu, &mut params, &mut coeffs), MCDEM_OK);
    for (k, got) in coeffs.iter().enumerate() {
        let (a, b) = (k / 2, k % 2);
        let mut one = zero;
        assert_eq!(
            unsafe { mcdem_pair_coeffs_new(e[a], nu[a], e[b], nu[b], rest[k], fric[k], &mut one) },
            MCDEM_OK
        );
        let bits = |c: &mcdem_pair_coeffs| {
            [c.e_star, c.g_star, c.beta, c.friction, c.damping_ratio_t_n].map(f64::to_bits)
        };
        assert_eq!(bits(got), bits(&one), "type pair {a} {b}");
    }
    assert_eq!(
        (params[1].youngs_modulus, params[1].mpr, params[1].cap, params[1].radius),
        (1e6, 0.0, MCDEM_CAP_ABS, 1.0)
    );
    assert_eq!(unsafe { mcdem_validate_mc_params(&params[0]) }, MCDEM_OK);
    assert_eq!(table(&[0.5, 0.6], &mut params, &mut coeffs), MCDEM_ERR_PARAMETER);
    assert!(last().1.starts_with("invalid poissonsRatio for atom type 2"), "{}", last().1);
}

//! C ABI entry points the LIGGGHTS plugin calls while it sets a run up: the settings of
//! `model mc_advanced` (`physics::mc_settings`) and the material table. The deck reader of
//! `mcdem run` uses the same Rust functions directly, so both engines read, check and build
//! these from one place.

use std::os::raw::c_char;

use super::{
    guard, mcdem_mc_params, mcdem_pair_coeffs, non_null, non_null_mut, param, FfiError, MCDEM_CAP_ABS,
    MCDEM_CAP_SIGNED,
};
use crate::physics::ghods2022::MprTest;
use crate::physics::material::{pair_table, Material};
use crate::physics::mc_settings::{check_wall, McSetting, ENGINE_ONLY, ENGINE_ONLY_WHY, MC_SETTINGS};

/// Keyword of setting `k` of `model mc_advanced` (`MCDEM_SETTING_*`, `physics::mc_settings`), a
/// static NUL-terminated string; null when `k` is not a setting (the shim loops until it is).
#[no_mangle]
pub extern "C" fn mcdem_setting_name(k: i32) -> *const c_char {
    McSetting::from_index(k).map_or(std::ptr::null(), |s| s.c_name().as_ptr())
}

/// Keyword `k` of `model mc_advanced` that only `mcdem run` implements
/// (`physics::mc_settings::ENGINE_ONLY`), a static NUL-terminated string; null past the last one
/// (the shim loops until it is).
#[no_mangle]
pub extern "C" fn mcdem_engine_only_setting(k: i32) -> *const c_char {
    usize::try_from(k).ok().and_then(|k| ENGINE_ONLY.get(k)).map_or(std::ptr::null(), |s| s.as_ptr())
}

/// Why the plugin refuses the keywords of [`mcdem_engine_only_setting`] (a static string).
#[no_mangle]
pub extern "C" fn mcdem_engine_only_why() -> *const c_char {
    ENGINE_ONLY_WHY.as_ptr()
}

/// Value of setting `k` when the deck line does not give it (NaN when `k` is not a setting).
#[no_mangle]
pub extern "C" fn mcdem_setting_default(k: i32) -> f64 {
    McSetting::from_index(k).map_or(f64::NAN, McSetting::default_value)
}

fn setting(k: i32) -> Result<McSetting, FfiError> {
    McSetting::from_index(k).ok_or_else(|| param(format!("no model setting with index {k}")))
}

/// Reads the deck word after keyword `k` into `*value` (a choice as 0 or 1); on a bad word
/// `MCDEM_ERR_PARAMETER` with the message both engines print, naming keyword, word and what is
/// expected.
/// # Safety
/// `word` must be null (rejected) or a NUL-terminated string; `value` null (rejected) or valid.
#[no_mangle]
pub unsafe extern "C" fn mcdem_setting_parse(k: i32, word: *const c_char, value: *mut f64) -> i32 {
    guard(|| {
        let s = setting(k)?;
        let word = non_null(word, "word")?;
        // SAFETY: non-null, NUL-terminated by the caller's promise.
        let word = unsafe { std::ffi::CStr::from_ptr(word) }.to_string_lossy();
        *non_null_mut(value, "value")? = s.parse(&word).map_err(param)?;
        Ok(())
    })
}

/// Checks a wall's settings against the pair style's (`MCDEM_SETTINGS` entries each; `given[k]`
/// non-zero when the wall line gave setting `k`): `MCDEM_ERR_PARAMETER` naming the first shared
/// setting that differs.
/// # Safety
/// Each pointer must be null (rejected) or valid for `MCDEM_SETTINGS` elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_settings_check_wall(
    wall: *const f64,
    given: *const u8,
    pair: *const f64,
) -> i32 {
    guard(|| {
        let n = MC_SETTINGS.len();
        let (wall, given, pair) =
            (non_null(wall, "wall")?, non_null(given, "given")?, non_null(pair, "pair")?);
        // SAFETY: each holds MCDEM_SETTINGS elements by the caller's promise.
        let (wall, given, pair) = unsafe {
            (
                std::slice::from_raw_parts(wall, n),
                std::slice::from_raw_parts(given, n),
                std::slice::from_raw_parts(pair, n),
            )
        };
        let arr = |x: &[f64]| -> [f64; 4] { std::array::from_fn(|k| x[k]) };
        let given: [bool; 4] = std::array::from_fn(|k| given[k] != 0);
        check_wall(&arr(wall), &given, &arr(pair)).map_err(param)
    })
}

/// The material table of `n` atom types (walls are atom types too): per type E [Pa], ν, γ and
/// MPR with the `cap` (`MCDEM_CAP_ABS` or `MCDEM_CAP_SIGNED`) into `params[n]` (radius 1: the
/// caller sets each particle's own), and the pair coefficients of every ordered type pair from the
/// `peratomtypepair` tables `restitution[n*n]` and `friction[n*n]` (null: frictionless) into
/// `coeffs[n*n]`, row-major. A bad value gives `MCDEM_ERR_PARAMETER` naming the LIGGGHTS property
/// and the atom type(s).
/// # Safety
/// Each pointer must be null (rejected, `friction` excepted) or valid for the stated count.
#[no_mangle]
#[allow(clippy::too_many_arguments)] // the C signature: one array per LIGGGHTS property
pub unsafe extern "C" fn mcdem_material_table(
    n: usize,
    youngs: *const f64,
    poisson: *const f64,
    gamma: *const f64,
    mpr: *const f64,
    cap: i32,
    restitution: *const f64,
    friction: *const f64,
    params: *mut mcdem_mc_params,
    coeffs: *mut mcdem_pair_coeffs,
) -> i32 {
    guard(|| {
        let test = match cap {
            MCDEM_CAP_ABS => MprTest::Abs,
            MCDEM_CAP_SIGNED => MprTest::Signed,
            other => return Err(param(format!("invalid cap = {other}: must be 1 (abs) or 2 (signed)"))),
        };
        let per_type = |p: *const f64, name: &str| -> Result<&[f64], FfiError> {
            // SAFETY: non-null, n elements by the caller's promise.
            Ok(unsafe { std::slice::from_raw_parts(non_null(p, name)?, n) })
        };
        let (e, nu, g, m) = (
            per_type(youngs, "youngs")?,
            per_type(poisson, "poisson")?,
            per_type(gamma, "gamma")?,
            per_type(mpr, "mpr")?,
        );
        // SAFETY: non-null, n*n elements by the caller's promise; a null friction is μ = 0.
        let rest = unsafe { std::slice::from_raw_parts(non_null(restitution, "restitution")?, n * n) };
        let zeros = vec![0.0; n * n];
        let fric = match friction.is_null() {
            true => &zeros[..],
            false => unsafe { std::slice::from_raw_parts(friction, n * n) },
        };
        non_null_mut(params, "params")?;
        non_null_mut(coeffs, "coeffs")?;
        let mut materials = Vec::with_capacity(n);
        for t in 0..n {
            let mat = Material::new(e[t], nu[t], g[t], Some((m[t], test))).map_err(|err| {
                param(format!("invalid {} for atom type {} ({err})", err.property(), t + 1))
            })?;
            materials.push(mat);
        }
        let table = pair_table(&materials, rest, fric).map_err(|err| param(format!("atom {err}")))?;
        // SAFETY: non-null, n and n*n elements by the caller's promise.
        let (params, coeffs) = unsafe {
            (std::slice::from_raw_parts_mut(params, n), std::slice::from_raw_parts_mut(coeffs, n * n))
        };
        for (t, p) in params.iter_mut().enumerate() {
            *p = mcdem_mc_params {
                radius: 1.0,
                youngs_modulus: e[t],
                poisson_ratio: nu[t],
                gamma: g[t],
                mpr: m[t],
                cap,
            };
        }
        for (c, t) in coeffs.iter_mut().zip(table) {
            *c = mcdem_pair_coeffs {
                e_star: t.e_star,
                g_star: t.g_star,
                beta: t.beta,
                friction: t.friction,
                damping_ratio_t_n: t.damping_ratio_t_n,
            };
        }
        Ok(())
    })
}

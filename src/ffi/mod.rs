//! C ABI over the physics core, for the LIGGGHTS shim and any other C/C++ caller. The header is
//! `native/mcdem.h`; a test compiles a C program against it so header and library cannot drift.
//!
//! Every entry point validates its pointers and parameters, returns an error code, and keeps the
//! message for [`mcdem_last_error`]. No panic crosses the boundary: each body runs under
//! `catch_unwind` and a panic becomes `MCDEM_ERR_INTERNAL`.

use std::cell::RefCell;
use std::os::raw::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::physics::contact_set::{
    radius_changes, ContactLoad, InfluenceCache, KernelError, KernelSummary, McParams,
};
use crate::physics::ghods2022::{Cap, MprTest};
use crate::physics::hertz;
use crate::physics::material::{check_poisson_ratio, check_youngs_modulus, Material, PairCoeffs};
use crate::physics::pair::{self, Body, ContactError, ContactForce, PairLanes, WallPoint};
use crate::physics::Vec3;

mod setup;
pub use setup::*;

pub const MCDEM_OK: i32 = 0;
pub const MCDEM_ERR_NULL: i32 = 1;
pub const MCDEM_ERR_PARAMETER: i32 = 2;
pub const MCDEM_ERR_NON_FINITE: i32 = 3;
pub const MCDEM_ERR_OVERLAP: i32 = 4;
pub const MCDEM_ERR_COINCIDENT: i32 = 5;
pub const MCDEM_ERR_INTERNAL: i32 = 6;

pub const MCDEM_CAP_NONE: i32 = 0;
pub const MCDEM_CAP_ABS: i32 = 1;
pub const MCDEM_CAP_SIGNED: i32 = 2;

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

pub(crate) struct FfiError(pub(crate) i32, pub(crate) String);

fn set_error(msg: String) {
    LAST_ERROR.with(|e| *e.borrow_mut() = msg);
}

/// Runs `f`, turning errors and panics into codes and a stored message.
pub(crate) fn guard(f: impl FnOnce() -> Result<(), FfiError>) -> i32 {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => MCDEM_OK,
        Ok(Err(FfiError(code, msg))) => {
            set_error(msg);
            code
        }
        Err(_) => {
            set_error("internal error in mcdem (panic caught at the C boundary)".into());
            MCDEM_ERR_INTERNAL
        }
    }
}

pub(crate) fn param<E: std::fmt::Display>(e: E) -> FfiError {
    FfiError(MCDEM_ERR_PARAMETER, e.to_string())
}

fn contact_err(e: ContactError) -> FfiError {
    let code = match e {
        ContactError::OverlapBeyondRadius { .. } => MCDEM_ERR_OVERLAP,
        ContactError::CoincidentCentres => MCDEM_ERR_COINCIDENT,
        ContactError::NonFinite => MCDEM_ERR_NON_FINITE,
    };
    FfiError(code, e.to_string())
}

pub(crate) fn non_null<'a, T>(p: *const T, name: &str) -> Result<&'a T, FfiError> {
    // SAFETY: the caller promises a valid pointer or null; null is rejected here.
    unsafe { p.as_ref() }.ok_or_else(|| FfiError(MCDEM_ERR_NULL, format!("{name} is a null pointer")))
}

pub(crate) fn non_null_mut<'a, T>(p: *mut T, name: &str) -> Result<&'a mut T, FfiError> {
    // SAFETY: as above, for an exclusive pointer.
    unsafe { p.as_mut() }.ok_or_else(|| FfiError(MCDEM_ERR_NULL, format!("{name} is a null pointer")))
}

/// Particle-side parameters of the multi-contact kernel.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct mcdem_mc_params {
    pub radius: f64,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub gamma: f64,
    /// Maximum penetration ratio; read only when `cap` is not `MCDEM_CAP_NONE`.
    pub mpr: f64,
    /// `MCDEM_CAP_NONE` (standard MC), `MCDEM_CAP_ABS` or `MCDEM_CAP_SIGNED` (advanced MC).
    pub cap: i32,
}

/// One contact of a particle: point relative to the centre [m], previous-step normal force [N].
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct mcdem_contact_load {
    pub point: [f64; 3],
    pub force: f64,
}

/// Pair coefficients (App. C), built by [`mcdem_pair_coeffs_new`] or [`mcdem_material_table`].
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct mcdem_pair_coeffs {
    pub e_star: f64,
    pub g_star: f64,
    pub beta: f64,
    pub friction: f64,
    /// √(4G*/E*), derived once here so that a contact pays no square root and division for it.
    pub damping_ratio_t_n: f64,
}

/// Output of the Hertz normal sub-model.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct mcdem_normal_force {
    pub force: f64,
    pub elastic: f64,
    pub kn: f64,
    pub kt: f64,
    pub gamma_n: f64,
    pub gamma_t: f64,
}

/// Kinematic state of a body.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct mcdem_body {
    pub x: [f64; 3],
    pub v: [f64; 3],
    pub omega: [f64; 3],
    pub radius: f64,
    pub mass: f64,
}

/// Result of a pair or wall force evaluation.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct mcdem_contact_force {
    pub force_i: [f64; 3],
    pub torque_i: [f64; 3],
    pub torque_j: [f64; 3],
    pub en: [f64; 3],
    pub point: [f64; 3],
    pub overlap: f64,
    pub normal_force: f64,
    /// 1 when the bodies are in contact, 0 otherwise (all other fields then zero).
    pub in_contact: i32,
}

fn v3(a: &[f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

fn a3(v: &Vec3) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

fn body(b: &mcdem_body) -> Body {
    Body { x: v3(&b.x), v: v3(&b.v), omega: v3(&b.omega), radius: b.radius, mass: b.mass }
}

/// Whether a damping ratio √(4G*/E*) is one that `mcdem_pair_coeffs_new` derived (finite, > 0) rather
/// than the zero of a struct filled by hand.
fn derived_by_coeffs_new(damping_ratio_t_n: f64) -> bool {
    damping_ratio_t_n > 0.0 && damping_ratio_t_n.is_finite()
}

fn coeffs(c: &mcdem_pair_coeffs) -> Result<PairCoeffs, FfiError> {
    // A struct filled by hand rather than by mcdem_pair_coeffs_new lacks the derived ratio, which
    // would silently remove the tangential damping.
    if !derived_by_coeffs_new(c.damping_ratio_t_n) {
        return Err(FfiError(
            MCDEM_ERR_PARAMETER,
            format!(
                "pair coefficients not built by mcdem_pair_coeffs_new (damping_ratio_t_n = {:e})",
                c.damping_ratio_t_n
            ),
        ));
    }
    // The C ABI's pair functions are the history model (the plugin leaves the tangential
    // sub-model to LIGGGHTS).
    Ok(PairCoeffs {
        e_star: c.e_star,
        g_star: c.g_star,
        beta: c.beta,
        friction: c.friction,
        tangential: crate::physics::hertz::Tangential::History,
        normal: crate::physics::NormalLaw::Hertz,
        cohesion: 0.0,
        tangential_reduce: false,
        rolling_friction: 0.0,
        rolling_law: crate::physics::RollingLaw::Cdt,
        damping_ratio_t_n: c.damping_ratio_t_n,
    })
}

fn write_contact(out: &mut mcdem_contact_force, r: Option<ContactForce>) {
    *out = match r {
        None => mcdem_contact_force::default(),
        Some(c) => mcdem_contact_force {
            force_i: a3(&c.force_i),
            torque_i: a3(&c.torque_i),
            torque_j: a3(&c.torque_j),
            en: a3(&c.en),
            point: a3(&c.point),
            overlap: c.overlap,
            normal_force: c.normal.force,
            in_contact: 1,
        },
    };
}

/// Converts C parameters into validated core parameters.
fn mc_params(p: &mcdem_mc_params) -> Result<McParams, FfiError> {
    let cap = match p.cap {
        MCDEM_CAP_NONE => None,
        MCDEM_CAP_ABS => Some(Cap { mpr: p.mpr, test: MprTest::Abs }),
        MCDEM_CAP_SIGNED => Some(Cap { mpr: p.mpr, test: MprTest::Signed }),
        other => {
            return Err(FfiError(
                MCDEM_ERR_PARAMETER,
                format!("invalid cap = {other}: must be 0 (none), 1 (abs) or 2 (signed)"),
            ))
        }
    };
    let params = McParams {
        radius: p.radius,
        youngs_modulus: p.youngs_modulus,
        poisson_ratio: p.poisson_ratio,
        gamma: p.gamma,
        cap,
    };
    params.validate().map_err(param)?;
    Ok(params)
}

/// Checks the parameters of one particle type; returns `MCDEM_ERR_PARAMETER` with a message that
/// names the parameter when one is out of range. The LIGGGHTS shim calls it once at setup.
/// # Safety
/// Each pointer must be null (rejected with `MCDEM_ERR_NULL`) or valid for the documented
/// number of elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_validate_mc_params(params: *const mcdem_mc_params) -> i32 {
    guard(|| mc_params(non_null(params, "params")?).map(|_| ()))
}

/// Radius change Δ_c [m] of one particle at each of its `n` contacts (Eq. 2, with the Eq. 3 cap
/// when `params->cap` is set). `delta` and `hertz_fallback` must hold `n` entries; `n_fallback`
/// (may be null) receives the number of contacts the cap switched back to Hertz.
/// # Safety
/// Each pointer must be null (rejected with `MCDEM_ERR_NULL`) or valid for the documented
/// number of elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_radius_changes(
    params: *const mcdem_mc_params,
    contacts: *const mcdem_contact_load,
    n: usize,
    delta: *mut f64,
    hertz_fallback: *mut u8,
    n_fallback: *mut usize,
) -> i32 {
    // SAFETY: forwarded from the caller's promise.
    unsafe { kernel_call(params, contacts, n, delta, hertz_fallback, n_fallback, radius_changes) }
}

/// A store of influence matrices for the geometry tolerance (see [`InfluenceCache`]).
#[allow(non_camel_case_types)] // the C name, as the other C types here
pub struct mcdem_influence_cache(InfluenceCache);

/// New store for a geometry tolerance ≥ 0 (a fraction of the particle radius); null on bad input,
/// with the reason in `mcdem_last_error`. Free it with `mcdem_influence_cache_free`.
#[no_mangle]
pub extern "C" fn mcdem_influence_cache_new(tolerance: f64) -> *mut mcdem_influence_cache {
    match InfluenceCache::new(tolerance) {
        Ok(c) => Box::into_raw(Box::new(mcdem_influence_cache(c))),
        Err(e) => {
            set_error(e.to_string());
            std::ptr::null_mut()
        }
    }
}

/// Frees a store from `mcdem_influence_cache_new` (null is ignored).
/// # Safety
/// `cache` must come from `mcdem_influence_cache_new` and not be used afterwards.
#[no_mangle]
pub unsafe extern "C" fn mcdem_influence_cache_free(cache: *mut mcdem_influence_cache) {
    if !cache.is_null() {
        // SAFETY: created by Box::into_raw in mcdem_influence_cache_new, freed once.
        drop(unsafe { Box::from_raw(cache) });
    }
}

/// Influence matrices (re)computed by this store so far.
/// # Safety
/// `cache` must be null (gives 0) or a live store.
#[no_mangle]
pub unsafe extern "C" fn mcdem_influence_cache_recomputed(cache: *const mcdem_influence_cache) -> u64 {
    // SAFETY: null or a live store, by the caller's promise.
    unsafe { cache.as_ref() }.map_or(0, |c| c.0.recomputed)
}

/// `mcdem_radius_changes` through the influence matrix kept in `slot` of `cache` (any stable
/// per-particle number, e.g. a local index): reused while the points are within the store's
/// tolerance of those it was computed from, recomputed otherwise.
/// # Safety
/// As `mcdem_radius_changes`; `cache` must be a live store used by one thread at a time.
#[no_mangle]
pub unsafe extern "C" fn mcdem_radius_changes_cached(
    cache: *mut mcdem_influence_cache,
    slot: usize,
    params: *const mcdem_mc_params,
    contacts: *const mcdem_contact_load,
    n: usize,
    delta: *mut f64,
    hertz_fallback: *mut u8,
    n_fallback: *mut usize,
) -> i32 {
    // SAFETY: null or a live store used by this thread only, by the caller's promise.
    let Some(cache) = (unsafe { cache.as_mut() }) else {
        set_error("cache is a null pointer".into());
        return MCDEM_ERR_NULL;
    };
    // SAFETY: forwarded from the caller's promise.
    unsafe {
        kernel_call(params, contacts, n, delta, hertz_fallback, n_fallback, |p, cs, d, fb| {
            cache.0.radius_changes(slot, p, cs, d, fb)
        })
    }
}

/// The checks and buffer views shared by the kernel entry points.
/// # Safety
/// As `mcdem_radius_changes`.
unsafe fn kernel_call(
    params: *const mcdem_mc_params,
    contacts: *const mcdem_contact_load,
    n: usize,
    delta: *mut f64,
    hertz_fallback: *mut u8,
    n_fallback: *mut usize,
    kernel: impl FnOnce(&McParams, &[ContactLoad], &mut [f64], &mut [bool]) -> Result<KernelSummary, KernelError>,
) -> i32 {
    guard(|| {
        let p = mc_params(non_null(params, "params")?)?;
        if n == 0 {
            if let Some(nf) = unsafe { n_fallback.as_mut() } {
                *nf = 0;
            }
            return Ok(());
        }
        non_null(contacts, "contacts")?;
        non_null_mut(delta, "delta")?;
        non_null_mut(hertz_fallback, "hertz_fallback")?;
        // SAFETY: non-null, and the caller guarantees `n` elements each. `mcdem_contact_load` and
        // `ContactLoad` share one #[repr(C)] layout (asserted in the tests); the flag buffer is
        // zeroed as bytes before it is viewed as `bool`, so every byte is a valid `bool`.
        let (cs, d, fb) = unsafe {
            std::ptr::write_bytes(hertz_fallback, 0, n);
            (
                std::slice::from_raw_parts(contacts.cast::<ContactLoad>(), n),
                std::slice::from_raw_parts_mut(delta, n),
                std::slice::from_raw_parts_mut(hertz_fallback.cast::<bool>(), n),
            )
        };
        let s = kernel(&p, cs, d, fb).map_err(|e| FfiError(MCDEM_ERR_NON_FINITE, e.to_string()))?;
        if let Some(nf) = unsafe { n_fallback.as_mut() } {
            *nf = s.fallbacks;
        }
        Ok(())
    })
}

/// Pair coefficients from the two materials (E [Pa], ν), restitution e ∈ (0, 1] and friction μ ≥ 0.
/// # Safety
/// Each pointer must be null (rejected with `MCDEM_ERR_NULL`) or valid for the documented
/// number of elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_pair_coeffs_new(
    youngs_i: f64,
    poisson_i: f64,
    youngs_j: f64,
    poisson_j: f64,
    restitution: f64,
    friction: f64,
    out: *mut mcdem_pair_coeffs,
) -> i32 {
    guard(|| {
        let out = non_null_mut(out, "out")?;
        check_youngs_modulus(youngs_i).map_err(param)?;
        check_youngs_modulus(youngs_j).map_err(param)?;
        check_poisson_ratio(poisson_i).map_err(param)?;
        check_poisson_ratio(poisson_j).map_err(param)?;
        let mi = Material::hertz(youngs_i, poisson_i).map_err(param)?;
        let mj = Material::hertz(youngs_j, poisson_j).map_err(param)?;
        let c = PairCoeffs::new(&mi, &mj, restitution, friction).map_err(param)?;
        *out = mcdem_pair_coeffs {
            e_star: c.e_star,
            g_star: c.g_star,
            beta: c.beta,
            friction: c.friction,
            damping_ratio_t_n: c.damping_ratio_t_n,
        };
        Ok(())
    })
}

/// Hertz normal sub-model (Eq. 5, App. C) for overlap `delta` [m], effective radius and mass, and
/// normal relative velocity `vn` [m/s]. A non-positive overlap gives zero force.
/// # Safety
/// Each pointer must be null (rejected with `MCDEM_ERR_NULL`) or valid for the documented
/// number of elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_hertz_normal(
    coeffs_: *const mcdem_pair_coeffs,
    delta: f64,
    reff: f64,
    meff: f64,
    vn: f64,
    out: *mut mcdem_normal_force,
) -> i32 {
    guard(|| {
        let c = coeffs(non_null(coeffs_, "coeffs")?)?;
        let out = non_null_mut(out, "out")?;
        let n = hertz::normal(&c, delta, reff, meff, vn);
        if !(n.force.is_finite() && n.kt.is_finite() && n.gamma_n.is_finite()) {
            return Err(FfiError(
                MCDEM_ERR_NON_FINITE,
                format!("Hertz normal force not finite (delta = {delta:e}, reff = {reff:e}, meff = {meff:e}, vn = {vn:e})"),
            ));
        }
        *out = mcdem_normal_force {
            force: n.force,
            elastic: n.elastic,
            kn: n.kn,
            kt: n.kt,
            gamma_n: n.gamma_n,
            gamma_t: n.gamma_t,
        };
        Ok(())
    })
}

/// Particle–particle contact force with radius changes `dri`, `drj` [m]; `shear` is the contact's
/// tangential history (3 doubles, updated in place).
/// # Safety
/// Each pointer must be null (rejected with `MCDEM_ERR_NULL`) or valid for the documented
/// number of elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_particle_particle(
    coeffs_: *const mcdem_pair_coeffs,
    bi: *const mcdem_body,
    bj: *const mcdem_body,
    dri: f64,
    drj: f64,
    dt: f64,
    shear: *mut f64,
    out: *mut mcdem_contact_force,
) -> i32 {
    guard(|| {
        let c = coeffs(non_null(coeffs_, "coeffs")?)?;
        let (bi, bj) = (body(non_null(bi, "bi")?), body(non_null(bj, "bj")?));
        let out = non_null_mut(out, "out")?;
        non_null_mut(shear, "shear")?;
        // SAFETY: non-null, three doubles by contract.
        let sh = unsafe { std::slice::from_raw_parts_mut(shear, 3) };
        let mut s = Vec3::new(sh[0], sh[1], sh[2]);
        let r = pair::particle_particle(&c, &bi, &bj, dri, drj, dt, &mut s).map_err(contact_err)?;
        sh.copy_from_slice(s.as_slice());
        write_contact(out, r);
        Ok(())
    })
}

/// The range check of the contact law for callers that compute the overlap themselves (the LIGGGHTS
/// shim's one-contact path): `MCDEM_ERR_OVERLAP` with the core's message when `overlap` [m] reached
/// `rmin` [m], the smaller original radius of the two bodies (the particle's own for a wall).
#[no_mangle]
pub extern "C" fn mcdem_check_overlap(overlap: f64, rmin: f64) -> i32 {
    guard(|| pair::overlap_error(overlap, rmin).map_or(Ok(()), |e| Err(contact_err(e))))
}

/// Size in bytes of `mcdem_pair_batch` as this library lays it out (the C header declares the same
/// fields; callers check the two agree before the first batch).
#[no_mangle]
pub extern "C" fn mcdem_pair_batch_size() -> usize {
    std::mem::size_of::<PairLanes>()
}

/// Evaluates lanes `0..used` of a batch of overlapping particle pairs (`mcdem_pair_batch`, the
/// core's [`PairLanes`]): the same contact as [`mcdem_particle_particle`] lane by lane, bit for bit,
/// four lanes per instruction where the CPU has AVX2. Lanes `used..` are overwritten with copies of
/// lane 0. A lane whose `ok` comes out 0 cannot be integrated (overlap reached a radius, coincident
/// centres, or a non-finite result): the caller asks `mcdem_particle_particle` for the reason.
/// # Safety
/// `batch` must be null (rejected with `MCDEM_ERR_NULL`) or point to a writable, 64-byte aligned
/// `mcdem_pair_batch`.
#[no_mangle]
pub unsafe extern "C" fn mcdem_pair_batch_evaluate(batch: *mut PairLanes, used: usize, dt: f64) -> i32 {
    guard(|| {
        if batch.is_null() {
            return Err(FfiError(MCDEM_ERR_NULL, "batch is a null pointer".into()));
        }
        if batch as usize % std::mem::align_of::<PairLanes>() != 0 {
            return Err(FfiError(MCDEM_ERR_PARAMETER, "batch is not 64-byte aligned".into()));
        }
        // SAFETY: non-null and aligned; `ok` is an output whose bytes the caller may have left
        // uninitialised, so it is given valid booleans before the struct is borrowed.
        let b = unsafe {
            std::ptr::addr_of_mut!((*batch).ok).write([false; pair::LANES]);
            &mut *batch
        };
        if used == 0 || used > pair::LANES {
            return Err(FfiError(
                MCDEM_ERR_PARAMETER,
                format!("batch lanes used = {used}, must be 1 to {}", pair::LANES),
            ));
        }
        // A lane without the derived damping ratio was not filled from mcdem_pair_coeffs_new.
        if let Some(l) = (0..used).find(|&l| !derived_by_coeffs_new(b.coeffs.damping_ratio_t_n[l])) {
            return Err(FfiError(
                MCDEM_ERR_PARAMETER,
                format!(
                    "batch lane {l}: pair coefficients not built by mcdem_pair_coeffs_new (damping_ratio_t_n = {:e})",
                    b.coeffs.damping_ratio_t_n[l]
                ),
            ));
        }
        b.pad_from_first(used);
        b.evaluate(dt);
        Ok(())
    })
}

/// Particle–wall contact force: `wall_point` is the closest wall point to the centre and
/// `wall_velocity` its velocity; `dri` the particle's radius change at this contact.
/// # Safety
/// Each pointer must be null (rejected with `MCDEM_ERR_NULL`) or valid for the documented
/// number of elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_particle_wall(
    coeffs_: *const mcdem_pair_coeffs,
    bi: *const mcdem_body,
    wall_point: *const f64,
    wall_velocity: *const f64,
    dri: f64,
    dt: f64,
    shear: *mut f64,
    out: *mut mcdem_contact_force,
) -> i32 {
    guard(|| {
        let c = coeffs(non_null(coeffs_, "coeffs")?)?;
        let bi = body(non_null(bi, "bi")?);
        let out = non_null_mut(out, "out")?;
        non_null(wall_point, "wall_point")?;
        non_null(wall_velocity, "wall_velocity")?;
        non_null_mut(shear, "shear")?;
        // SAFETY: non-null, three doubles each by contract.
        let (wp, wv, sh) = unsafe {
            (
                std::slice::from_raw_parts(wall_point, 3),
                std::slice::from_raw_parts(wall_velocity, 3),
                std::slice::from_raw_parts_mut(shear, 3),
            )
        };
        let wall = WallPoint { point: Vec3::from_column_slice(wp), velocity: Vec3::from_column_slice(wv) };
        let mut s = Vec3::new(sh[0], sh[1], sh[2]);
        let r = pair::particle_wall(&c, &bi, &wall, dri, dt, &mut s).map_err(contact_err)?;
        sh.copy_from_slice(s.as_slice());
        write_contact(out, r);
        Ok(())
    })
}

/// Copies the last error message of this thread into `buf` (NUL-terminated, truncated to `len`).
/// Returns the full message length in bytes (without the NUL).
/// # Safety
/// Each pointer must be null (rejected with `MCDEM_ERR_NULL`) or valid for the documented
/// number of elements.
#[no_mangle]
pub unsafe extern "C" fn mcdem_last_error(buf: *mut c_char, len: usize) -> usize {
    LAST_ERROR.with(|e| {
        let msg = e.borrow();
        let bytes = msg.as_bytes();
        if !buf.is_null() && len > 0 {
            let n = bytes.len().min(len - 1);
            // SAFETY: buf holds `len` bytes by contract; we write n + 1 ≤ len.
            unsafe {
                std::ptr::copy_nonoverlapping(bytes.as_ptr(), buf.cast::<u8>(), n);
                *buf.add(n) = 0;
            }
        }
        bytes.len()
    })
}

/// Library version, a static NUL-terminated string.
#[no_mangle]
pub extern "C" fn mcdem_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

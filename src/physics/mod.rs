//! The contact-physics core: every engine in mcdem (the LIGGGHTS plugin through the C ABI, the
//! standalone DEM, the nonlocal reference) calls these functions and nothing else for contact forces.
//!
//! One file per published model, named after the paper, so a reader finds the formula where the
//! citation is:
//! - [`hertz`]: Hertz normal force with viscous damping and the history tangential force
//!   (Ghods et al. 2022, App. C; identical to LIGGGHTS `hertz tangential history`).
//! - [`hooke`]: LIGGGHTS' linear `model hooke` (normal_model_hooke.h), with the same tangential
//!   sub-models.
//! - [`hooke_hysteresis`]: LIGGGHTS' `model hooke/hysteresis` (Walton–Braun loop with adhesion).
//! - [`sjkr`]: LIGGGHTS' `cohesion sjkr` (simplified JKR cohesion).
//! - [`rolling_cdt`]: LIGGGHTS' `rolling_friction cdt` (constant directional rolling torque).
//! - [`rolling_epsd`]: LIGGGHTS' `rolling_friction epsd`/`epsd2` (elastic–plastic rolling spring).
//! - [`brodu2015`]: the standard multi-contact displacement (Brodu et al. 2015; Ghods et al. Eq. 2).
//! - [`ghods2022`]: the advanced multi-contact switch (Ghods et al. Eq. 3 and App. A).
//! - [`contact_set`]: the per-particle kernel that applies Eq. 2 (and Eq. 3) to all contacts of one particle.
//! - [`pair`]: contact geometry computed once, then the normal and tangential sub-models, for
//!   particle–particle and particle–wall contacts alike.
//!
//! Pure functions on plain data: no I/O and no allocation in the hot paths.

pub mod brodu2015;
pub mod contact_set;
pub mod ghods2022;
pub mod hertz;
pub mod hooke;
pub mod hooke_hysteresis;
pub mod lanes;
pub mod material;
pub mod mc_settings;
pub mod model_kind;
pub mod pair;
pub mod rolling_cdt;
pub mod rolling_epsd;
pub mod sjkr;
pub mod timestep;

/// Whether this CPU has AVX2. The compiler vectorises loops with square roots and divisions only
/// under AVX2's cost model, not under the x86-64 baseline's; the batch of pair forces is therefore
/// compiled a second time for AVX2, and the multi-contact kernel runs on explicit AVX2 lanes
/// ([`lanes`]), both chosen here at run time. Rust never fuses a product and a sum on its own, so
/// both paths give the same results bit for bit.
#[inline]
pub fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        !PORTABLE.load(std::sync::atomic::Ordering::Relaxed) && std::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

static PORTABLE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Makes [`avx2`] answer false from now on, in this process: the baseline code paths then run
/// whatever the CPU, so a test can compare them with the AVX2 ones (they must agree bit for bit).
#[doc(hidden)]
pub fn use_portable_code() {
    PORTABLE.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// 3-vector used throughout the core (SI units).
pub type Vec3 = nalgebra::Vector3<f64>;

pub use contact_set::{ContactLoad, ContactSetKernel, McParams};
pub use ghods2022::{Cap, MprTest};
pub use material::{Hooke, Hysteresis, Material, MaterialError, NormalLaw, PairCoeffs, RollingLaw};

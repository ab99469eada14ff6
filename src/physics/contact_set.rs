//! Per-particle contact-set kernel: applies Eq. 2 (standard MC) and optionally the Eq. 3 cap
//! (advanced MC) to every contact of one particle, giving the radius change Δ_c the pair loop uses
//! at contact c (r_i' = r_i + Δ_c, SPEC §2).
//!
//! The caller owns every buffer: no allocation per call. A particle with fewer than two loaded
//! contacts has no neighbour terms and returns at once with all Δ = 0.

use std::fmt;

use super::brodu2015::{bracket, compliance_prefactor, MIN_CHORD};
use super::ghods2022::Cap;
use super::material::{
    check, check_gamma, check_mpr, check_poisson_ratio, check_youngs_modulus, Material, MaterialError,
};
use super::Vec3;

/// Relative force threshold below which a contact is treated as unloaded: F_k ≤ E r² · 1e-14.
/// The same threshold as LIGGGHTS `fix multicontact/halfspace`, so both codes agree on which
/// contacts enter the sum (a contact that merely touches carries no load and deforms nothing).
pub const LOADED_FORCE_FACTOR: f64 = 1e-14;

/// The particle-side parameters of the kernel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct McParams {
    /// Original (undeformed) radius r_i [m].
    pub radius: f64,
    /// Particle's own Young's modulus E [Pa] (not E*).
    pub youngs_modulus: f64,
    /// Particle's own Poisson ratio ν.
    pub poisson_ratio: f64,
    /// Geometric prefactor γ.
    pub gamma: f64,
    /// Advanced-MC cap; `None` is standard MC.
    pub cap: Option<Cap>,
}

impl McParams {
    /// Validated parameters for one particle.
    pub fn new(radius: f64, material: &Material) -> Result<Self, MaterialError> {
        let p = Self {
            radius,
            youngs_modulus: material.youngs_modulus,
            poisson_ratio: material.poisson_ratio,
            gamma: material.gamma,
            cap: material.cap,
        };
        p.validate()?;
        Ok(p)
    }

    /// Checks every field (the C ABI and the JSON front end build the struct directly).
    pub fn validate(&self) -> Result<(), MaterialError> {
        check("radius", self.radius, "finite and > 0", |v| v > 0.0)?;
        check_youngs_modulus(self.youngs_modulus)?;
        check_poisson_ratio(self.poisson_ratio)?;
        check_gamma(self.gamma)?;
        if let Some(cap) = self.cap {
            check_mpr(cap.mpr)?;
        }
        Ok(())
    }

    /// Force below which a contact counts as unloaded (see [`LOADED_FORCE_FACTOR`]).
    #[inline]
    pub fn loaded_threshold(&self) -> f64 {
        self.youngs_modulus * self.radius * self.radius * LOADED_FORCE_FACTOR
    }
}

/// One contact of the particle as the kernel sees it. `#[repr(C)]`: the C ABI passes arrays of
/// `mcdem_contact_load { double point[3]; double force; }` straight through.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLoad {
    /// Contact point relative to the particle centre [m].
    pub point: Vec3,
    /// Normal force magnitude of this contact at the previous time step [N] (Eq. 2 is lagged).
    pub force: f64,
}

/// What one kernel call found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct KernelSummary {
    /// Contacts whose force is above the loaded threshold.
    pub loaded: usize,
    /// Contacts switched back to Hertz by the cap.
    pub fallbacks: usize,
}

/// A kernel call that cannot give finite radius changes.
#[derive(Debug, Clone, PartialEq)]
pub enum KernelError {
    /// Output buffers shorter than the contact list.
    BufferTooShort { contacts: usize, delta: usize, fallback: usize },
    /// A contact point or force is not finite.
    NonFiniteInput { contact: usize },
    /// The sum overflowed (forces far outside any physical range).
    NonFiniteResult { contact: usize },
}

impl fmt::Display for KernelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KernelError::BufferTooShort { contacts, delta, fallback } => write!(
                f,
                "output buffers too short: {contacts} contacts, delta has {delta}, hertz_fallback has {fallback}"
            ),
            KernelError::NonFiniteInput { contact } => {
                write!(f, "contact {contact}: point or force is not finite")
            }
            KernelError::NonFiniteResult { contact } => write!(
                f,
                "contact {contact}: radius change is not finite (forces outside any physical range)"
            ),
        }
    }
}

impl std::error::Error for KernelError {}

/// Unit-free helper: the contact-set kernel as a value, so engines can hold one per material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSetKernel {
    pub params: McParams,
}

impl ContactSetKernel {
    pub fn new(params: McParams) -> Result<Self, MaterialError> {
        params.validate()?;
        Ok(Self { params })
    }

    /// See [`radius_changes`].
    pub fn run(
        &self,
        contacts: &[ContactLoad],
        delta: &mut [f64],
        hertz_fallback: &mut [bool],
    ) -> Result<KernelSummary, KernelError> {
        radius_changes(&self.params, contacts, delta, hertz_fallback)
    }
}

/// Contact counts up to which the kernel keeps its per-contact scratch on the stack.
const STACK_CONTACTS: usize = 48;

/// Sums the Eq. 2 terms at every contact, applying the cap; returns the number of contacts
/// switched back to Hertz.
///
/// Each unordered pair (c, k) is visited once: the chord, its length and direction serve both
/// terms (k on c and c on k; the reverse direction is the exact negation, so both terms are the
/// same doubles as when computed separately). Contact c receives its terms in increasing k,
/// exactly the order of a per-contact loop, so Δ_c does not depend on this traversal.
/// `hertz_fallback` doubles as the "tripped" mark while summing.
#[allow(clippy::too_many_arguments)]
#[inline]
fn accumulate(
    contacts: &[ContactLoad],
    normal: impl Fn(usize) -> Option<Vec3>,
    loaded: impl Fn(usize) -> bool,
    pref: f64,
    nu: f64,
    cap: Option<Cap>,
    delta_max: Option<f64>,
    delta: &mut [f64],
    hertz_fallback: &mut [bool],
) -> Result<usize, KernelError> {
    let n = contacts.len();
    let trips = |term: f64| match (cap, delta_max) {
        (Some(cap), Some(dm)) => cap.trips(term, dm),
        _ => false,
    };
    for ci in 0..n {
        let Some(n_c) = normal(ci) else { continue };
        let c = &contacts[ci];
        let c_loaded = loaded(ci);
        for ki in ci + 1..n {
            let k_loaded = loaded(ki);
            if !(c_loaded || k_loaded) {
                continue;
            }
            let Some(n_k) = normal(ki) else { continue };
            let k = &contacts[ki];
            let chord = c.point - k.point;
            let d = chord.norm();
            if d < MIN_CHORD {
                continue;
            }
            let u = chord / d;
            if k_loaded && !hertz_fallback[ci] {
                let term = pref * k.force / d * bracket(&n_k, &n_c, &u, nu);
                if trips(term) {
                    hertz_fallback[ci] = true;
                } else {
                    delta[ci] += term;
                }
            }
            if c_loaded && !hertz_fallback[ki] {
                let term = pref * c.force / d * bracket(&n_c, &n_k, &-u, nu);
                if trips(term) {
                    hertz_fallback[ki] = true;
                } else {
                    delta[ki] += term;
                }
            }
        }
    }
    let mut fallbacks = 0;
    for ci in 0..n {
        if hertz_fallback[ci] {
            delta[ci] = 0.0;
            fallbacks += 1;
        } else if !delta[ci].is_finite() {
            return Err(KernelError::NonFiniteResult { contact: ci });
        }
    }
    Ok(fallbacks)
}

/// Radius change Δ_c (m) of the particle at every contact c, Eq. 2 summed over k ≠ c, with the
/// Eq. 3 cap when `p.cap` is set. `delta[c]` and `hertz_fallback[c]` are written for every contact
/// in input order; a contact that the cap switched to Hertz gets Δ_c = 0 and `hertz_fallback = true`.
///
/// Unloaded contacts (force ≤ [`McParams::loaded_threshold`]) exert no displacement but still
/// receive one: a contact that is just closing already sees the deformation from the others.
pub fn radius_changes(
    p: &McParams,
    contacts: &[ContactLoad],
    delta: &mut [f64],
    hertz_fallback: &mut [bool],
) -> Result<KernelSummary, KernelError> {
    let n = contacts.len();
    if delta.len() < n || hertz_fallback.len() < n {
        return Err(KernelError::BufferTooShort {
            contacts: n,
            delta: delta.len(),
            fallback: hertz_fallback.len(),
        });
    }
    let threshold = p.loaded_threshold();
    let mut loaded = 0;
    for (i, c) in contacts.iter().enumerate() {
        if !(c.force.is_finite() && c.point.iter().all(|x| x.is_finite())) {
            return Err(KernelError::NonFiniteInput { contact: i });
        }
        if c.force > threshold {
            loaded += 1;
        }
    }
    delta[..n].fill(0.0);
    hertz_fallback[..n].fill(false);
    // No loaded contact, a single contact, or γ = 0: no neighbour term for anybody. With exactly
    // one loaded contact the others still receive its displacement (that is how a contact created
    // by radius growth appears, as in LIGGGHTS), which costs one pass over the list.
    if loaded == 0 || n < 2 || p.gamma == 0.0 {
        return Ok(KernelSummary { loaded, fallbacks: 0 });
    }
    let nu = p.poisson_ratio;
    let pref = compliance_prefactor(p.gamma, p.youngs_modulus, nu);
    let delta_max = p.cap.map(|cap| cap.delta_max(p.radius));
    // Inward normals are computed once per contact, on the stack for the usual contact counts
    // (the same expression as when recomputed per term, so results do not depend on the path).
    let is_loaded = |i: usize| contacts[i].force > threshold;
    let fallbacks = if n <= STACK_CONTACTS {
        let mut normals = [Vec3::zeros(); STACK_CONTACTS];
        let mut has_normal = [false; STACK_CONTACTS];
        for (i, c) in contacts.iter().enumerate() {
            let l = c.point.norm();
            if l > 0.0 {
                normals[i] = -c.point / l;
                has_normal[i] = true;
            }
        }
        let normal = |i: usize| if has_normal[i] { Some(normals[i]) } else { None };
        accumulate(contacts, normal, is_loaded, pref, nu, p.cap, delta_max, delta, hertz_fallback)?
    } else {
        let normal = |i: usize| {
            let l = contacts[i].point.norm();
            if l > 0.0 {
                Some(-contacts[i].point / l)
            } else {
                None
            }
        };
        accumulate(contacts, normal, is_loaded, pref, nu, p.cap, delta_max, delta, hertz_fallback)?
    };
    Ok(KernelSummary { loaded, fallbacks })
}

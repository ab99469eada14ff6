//! Per-particle contact-set kernel: applies Eq. 2 (standard MC) and optionally the Eq. 3 cap
//! (advanced MC) to every contact of one particle, giving the radius change Δ_c the pair loop uses
//! at contact c (r_i' = r_i + Δ_c, SPEC §2).
//!
//! The caller owns every buffer: no allocation per call. A particle with fewer than two loaded
//! contacts has no neighbour terms and returns at once with all Δ = 0.

use std::fmt;

use super::brodu2015::{bracket_pair, compliance_prefactor, MIN_CHORD};
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
    let cap = p.cap.map(|cap| (cap, cap.delta_max(p.radius)));
    // Inward normals once per contact (n sqrt instead of n² ); a particle has far fewer than
    // NORMALS_ON_STACK contacts, beyond that they are recomputed per pair instead of allocated.
    const NORMALS_ON_STACK: usize = 32;
    let mut normals = [Vec3::zeros(); NORMALS_ON_STACK];
    let inward = |c: &ContactLoad| {
        let l = c.point.norm();
        if l > 0.0 {
            -c.point / l
        } else {
            Vec3::zeros()
        }
    };
    if n <= NORMALS_ON_STACK {
        for (nv, c) in normals.iter_mut().zip(contacts) {
            *nv = inward(c);
        }
    }
    let normal = |i: usize| if n <= NORMALS_ON_STACK { normals[i] } else { inward(&contacts[i]) };
    // Each unordered pair once: the chord (one sqrt) serves both directions a→b and b→a. `delta`
    // accumulates the sums and `hertz_fallback` the trips; for every target the terms still arrive
    // in increasing source index, so the sum does not depend on how the pairs are visited.
    let add = |target: usize, term: f64, delta: &mut [f64], tripped: &mut [bool]| {
        if let Some((cap, dm)) = cap {
            if cap.trips(term, dm) {
                tripped[target] = true;
            }
        }
        delta[target] += term;
    };
    for (a, ca) in contacts.iter().enumerate() {
        let (pa, fa) = (ca.point, ca.force);
        let na = normal(a);
        for (b, cb) in contacts.iter().enumerate().skip(a + 1) {
            let (pb, fb) = (cb.point, cb.force);
            let (a_loaded, b_loaded) = (fa > threshold, fb > threshold);
            if !(a_loaded || b_loaded) {
                continue;
            }
            let chord = pb - pa;
            let d = chord.norm();
            let nb = normal(b);
            if d < MIN_CHORD || na == Vec3::zeros() || nb == Vec3::zeros() {
                continue;
            }
            let (b_ab, b_ba) = bracket_pair(&na, &nb, &(chord / d), nu);
            if a_loaded {
                add(b, pref * fa / d * b_ab, delta, hertz_fallback);
            }
            if b_loaded {
                add(a, pref * fb / d * b_ba, delta, hertz_fallback);
            }
        }
    }
    let mut fallbacks = 0;
    for (i, (dv, tripped)) in delta[..n].iter_mut().zip(&hertz_fallback[..n]).enumerate() {
        if *tripped {
            *dv = 0.0;
            fallbacks += 1;
        } else if !dv.is_finite() {
            return Err(KernelError::NonFiniteResult { contact: i });
        }
    }
    Ok(KernelSummary { loaded, fallbacks })
}

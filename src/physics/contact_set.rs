//! Per-particle contact-set kernel: applies Eq. 2 (standard MC) and optionally the Eq. 3 cap
//! (advanced MC) to every contact of one particle, giving the radius change Δ_c the pair loop uses
//! at contact c (r_i' = r_i + Δ_c, docs/spec.md §2).
//!
//! The caller owns every buffer: no allocation per call. A particle with fewer than two loaded
//! contacts has no neighbour terms and returns at once with all Δ = 0.

use std::cell::RefCell;
use std::fmt;

use super::brodu2015::{bracket_pair_over_chord, compliance_prefactor};
use super::ghods2022::{Cap, MprTest};
#[cfg(target_arch = "x86_64")]
use super::lanes::F64x4;
use super::lanes::Lane;
use super::material::{
    check, check_gamma, check_mpr, check_poisson_ratio, check_youngs_modulus, Material, MaterialError,
};
use super::Vec3;

/// Relative force threshold below which a contact is treated as unloaded: F_k ≤ E r² · 1e-14.
/// The same threshold as LIGGGHTS `fix multicontact/halfspace`, so both codes agree on which
/// contacts enter the sum (a contact that merely touches carries no load and deforms nothing).
pub const LOADED_FORCE_FACTOR: f64 = 1e-14;

/// Force [N] below which a contact of a particle with Young's modulus E [Pa] and radius r [m]
/// counts as unloaded: E r² · [`LOADED_FORCE_FACTOR`]. Engines also switch the contact point on it.
#[inline]
pub fn loaded_threshold(youngs_modulus: f64, radius: f64) -> f64 {
    youngs_modulus * radius * radius * LOADED_FORCE_FACTOR
}

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

    /// Force below which a contact counts as unloaded (see [`loaded_threshold`]).
    #[inline]
    pub fn loaded_threshold(&self) -> f64 {
        loaded_threshold(self.youngs_modulus, self.radius)
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
    /// An influence matrix with fewer than n² values.
    MatrixTooShort { contacts: usize, len: usize },
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
            KernelError::MatrixTooShort { contacts, len } => write!(
                f,
                "influence matrix too short: {contacts} contacts need {} values, it has {len}",
                contacts * contacts
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
    let loaded = match prologue(p, contacts, delta, hertz_fallback, true)? {
        Start::Done(summary) => return Ok(summary),
        Start::Sum { loaded } => loaded,
    };
    let n = contacts.len();
    let threshold = p.loaded_threshold();
    let nu = p.poisson_ratio;
    let pref = compliance_prefactor(p.gamma, p.youngs_modulus, nu);
    SCRATCH.with(|s| {
        let s = &mut *s.borrow_mut();
        match p.cap.map(|c| c.test) {
            None => s.run::<NO_CAP>(Pass::RadiusChanges, contacts, pref, threshold, nu),
            Some(MprTest::Abs) => s.run::<ABS_CAP>(Pass::RadiusChanges, contacts, pref, threshold, nu),
            Some(MprTest::Signed) => s.run::<SIGNED_CAP>(Pass::RadiusChanges, contacts, pref, threshold, nu),
        }
        delta[..n].copy_from_slice(&s.delta[..n]);
        let fallbacks = finish(p, &mut delta[..n], &mut hertz_fallback[..n], &s.peak[..n])?;
        Ok(KernelSummary { loaded, fallbacks })
    })
}

/// How a kernel call starts: with the answer already known, or with sums to do.
enum Start {
    Done(KernelSummary),
    Sum { loaded: usize },
}

/// What every kernel entry point does first: buffer lengths, finite inputs (points too when
/// `check_points`), the loaded count, zeroed outputs, and the early answer when no neighbour term
/// exists (no loaded contact, a single contact, or γ = 0). With exactly one loaded contact the
/// others still receive its displacement: that is how a contact created by radius growth appears,
/// as in LIGGGHTS.
fn prologue(
    p: &McParams,
    contacts: &[ContactLoad],
    delta: &mut [f64],
    hertz_fallback: &mut [bool],
    check_points: bool,
) -> Result<Start, KernelError> {
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
        if !(c.force.is_finite() && (!check_points || c.point.iter().all(|x| x.is_finite()))) {
            return Err(KernelError::NonFiniteInput { contact: i });
        }
        loaded += usize::from(c.force > threshold);
    }
    delta[..n].fill(0.0);
    hertz_fallback[..n].fill(false);
    if loaded == 0 || n < 2 || p.gamma == 0.0 {
        return Ok(Start::Done(KernelSummary { loaded, fallbacks: 0 }));
    }
    Ok(Start::Sum { loaded })
}

/// Eq. 3 on the sums: a contact whose peak term trips the cap gets Δ = 0 and the Hertz flag (the
/// peak trips exactly when one of the terms does: peaks start at 0 and δ_max ≥ 0); every other
/// Δ must be finite. Returns the number of fallbacks.
fn finish(
    p: &McParams,
    delta: &mut [f64],
    hertz_fallback: &mut [bool],
    peak: &[f64],
) -> Result<usize, KernelError> {
    if let Some(cap) = p.cap {
        let dm = cap.delta_max(p.radius);
        for (t, &pk) in hertz_fallback.iter_mut().zip(peak) {
            *t = cap.trips(pk, dm);
        }
    }
    let mut fallbacks = 0;
    for (i, (dv, tripped)) in delta.iter_mut().zip(hertz_fallback.iter()).enumerate() {
        if *tripped {
            *dv = 0.0;
            fallbacks += 1;
        } else if !dv.is_finite() {
            return Err(KernelError::NonFiniteResult { contact: i });
        }
    }
    Ok(fallbacks)
}

/// Eq. 2's geometric part for one particle's contact set, by source: `g[k·n + c]` =
/// −γ(1+ν)/(2πE) · B_{k→c} / d_kc, so that Δ_c = Σ_k g[k·n + c] F_k (zero diagonal). It depends on the contact points
/// only: an engine may keep it while the points move less than a tolerance, and then pays n²
/// multiply-adds per step ([`radius_changes_with`]) instead of n²/2 square roots and divisions.
/// Forces in `contacts` are ignored. `g` must hold n² values.
pub fn influence(p: &McParams, contacts: &[ContactLoad], g: &mut [f64]) -> Result<(), KernelError> {
    let n = contacts.len();
    if g.len() < n * n {
        return Err(KernelError::MatrixTooShort { contacts: n, len: g.len() });
    }
    if let Some(i) = contacts.iter().position(|c| !c.point.iter().all(|x| x.is_finite())) {
        return Err(KernelError::NonFiniteInput { contact: i });
    }
    let nu = p.poisson_ratio;
    let pref = compliance_prefactor(p.gamma, p.youngs_modulus, nu);
    SCRATCH.with(|s| {
        let s = &mut *s.borrow_mut();
        // Unit sources: the threshold and the cap play no part.
        s.run::<NO_CAP>(Pass::Influence, contacts, pref, 0.0, nu);
        let st = s.stride;
        for (a, row) in g[..n * n].chunks_exact_mut(n.max(1)).enumerate() {
            // The diagonal of `terms` is zero, as g's must be.
            row.copy_from_slice(&s.terms[a * st..][..n]);
        }
    });
    Ok(())
}

/// [`radius_changes`] from an [`influence`] matrix `g` of the same contacts (their points may have
/// moved since; the forces are this step's). The terms of each target are summed in increasing
/// source index, as in [`radius_changes`], so with a fresh `g` the two agree to round-off.
pub fn radius_changes_with(
    p: &McParams,
    g: &[f64],
    contacts: &[ContactLoad],
    delta: &mut [f64],
    hertz_fallback: &mut [bool],
) -> Result<KernelSummary, KernelError> {
    let n = contacts.len();
    if g.len() < n * n {
        return Err(KernelError::MatrixTooShort { contacts: n, len: g.len() });
    }
    // The points entered through `g`; only the forces are read here.
    let loaded = match prologue(p, contacts, delta, hertz_fallback, false)? {
        Start::Done(summary) => return Ok(summary),
        Start::Sum { loaded } => loaded,
    };
    let threshold = p.loaded_threshold();
    SCRATCH.with(|s| {
        let s = &mut *s.borrow_mut();
        // Unloaded contacts exert nothing: their force enters as 0.
        s.w.clear();
        s.w.extend(contacts.iter().map(|c| if c.force > threshold { c.force } else { 0.0 }));
        s.delta.resize(n + LANES, 0.0);
        s.peak.resize(n + LANES, 0.0);
        let delta = &mut delta[..n];
        match p.cap.map(|c| c.test) {
            None => s.apply::<NO_CAP>(g, delta),
            Some(MprTest::Abs) => s.apply::<ABS_CAP>(g, delta),
            Some(MprTest::Signed) => s.apply::<SIGNED_CAP>(g, delta),
        }
        let fallbacks = finish(p, delta, &mut hertz_fallback[..n], &s.peak[..n])?;
        Ok(KernelSummary { loaded, fallbacks })
    })
}

/// Radius changes under a geometry tolerance: one kept [`influence`] matrix per caller-chosen slot
/// (an engine's particle index), reused while the contact set has the same parameters, the same
/// number of contacts and every point within `tolerance` × radius of the point the matrix was
/// computed from, and recomputed otherwise. The matrix is a function of the points alone, so the
/// test needs no contact identities: any bookkeeping that lists a particle's contacts in a stable
/// order gets the reuse, and anything else only costs a recomputation. `tolerance` = 0 reuses a
/// matrix only for identical points, i.e. it is the exact kernel to round-off.
#[derive(Debug, Default)]
pub struct InfluenceCache {
    tolerance: f64,
    kept: Vec<KeptInfluence>,
    /// Calls that (re)computed a matrix.
    pub recomputed: u64,
}

/// One slot of an [`InfluenceCache`]: the matrix kept for one contact set. Slots are independent,
/// so an engine may hand disjoint runs of them to different threads ([`InfluenceCache::slots_mut`]).
#[derive(Debug, Default)]
pub struct KeptInfluence {
    params: Option<McParams>,
    points: Vec<Vec3>,
    g: Vec<f64>,
}

impl KeptInfluence {
    /// Asks the CPU to bring this slot's kept points and matrix into cache, so that a caller
    /// walking the slots in order can issue it for the next slot while it works on this one. The
    /// slots live in separate allocations and are revisited only at the next update, by which time
    /// the steps in between have evicted them: without the hint each call starts with cache misses.
    /// A hint only: no effect on any result.
    #[inline]
    pub fn prefetch(&self) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            const LINE: usize = 64;
            let bytes = |n: usize, size: usize| (0..n * size).step_by(LINE);
            for off in bytes(self.points.len(), std::mem::size_of::<Vec3>()) {
                // SAFETY: a prefetch does not access memory (no fault, no effect on results); the
                // address lies inside the allocation.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(self.points.as_ptr().cast::<i8>().add(off)) };
            }
            for off in bytes(self.g.len(), std::mem::size_of::<f64>()) {
                // SAFETY: as above.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(self.g.as_ptr().cast::<i8>().add(off)) };
            }
        }
    }

    /// [`radius_changes`] from the kept matrix, recomputed first unless it is current for
    /// `contacts` within `tolerance` × radius (see [`InfluenceCache`]). The flag says whether it
    /// was recomputed.
    pub fn radius_changes(
        &mut self,
        tolerance: f64,
        p: &McParams,
        contacts: &[ContactLoad],
        delta: &mut [f64],
        hertz_fallback: &mut [bool],
    ) -> Result<(KernelSummary, bool), KernelError> {
        let lim = (tolerance * p.radius).powi(2);
        let current = self.params.as_ref() == Some(p)
            && self.points.len() == contacts.len()
            && contacts.iter().zip(&self.points).all(|(c, q)| (c.point - q).norm_squared() <= lim);
        if !current {
            let n = contacts.len();
            // LANES values past the matrix: room for the last chunk of its last row (see
            // `Scratch::apply`).
            self.g.clear();
            self.g.resize(n * n + LANES, 0.0);
            self.params = None;
            influence(p, contacts, &mut self.g)?;
            self.points.clear();
            self.points.extend(contacts.iter().map(|c| c.point));
            self.params = Some(*p);
        }
        let summary = radius_changes_with(p, &self.g, contacts, delta, hertz_fallback)?;
        Ok((summary, !current))
    }
}

impl InfluenceCache {
    /// `tolerance` as a fraction of the particle radius: finite and ≥ 0.
    pub fn new(tolerance: f64) -> Result<Self, MaterialError> {
        check("geometry tolerance", tolerance, "finite and >= 0 (a fraction of the particle radius)", |v| {
            v >= 0.0
        })?;
        Ok(Self { tolerance, ..Default::default() })
    }

    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Follows a renumbering of the slots: the matrix kept in slot `old_of_new[k]` moves to slot k
    /// (slots beyond `old_of_new` are dropped). Validity is still checked by the points, so a
    /// slot whose contacts come in a different order afterwards is simply recomputed.
    pub fn reorder(&mut self, old_of_new: &[u32]) {
        let mut old = std::mem::take(&mut self.kept);
        self.kept = old_of_new
            .iter()
            .map(|&o| old.get_mut(o as usize).map(std::mem::take).unwrap_or_default())
            .collect();
    }

    /// The first `n` slots (grown as needed), to be used independently, with the tolerance.
    /// Add the recomputations to [`InfluenceCache::recomputed`].
    pub fn slots_mut(&mut self, n: usize) -> (f64, &mut [KeptInfluence]) {
        if self.kept.len() < n {
            self.kept.resize_with(n, Default::default);
        }
        (self.tolerance, &mut self.kept[..n])
    }

    /// [`radius_changes`] of the contact set kept in `slot`.
    pub fn radius_changes(
        &mut self,
        slot: usize,
        p: &McParams,
        contacts: &[ContactLoad],
        delta: &mut [f64],
        hertz_fallback: &mut [bool],
    ) -> Result<KernelSummary, KernelError> {
        self.slots_mut(slot + 1);
        // Callers go through the slots in order (the plugin: particle by particle).
        if let Some(next) = self.kept.get(slot + 1) {
            next.prefetch();
        }
        let (summary, recomputed) =
            self.kept[slot].radius_changes(self.tolerance, p, contacts, delta, hertz_fallback)?;
        self.recomputed += u64::from(recomputed);
        Ok(summary)
    }
}

/// Which per-term measure the peak tracks (a const parameter, so each variant compiles to its own
/// loop): none for standard MC, |δ| or δ for the two `mprTest` readings of Eq. 3.
const NO_CAP: u8 = 0;
const ABS_CAP: u8 = 1;
const SIGNED_CAP: u8 = 2;

/// What a [`Scratch::run`] computes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// Radius changes from this step's forces ([`radius_changes`]).
    RadiusChanges,
    /// The influence matrix: every contact a unit source, no sums ([`influence`]).
    Influence,
}

thread_local! {
    /// Working memory of the kernel, one per thread: grown to the largest contact set seen and
    /// reused, so a call allocates nothing once warm (the LIGGGHTS plugin calls it per particle).
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Padding of the per-contact arrays and of each term row: room for the last chunk of a row in the
/// widest lane type ([`super::lanes::F64x4`]).
pub(crate) const LANES: usize = 4;

/// The contacts of one particle by component (structure of arrays), padded with [`LANES`] zero
/// contacts, and the terms of Eq. 2 between them in one row-major matrix (source by target).
///
/// Why this shape: a particle has few contacts (4–16), so a loop over the pairs of one row is
/// short, and a compiled loop of unknown length spends more time in its remainder and alias checks
/// than in its body. Every row is therefore evaluated in whole chunks of [`LANES`] pairs of a fixed
/// length; the lanes past the last contact read the zero padding (finite, weight 0) and their
/// results land in padding that is never read. The chunk compiles to straight vector code, one
/// square root and one division per lane, with AVX2 chosen at run time (see [`super::avx2`]).
#[derive(Default)]
struct Scratch {
    px: Vec<f64>,
    py: Vec<f64>,
    pz: Vec<f64>,
    nx: Vec<f64>,
    ny: Vec<f64>,
    nz: Vec<f64>,
    /// |p_k|, the distance of the contact point from the centre.
    len: Vec<f64>,
    /// Source weight −γ(1+ν)/(2πE) · F_k; zero for an unloaded contact (it exerts nothing).
    w: Vec<f64>,
    /// Row stride of `terms`: n + [`LANES`], so that the last chunk of a row fits.
    stride: usize,
    /// `terms[k·stride + c]` = t_{k→c}: the term source k adds at target c, zero on the
    /// diagonal, n + [`LANES`] rows (the last chunk of a row writes its column into padding rows).
    /// Sources run down the rows, so [`Scratch::sums`] adds each target's terms in increasing
    /// source index with whole aligned chunks of targets.
    terms: Vec<f64>,
    /// Per contact count n, the chunks [`Scratch::rows`] evaluates, as (a, b0): source a and the
    /// first target b0 of `LANES` consecutive targets, row by row in the order of the nested loops
    /// they replace. Built once per n seen; one flat loop over them has a fixed trip count per n,
    /// where nested loops over rows of 1–4 chunks mispredict the end of nearly every row.
    chunks: Vec<Vec<[u32; 2]>>,
    /// Lanes per chunk the lists in `chunks` were built for.
    chunks_width: usize,
    /// Radius change per contact (n + [`LANES`], the padding never read).
    delta: Vec<f64>,
    /// Largest neighbour term received so far, in the cap's measure (starts at 0).
    peak: Vec<f64>,
}

impl Scratch {
    /// Points, normals and source weights pref·F_k, padded with zero contacts; `unit_sources`
    /// gives every contact the weight pref whatever its force (the influence matrix, which the
    /// forces multiply later). Sizes the term matrix (not cleared: [`Scratch::rows`] writes every
    /// entry that [`Scratch::sums`] reads for a contact). The normals n = −p/|p| and the weights
    /// are formed `L::WIDTH` contacts at a time.
    #[inline(always)]
    fn load<L: Lane>(&mut self, contacts: &[ContactLoad], pref: f64, threshold: f64, unit_sources: bool) {
        let n = contacts.len();
        let len = n + LANES;
        // Grown, never shrunk: only the padding past the contacts is zeroed here, every entry
        // before it is written below (no clearing of whole arrays per call).
        for v in [
            &mut self.px,
            &mut self.py,
            &mut self.pz,
            &mut self.len,
            &mut self.w,
            &mut self.nx,
            &mut self.ny,
            &mut self.nz,
        ] {
            if v.len() < len {
                v.resize(len, 0.0);
            }
            v[n..len].fill(0.0);
        }
        self.stride = len;
        // Length only: `rows` writes every entry of `terms` and `sums` every entry of `delta` and
        // `peak` that is read for a contact.
        if self.terms.len() < len * len {
            self.terms.resize(len * len, 0.0);
        }
        self.delta.resize(len, 0.0);
        self.peak.resize(len, 0.0);
        for (k, c) in contacts.iter().enumerate() {
            (self.px[k], self.py[k], self.pz[k]) = (c.point.x, c.point.y, c.point.z);
            // The force for now; the weight replaces it below.
            self.w[k] = c.force;
        }
        // |p| `L::WIDTH` contacts at a time, with the operations of `Vec3::norm` (x² + y² + z² in
        // that order, then the square root): the same bits.
        let mut k0 = 0;
        while k0 < n {
            let (x, y, z) = (L::load(&self.px[k0..]), L::load(&self.py[k0..]), L::load(&self.pz[k0..]));
            (x * x + y * y + z * z).sqrt().store(&mut self.len[k0..]);
            k0 += L::WIDTH;
        }
        let (zero, pref_l, threshold) = (L::splat(0.0), L::splat(pref), L::splat(threshold));
        let mut k0 = 0;
        while k0 < n {
            let l = L::load(&self.len[k0..]);
            let has_normal = l.gt(zero);
            for (p, nrm) in [(&self.px, &mut self.nx), (&self.py, &mut self.ny), (&self.pz, &mut self.nz)] {
                L::select(has_normal, L::load(&p[k0..]).neg() / l, zero).store(&mut nrm[k0..]);
            }
            // A point at the centre has no normal: zero normal and weight make the contact
            // neither exert nor receive a term (every term carries a normal or the weight). An
            // unloaded contact exerts nothing. The padding (force and length 0) gets weight 0.
            let f = L::load(&self.w[k0..]);
            let weight = if unit_sources { pref_l } else { L::select(f.gt(threshold), pref_l * f, zero) };
            L::select(has_normal, weight, zero).store(&mut self.w[k0..]);
            k0 += L::WIDTH;
        }
    }

    /// One kernel pass over a particle's contacts: [`Scratch::load`] and the terms of every pair
    /// ([`Scratch::rows`]); for [`Pass::RadiusChanges`] also their sums in `delta` and `peak`
    /// ([`Scratch::sums`]), while [`Pass::Influence`] gives every contact the unit weight pref and
    /// leaves the matrix in `up` and `back`. Four pairs per instruction when the CPU has AVX2;
    /// both paths give the same bits.
    fn run<const CAP: u8>(
        &mut self,
        pass: Pass,
        contacts: &[ContactLoad],
        pref: f64,
        threshold: f64,
        nu: f64,
    ) {
        #[cfg(target_arch = "x86_64")]
        if super::avx2() {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { self.run_avx2::<CAP>(pass, contacts, pref, threshold, nu) };
            return;
        }
        self.run_lanes::<f64, CAP>(pass, contacts, pref, threshold, nu);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn run_avx2<const CAP: u8>(
        &mut self,
        pass: Pass,
        contacts: &[ContactLoad],
        pref: f64,
        threshold: f64,
        nu: f64,
    ) {
        self.run_lanes::<F64x4, CAP>(pass, contacts, pref, threshold, nu);
    }

    #[inline(always)]
    fn run_lanes<L: Lane, const CAP: u8>(
        &mut self,
        pass: Pass,
        contacts: &[ContactLoad],
        pref: f64,
        threshold: f64,
        nu: f64,
    ) {
        self.load::<L>(contacts, pref, threshold, pass == Pass::Influence);
        self.rows::<L>(contacts.len(), nu);
        if pass == Pass::RadiusChanges {
            self.sums::<L, CAP>(contacts.len());
        }
    }

    /// Eq. 2's bracket over the chord, both ways, for every unordered pair (a, b > a) of the first
    /// `n` contacts, times the source weights: t_{a→b} along row a of `terms`, t_{b→a} down its
    /// column a (one value per lane), and zeros on the diagonal. Pairs run in whole chunks of
    /// `L::WIDTH` along row a (see [`Scratch`]).
    #[inline(always)]
    fn rows<L: Lane>(&mut self, n: usize, nu: f64) {
        let s = self.stride;
        let (px, py, pz) = (&self.px[..n + LANES], &self.py[..n + LANES], &self.pz[..n + LANES]);
        let (nx, ny, nz) = (&self.nx[..n + LANES], &self.ny[..n + LANES], &self.nz[..n + LANES]);
        let w = &self.w[..n + LANES];
        let terms = &mut self.terms[..(n + LANES) * s];
        for a in 0..n {
            terms[a * s + a] = 0.0;
        }
        if self.chunks_width != L::WIDTH {
            self.chunks.clear();
            self.chunks_width = L::WIDTH;
        }
        if self.chunks.len() <= n {
            self.chunks.resize_with(n + 1, Vec::new);
        }
        let chunks = &mut self.chunks[n];
        if chunks.is_empty() && n > 1 {
            for a in 0..n - 1 {
                chunks.extend((a + 1..n).step_by(L::WIDTH).map(|b0| [a as u32, b0 as u32]));
            }
        }
        for &[a, b0] in chunks.iter() {
            let (a, b0) = (a as usize, b0 as usize);
            let pa = [L::splat(px[a]), L::splat(py[a]), L::splat(pz[a])];
            let na = [L::splat(nx[a]), L::splat(ny[a]), L::splat(nz[a])];
            let pb = [L::load(&px[b0..]), L::load(&py[b0..]), L::load(&pz[b0..])];
            let nb = [L::load(&nx[b0..]), L::load(&ny[b0..]), L::load(&nz[b0..])];
            let (a_c, b_c, ab, d2) = chord(pa, na, pb, nb);
            let (g_ab, g_ba) = bracket_pair_over_chord(a_c, b_c, ab, d2, nu);
            (g_ab * L::splat(w[a])).store(&mut terms[a * s + b0..]);
            (g_ba * L::load(&w[b0..])).store_column(&mut terms[b0 * s + a..], s);
        }
    }

    /// Δ_c = Σ_k t_{k→c} and the cap's peaks for the first `n` contacts, every target summing its
    /// terms in increasing source index: down the columns of `terms` in aligned chunks of targets
    /// held in registers. The sum starts at +0 and so is never −0, hence adding the diagonal's +0
    /// changes no bit: each Δ_c is 0 + t_{0→c} + … in that order, skipping k = c.
    #[inline(always)]
    fn sums<L: Lane, const CAP: u8>(&mut self, n: usize) {
        let s = self.stride;
        let (delta, peak) = (&mut self.delta[..n + LANES], &mut self.peak[..n + LANES]);
        let terms = &self.terms[..n * s];
        let mut c0 = 0;
        while c0 < n {
            let (mut acc, mut pk) = (L::splat(0.0), L::splat(0.0));
            for row in terms.chunks_exact(s) {
                let t = L::load(&row[c0..]);
                acc = acc + t;
                if CAP != NO_CAP {
                    pk = peak_of::<L, CAP>(pk, t);
                }
            }
            acc.store(&mut delta[c0..]);
            pk.store(&mut peak[c0..]);
            c0 += L::WIDTH;
        }
    }

    /// Δ_c = Σ_k g[k·n + c] F_k with the forces in `w`, and the cap's peaks, into `delta` (the
    /// peaks stay in `peak`). Targets go in chunks of `L::WIDTH` held in registers while the
    /// sources run down their column in increasing index, so each target sums its terms in that
    /// order, as [`Scratch::sums`] does. A chunk reads `L::WIDTH` values of a row, past its end
    /// into the next row (lanes whose results are never read) and, on the last row, into
    /// [`LANES`] values after the matrix: four lanes at a time only when `g` has them (the kept
    /// matrices of [`KeptInfluence`] do), one otherwise; both give the same bits.
    fn apply<const CAP: u8>(&mut self, g: &[f64], delta: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if g.len() >= delta.len() * delta.len() + LANES && super::avx2() {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { self.apply_avx2::<CAP>(g, delta) };
            return;
        }
        self.apply_lanes::<f64, CAP>(g, delta);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn apply_avx2<const CAP: u8>(&mut self, g: &[f64], delta: &mut [f64]) {
        self.apply_lanes::<F64x4, CAP>(g, delta);
    }

    #[inline(always)]
    fn apply_lanes<L: Lane, const CAP: u8>(&mut self, g: &[f64], delta: &mut [f64]) {
        let n = delta.len();
        let w = &self.w[..n];
        let mut c0 = 0;
        while c0 < n {
            let (mut acc, mut pk) = (L::splat(0.0), L::splat(0.0));
            for (k, &wk) in w.iter().enumerate() {
                let t = L::load(&g[k * n + c0..]) * L::splat(wk);
                acc = acc + t;
                if CAP != NO_CAP {
                    pk = peak_of::<L, CAP>(pk, t);
                }
            }
            acc.store(&mut self.delta[c0..]);
            pk.store(&mut self.peak[c0..]);
            c0 += L::WIDTH;
        }
        delta.copy_from_slice(&self.delta[..n]);
    }
}

/// The running peak after one more term: max(peak, m) with m the term in the measure the cap
/// compares with δ_max (|t|, or t for `signed`). The peak starts at 0 and is never
/// NaN, so this is `f64::max` (a NaN term leaves the peak alone, as max does), written as a
/// comparison and a select so that it also runs on lanes.
#[inline(always)]
fn peak_of<L: Lane, const CAP: u8>(peak: L, t: L) -> L {
    let m = if CAP == SIGNED_CAP { t } else { t.abs() };
    L::select(m.gt(peak), m, peak)
}

/// The chord c = p_b − p_a of contacts a and b (points p, inward normals n) as Eq. 2's bracket
/// reads it: (n_a·c, n_b·c, n_a·n_b, c·c).
#[inline(always)]
fn chord<L: Lane>(pa: [L; 3], na: [L; 3], pb: [L; 3], nb: [L; 3]) -> (L, L, L, L) {
    let (cx, cy, cz) = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]);
    let d2 = cx * cx + cy * cy + cz * cz;
    let a_c = na[0] * cx + na[1] * cy + na[2] * cz;
    let b_c = nb[0] * cx + nb[1] * cy + nb[2] * cz;
    let ab = na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2];
    (a_c, b_c, ab, d2)
}

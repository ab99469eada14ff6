//! One run of the shear study: the material and time-step constants, the run specification and
//! protocol, the packing prepared by random sequential addition and affine compression, and the
//! sheared run with its steady-state test and averages (Ghods et al. 2022, Section 4).

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::engine::{Closure, Domain, FixedPoint, StepError, World};
use crate::physics::ghods2022::MprTest;
use crate::physics::hertz::Tangential;
use crate::physics::pair::ContactError;
use crate::physics::{Material, Vec3};

/// Particle diameter [m] (the paper's App. B hydrogel spheres). Results are dimensionless, so d
/// only sets the units.
pub const DIAMETER: f64 = 2e-3;
/// Young's modulus of the hydrogel [Pa] (paper Table 1).
pub const YOUNGS_MODULUS: f64 = 23.3e3;
/// Effective density of the hydrogel [kg/m³] (paper Table 1).
pub const DENSITY: f64 = 11.5;
/// Coefficient of restitution (Chialvo et al. 2012, whose set-up the paper follows).
pub const RESTITUTION: f64 = 0.7;
/// Overlap, as a fraction of d, at which the Hertz contact time that sets the step is evaluated.
pub const DT_OVERLAP: f64 = 0.1;
/// Steps per Hertz contact time.
pub const DT_PER_CONTACT: f64 = 50.0;
/// Volume fraction of the random sequential addition before compression.
pub const PHI_START: f64 = 0.3;
/// Neighbour skin as a fraction of d.
pub const SKIN: f64 = 0.1;
/// Most force passes per step of [`RunSpec::eq2_fixed_point`], and its tolerance (fraction of the
/// step's largest normal force). Measured on the dense reproducers: |gain| 0.5–0.8 reaches 1e-6 in
/// 11–18 passes; 100 passes converge any gain up to 0.87, and a step whose Eq. 3 decisions flip
/// between passes (no fixed point) stops there with its last iterate.
pub const FP_PASSES: u32 = 100;
pub const FP_TOLERANCE: f64 = 1e-6;

/// k_n = (4/3) E* = 2E / (3 (1 − ν²)) [Pa].
pub fn k_n(nu: f64) -> f64 {
    2.0 * YOUNGS_MODULUS / (3.0 * (1.0 - nu * nu))
}

/// Time unit of γ̂: d / √(k_n/ρ) [s].
pub fn time_unit(nu: f64) -> f64 {
    DIAMETER * (DENSITY / k_n(nu)).sqrt()
}

/// Step: the Hertz contact time π √(m_eff / k) with the tangent stiffness k = 2 E* √(R* δ) at
/// δ = DT_OVERLAP · d (R* = d/4, m_eff = m/2), divided by DT_PER_CONTACT.
pub fn time_step(nu: f64) -> f64 {
    let e_star = YOUNGS_MODULUS / (2.0 * (1.0 - nu * nu));
    let k = 2.0 * e_star * (0.25 * DIAMETER * DT_OVERLAP * DIAMETER).sqrt();
    let m = DENSITY * std::f64::consts::PI / 6.0 * DIAMETER.powi(3);
    std::f64::consts::PI * (0.5 * m / k).sqrt() / DT_PER_CONTACT
}

/// One grid point.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RunSpec {
    pub phi: f64,
    pub mu: f64,
    pub nu: f64,
    pub gamma_hat: f64,
    pub n: usize,
    /// γ of Eq. 2 and MPR of Eq. 3.
    pub gamma_mc: f64,
    pub mpr: f64,
    pub restitution: f64,
    pub seed: u64,
    /// Eq. 2 iterated to its fixed point within each step instead of lagged one step (the paper's
    /// and LIGGGHTS'): the check that a stop is the law's, not the lag's (docs/shear.md).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub eq2_fixed_point: bool,
}

impl RunSpec {
    /// File-name key: every parameter that changes the run.
    pub fn key(&self) -> String {
        format!(
            "phi{:.4}_mu{:.3}_nu{:.3}_g{:.3e}_n{}_gm{:.4}_mpr{:.4}_e{:.3}_s{}",
            self.phi,
            self.mu,
            self.nu,
            self.gamma_hat,
            self.n,
            self.gamma_mc,
            self.mpr,
            self.restitution,
            self.seed
        ) + if self.eq2_fixed_point { "_fp" } else { "" }
    }
}

/// Shear protocol: compression length, strain windows and the steady-state test.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Protocol {
    /// Steps of the affine compression from PHI_START to φ.
    pub compress_steps: u64,
    /// Strain per averaging window.
    pub window: f64,
    /// No steady state is declared before this strain.
    pub strain_min: f64,
    /// Give up the steady-state search (and average the last windows) at this strain.
    pub strain_max: f64,
    /// Windows per block of the steady-state test.
    pub block: usize,
    /// Steady when the block means p_B (last `block` windows) and p_A (the `block` before) satisfy
    /// |p_B − p_A| ≤ tol · (|p_A| + |p_B|)/2.
    pub tol: f64,
    /// Windows averaged after the steady state is found.
    pub avg_windows: usize,
    /// Stress/Z samples per window.
    pub samples_per_window: usize,
}

impl Protocol {
    pub fn quick() -> Self {
        Protocol {
            compress_steps: 2000,
            window: 0.25,
            strain_min: 1.0,
            strain_max: 3.0,
            block: 2,
            tol: 0.1,
            avg_windows: 2,
            samples_per_window: 50,
        }
    }

    pub fn full() -> Self {
        Protocol {
            compress_steps: 4000,
            window: 0.5,
            strain_min: 2.0,
            strain_max: 8.0,
            block: 2,
            tol: 0.05,
            avg_windows: 4,
            samples_per_window: 100,
        }
    }
}

/// What one run measured (averages over the steady-state windows).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunResult {
    pub spec: RunSpec,
    pub protocol: Protocol,
    /// p̂ = p / k_n: total, contact and kinetic parts.
    pub p_hat: f64,
    pub p_hat_contact: f64,
    pub p_hat_kinetic: f64,
    /// Z = 2 N_c / N.
    pub z: f64,
    /// −σ_xy / k_n (positive under positive γ̇) and the effective friction −σ_xy / p.
    pub shear_stress_hat: f64,
    #[serde(deserialize_with = "null_is_nan")]
    pub mu_eff: f64,
    /// Steady state found before strain_max?
    pub steady: bool,
    /// Strain at which the steady state was declared, and the averaged strain interval (the
    /// last block of the test and the windows after it).
    #[serde(deserialize_with = "null_is_nan")]
    pub strain_steady: f64,
    pub strain_avg_from: f64,
    pub strain_avg_to: f64,
    /// Mean p̂ of every window (the steady-state test's input).
    pub window_p_hat: Vec<f64>,
    /// Share of the contacts seen by the multi-contact kernel whose correction the Eq. 3 cap
    /// switched off (Hertz fallback), over the averaged windows (NaN in results written before it
    /// was recorded).
    #[serde(default = "nan", deserialize_with = "null_is_nan")]
    pub mc_fallback_share: f64,
    /// Relative standard error of p̂ from the averaged window means.
    #[serde(deserialize_with = "null_is_nan")]
    pub p_hat_rel_err: f64,
    pub gamma_dot: f64,
    pub dt: f64,
    pub k_n: f64,
    pub steps: u64,
    pub wall_s: f64,
    pub particle_steps_per_s: f64,
    /// Set when the run at the study's Δt stopped at the contact law's range limit and this result
    /// comes from the rerun at Δt/2 or Δt/4 that finished (see [`classify`]): the shear strain of
    /// that stop (0: in the compression). Such a stop depended on the step.
    #[serde(default)]
    pub stopped_at_full_step: Option<f64>,
}

pub(super) fn nan() -> f64 {
    f64::NAN
}

/// JSON has no NaN: serde_json writes it as null; read null back as NaN.
pub(super) fn null_is_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

use crate::rng::SplitMix64 as Rng;

/// Random sequential addition of n non-overlapping spheres of diameter d in a periodic cube of
/// side l (cell grid of side ≥ d).
pub(super) fn random_positions(n: usize, l: f64, d: f64, rng: &mut Rng) -> Result<Vec<Vec3>, String> {
    let m = ((l / d).floor() as usize).max(1);
    let cell = l / m as f64;
    let mut grid: Vec<Vec<usize>> = vec![Vec::new(); m * m * m];
    let mut out: Vec<Vec3> = Vec::with_capacity(n);
    let idx = |c: [usize; 3]| (c[2] * m + c[1]) * m + c[0];
    let mut tries = 0usize;
    while out.len() < n {
        tries += 1;
        if tries > 2000 * n + 10_000 {
            return Err(format!("random placement of {n} spheres in a box of side {l:e} m failed"));
        }
        let x = Vec3::new(rng.uniform() * l, rng.uniform() * l, rng.uniform() * l);
        let c = [0, 1, 2].map(|a| ((x[a] / cell) as usize).min(m - 1));
        let mut ok = true;
        'scan: for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let nc = [(c[0] as i64 + dx), (c[1] as i64 + dy), (c[2] as i64 + dz)]
                        .map(|v| v.rem_euclid(m as i64) as usize);
                    for &j in &grid[idx(nc)] {
                        let mut r = x - out[j];
                        for a in 0..3 {
                            r[a] -= l * (r[a] / l).round();
                        }
                        if r.norm_squared() < d * d {
                            ok = false;
                            break 'scan;
                        }
                    }
                }
            }
        }
        if ok {
            grid[idx(c)].push(out.len());
            out.push(x);
        }
    }
    Ok(out)
}

/// A World at φ (after the affine compression), not yet sheared, sorted, at the step Δt/`refine`.
fn prepare_refined(spec: &RunSpec, compress_steps: u64, refine: u32) -> Result<(World, f64), Stop> {
    prepare_with(spec, compress_steps, true, refine)
}

/// A World at φ (after the affine compression), not yet sheared, with or without spatial sorting
/// (the cost measurement times both).
pub(super) fn prepare_sorted(
    spec: &RunSpec,
    compress_steps: u64,
    sort: bool,
) -> Result<(World, f64), String> {
    prepare_with(spec, compress_steps, sort, 1).map_err(|s| s.message)
}

/// The run's packing compressed to φ (spatially sorted, as the study's runs) and set shearing at
/// γ̂ (the Lees–Edwards jump and streaming profile), not yet stepped under shear: the start of the
/// sheared scene of `mcdem bench`'s accuracy-budget front.
pub fn sheared_start(spec: &RunSpec, compress_steps: u64) -> Result<World, String> {
    let (mut w, l) = prepare_sorted(spec, compress_steps, true)?;
    start_shear(&mut w, spec.gamma_hat / time_unit(spec.nu), l);
    Ok(w)
}

/// The step is Δt/`refine` and the compression takes `refine` times `compress_steps` steps, so that
/// it runs at the same rate in time at every step size.
fn prepare_with(spec: &RunSpec, compress_steps: u64, sort: bool, refine: u32) -> Result<(World, f64), Stop> {
    let compress_steps = compress_steps * u64::from(refine);
    let d = DIAMETER;
    let vs = spec.n as f64 * std::f64::consts::PI / 6.0 * d.powi(3);
    let l = (vs / spec.phi).cbrt();
    let phi0 = spec.phi.min(PHI_START);
    let l0 = (vs / phi0).cbrt();
    let mut rng = Rng(spec.seed ^ 0x005e_ed0f_5ea4);
    let xs = random_positions(spec.n, l0, d, &mut rng)?;
    let mut w = World::new();
    w.domain = Some(Domain::new(Vec3::zeros(), Vec3::repeat(l0), [true; 3]));
    // Spatial sorting as in a deck (LAMMPS' default period): keeps the pair loop in cache at large N.
    w.sort_every = if sort { 1000 } else { 0 };
    let m = Material::new(YOUNGS_MODULUS, spec.nu, spec.gamma_mc, Some((spec.mpr, MprTest::Abs)))
        .map_err(|e| e.to_string())?;
    w.set_materials(vec![m], &[spec.restitution], &[spec.mu], Tangential::History)?;
    w.closure = Some(Closure::MultiContact);
    w.mc_range = 1.25;
    w.skin = SKIN * d;
    w.integrate = true;
    w.dt = time_step(spec.nu) / f64::from(refine);
    if spec.eq2_fixed_point {
        w.mc_fixed_point = Some(FixedPoint::new(FP_PASSES, FP_TOLERANCE, 1.0)?);
    }
    let gdot = spec.gamma_hat / time_unit(spec.nu);
    // Small zero-mean random velocities (half the shear velocity across one diameter).
    let v0 = 0.5 * gdot * d;
    let mut vs_: Vec<Vec3> = (0..spec.n)
        .map(|_| Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * (2.0 * v0))
        .collect();
    let mean = vs_.iter().sum::<Vec3>() / spec.n as f64;
    vs_.iter_mut().for_each(|v| *v -= mean);
    for (i, x) in xs.into_iter().enumerate() {
        w.p.push(i as i64 + 1, 0, x, d, DENSITY);
        w.p.v[i] = vs_[i];
    }
    w.setup()?;
    // Affine compression: positions and box scaled together, one small factor per step.
    let mut cur = l0;
    for s in 1..=compress_steps {
        let target = l0 + (l - l0) * s as f64 / compress_steps as f64;
        let f = target / cur;
        w.p.x.iter_mut().for_each(|x| *x *= f);
        if let Some(dom) = w.domain.as_mut() {
            dom.hi = Vec3::repeat(target);
        }
        cur = target;
        w.step().map_err(|e| Stop::engine(None, "compression", e))?;
    }
    if let Some(dom) = w.domain.as_mut() {
        dom.hi = Vec3::repeat(l);
    }
    Ok((w, l))
}

#[derive(Default, Clone, Copy)]
pub(super) struct Acc {
    n: f64,
    pc: f64,
    pk: f64,
    sxy: f64,
    z: f64,
    /// Multi-contact kernel counters over the window.
    mc_contacts: u64,
    mc_fallbacks: u64,
}

impl Acc {
    fn add(&mut self, o: &Acc) {
        self.n += o.n;
        self.pc += o.pc;
        self.pk += o.pk;
        self.sxy += o.sxy;
        self.z += o.z;
        self.mc_contacts += o.mc_contacts;
        self.mc_fallbacks += o.mc_fallbacks;
    }
    fn p(&self) -> f64 {
        (self.pc + self.pk) / self.n
    }
}

pub(super) fn sample(w: &World) -> Acc {
    let (sc, sk) = w.stress_parts();
    Acc {
        n: 1.0,
        pc: (sc[0][0] + sc[1][1] + sc[2][2]) / 3.0,
        pk: (sk[0][0] + sk[1][1] + sk[2][2]) / 3.0,
        sxy: 0.5 * (sc[0][1] + sc[1][0] + sk[0][1] + sk[1][0]),
        z: 2.0 * w.pair_contacts() as f64 / w.p.len() as f64,
        ..Default::default()
    }
}

/// Starts Lees–Edwards shear at rate `gdot` [1/s] in a box of height `l` [m]: velocity jump γ̇ L_y
/// across the y boundary, and the streaming profile added to every particle's velocity.
pub(super) fn start_shear(w: &mut World, gdot: f64, l: f64) {
    if let Some(dom) = w.domain.as_mut() {
        dom.le_vjump = gdot * l;
    }
    let dom = w.domain.expect("domain");
    for i in 0..w.p.len() {
        let u = dom.streaming_vx(w.p.x[i].y);
        w.p.v[i].x += u;
    }
}

/// A run that stopped: the shear strain reached (None: during the compression) and why.
#[derive(Debug, Clone)]
pub struct Stop {
    pub strain: Option<f64>,
    pub message: String,
    /// The contact law's error when a contact stopped the engine ([`StepError::contact`]);
    /// `None` for any other stop (placement, setup, a lost particle, ...).
    pub contact: Option<ContactError>,
}

impl From<String> for Stop {
    /// A stop before the run started (placement, materials, setup): no strain, no contact cause.
    fn from(message: String) -> Self {
        Stop { strain: None, message, contact: None }
    }
}

impl Stop {
    /// The engine stopped at `strain` during `stage`: its message and its typed contact cause.
    pub fn engine(strain: Option<f64>, stage: &str, e: StepError) -> Self {
        Stop { strain, message: format!("{stage}: {e}"), contact: e.contact }
    }

    /// The engine's contact-range stop (`physics::pair`): an overlap reached a particle radius.
    pub fn is_overlap_limit(&self) -> bool {
        matches!(self.contact, Some(ContactError::OverlapBeyondRadius { .. }))
    }

    fn at(&self) -> String {
        match self.strain {
            Some(g) => format!("shear strain {g:.3}"),
            None => "the compression".to_string(),
        }
    }
}

/// Leading words of a stop that is the contact law's, not the integrator's: it converges as Δt is
/// halved, or it persists down to Δt/4 (an overlap = radius met at every step size), so the state
/// is out of the model's range.
pub const OUT_OF_RANGE: &str = "out of the model's range";

/// Whether two stops at Δt and Δt/2 are the same event. A dense sheared packing is chaotic: any
/// perturbation, Δt included, moves its trajectory, and the measured place of a range stop moves by
/// a few per cent with Δt (docs/shear.md, "Runs that stop"); a stop made by the integrator (an
/// unstable step) moves by O(1) or vanishes. 10 % of the strain plus 0.02 separates the two.
fn same_stop(a: &Stop, b: &Stop) -> bool {
    match (a.strain, b.strain) {
        (None, None) => true,
        (Some(x), Some(y)) => (x - y).abs() <= 0.1 * x.max(y) + 0.02,
        _ => false,
    }
}

/// Runs one grid point single-threaded; a run that stops at the contact law's range limit is run
/// again at Δt/2 (and Δt/4 if the two stops differ) and classified by [`classify`].
pub fn run_one(spec: &RunSpec, proto: &Protocol) -> Result<RunResult, String> {
    classify(|refine| run_refined(spec, proto, refine))
}

/// [`run_one`] for a run whose stop at Δt is already on record (`recorded`, see
/// [`super::recorded_stop::recorded_stop`]): the run at Δt is deterministic, so only Δt/2 (and Δt/4)
/// are run to classify it.
pub fn run_one_from(spec: &RunSpec, proto: &Protocol, recorded: Option<Stop>) -> Result<RunResult, String> {
    classify_from(recorded, |refine| run_refined(spec, proto, refine))
}

/// Classifies a run by its stops as Δt is refined (`run(k)` runs at Δt/k):
/// - it finishes at Δt: its result;
/// - it stops for another reason than the contact range: that error, with the place;
/// - it stops at Δt but finishes at Δt/2 or Δt/4: that result, with
///   [`RunResult::stopped_at_full_step`] set (the stop depended on the step);
/// - the stop at Δt/2 is the same event as at Δt (or at Δt/4 as at Δt/2, see [`same_stop`]): an
///   error beginning with [`OUT_OF_RANGE`], since the stop converges in Δt: the contact law met its
///   limit, not the integrator;
/// - it stops at Δt, Δt/2 and Δt/4 at places that move: also [`OUT_OF_RANGE`]. A stop made by the
///   integrator (a step too large for the stiffest contact) vanishes once the step is small enough,
///   and a quarter of the step is four times inside any such limit; a stop that persists is the
///   contact law's, met at another place because any change of the step moves a sheared dense
///   packing's (chaotic) trajectory. Measured on the N = 2000 grid: φ 0.85, μ 0.5, ν 0.5,
///   γ̂ 1e-2 stops at strain 0.802, 0.434, 0.806 (docs/shear.md, "Runs that stop").
pub fn classify(run: impl FnMut(u32) -> Result<RunResult, Stop>) -> Result<RunResult, String> {
    classify_from(None, run)
}

/// [`classify`] starting from a stop at Δt already known (`recorded`): `run` is then called at Δt/2
/// and Δt/4 only.
pub fn classify_from(
    recorded: Option<Stop>,
    mut run: impl FnMut(u32) -> Result<RunResult, Stop>,
) -> Result<RunResult, String> {
    let refines: &[u32] = if recorded.is_some() { &[2, 4] } else { &[1, 2, 4] };
    let mut stops: Vec<Stop> = recorded.into_iter().collect();
    for &refine in refines {
        match run(refine) {
            Ok(mut r) => {
                r.stopped_at_full_step = stops.first().map(|s| s.strain.unwrap_or(0.0));
                return Ok(r);
            }
            Err(s) if !s.is_overlap_limit() => {
                return Err(format!("at {} (Δt/{refine}): {}", s.at(), s.message))
            }
            Err(s) => {
                let converged = stops.last().is_some_and(|p| same_stop(p, &s));
                stops.push(s);
                if converged {
                    break;
                }
            }
        }
    }
    let places: Vec<String> =
        stops.iter().zip(["Δt", "Δt/2", "Δt/4"]).map(|(s, h)| format!("{} with {h}", s.at())).collect();
    let k = stops.len();
    let why = if same_stop(&stops[k - 2], &stops[k - 1]) {
        "the stop converges in Δt: the contact law, not the integrator, met its limit"
    } else {
        "the run stops at every step down to Δt/4, at places that move with the step as a sheared dense \
         packing's trajectory does; a stop made by the integrator would vanish at a smaller step: the \
         contact law met its limit"
    };
    Err(format!("{OUT_OF_RANGE}: stopped at {} ({why}): {}", places.join(", "), stops[0].message))
}

/// Steps per averaging window of strain at shear rate `gdot` [1/s] and step `dt` [s].
pub(super) fn steps_per_window(proto: &Protocol, gdot: f64, dt: f64) -> u64 {
    (proto.window / (gdot * dt)).ceil().max(1.0) as u64
}

/// One run at the step Δt/`refine` (the study's Δt for `refine` = 1), no retry.
pub fn run_refined(spec: &RunSpec, proto: &Protocol, refine: u32) -> Result<RunResult, Stop> {
    let t0 = Instant::now();
    let (mut w, l) = prepare_refined(spec, proto.compress_steps, refine)?;
    let kn = k_n(spec.nu);
    let gdot = spec.gamma_hat / time_unit(spec.nu);
    let dt = w.dt;
    start_shear(&mut w, gdot, l);
    let steps_per_window = steps_per_window(proto, gdot, dt);
    let every = (steps_per_window / proto.samples_per_window.max(1) as u64).max(1);
    let mut windows: Vec<Acc> = Vec::new();
    let mut steady_at: Option<usize> = None;
    let mut shear_steps = 0u64;
    loop {
        let mut acc = Acc::default();
        w.mc_kernel_contacts = 0;
        w.mc_kernel_fallbacks = 0;
        for s in 1..=steps_per_window {
            if let Err(e) = w.step() {
                let strain = (windows.len() as f64 + s as f64 / steps_per_window as f64) * proto.window;
                return Err(Stop::engine(Some(strain), "shear", e));
            }
            if s % every == 0 {
                acc.add(&sample(&w));
            }
        }
        shear_steps += steps_per_window;
        acc.mc_contacts = w.mc_kernel_contacts;
        acc.mc_fallbacks = w.mc_kernel_fallbacks;
        windows.push(acc);
        let k = windows.len() - 1;
        let strain = (k + 1) as f64 * proto.window;
        match steady_at {
            None => {
                let b = proto.block.max(1);
                if k + 1 >= 2 * b && strain >= proto.strain_min - 1e-9 {
                    let mean = |ws: &[Acc]| {
                        let mut t = Acc::default();
                        ws.iter().for_each(|w| t.add(w));
                        t.p()
                    };
                    let pb = mean(&windows[k + 1 - b..=k]);
                    let pa = mean(&windows[k + 1 - 2 * b..=k - b]);
                    if (pb - pa).abs() <= proto.tol * 0.5 * (pa.abs() + pb.abs()) {
                        steady_at = Some(k);
                    }
                }
                if steady_at.is_none() && strain >= proto.strain_max - 1e-9 {
                    break;
                }
            }
            Some(s) => {
                if k - s >= proto.avg_windows {
                    break;
                }
            }
        }
    }
    let nwin = windows.len();
    let (from, to) = match steady_at {
        Some(s) => (s + 1 - proto.block.max(1), nwin),
        None => (nwin.saturating_sub(proto.avg_windows), nwin),
    };
    let mut tot = Acc::default();
    windows[from..to].iter().for_each(|a| tot.add(a));
    let means: Vec<f64> = windows[from..to].iter().map(|a| a.p() / kn).collect();
    let m = means.iter().sum::<f64>() / means.len() as f64;
    let rel_err = if means.len() > 1 {
        let var = means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (means.len() - 1) as f64;
        (var / means.len() as f64).sqrt() / m.abs()
    } else {
        f64::NAN
    };
    let p = tot.p();
    let sxy = tot.sxy / tot.n;
    let wall = t0.elapsed().as_secs_f64();
    let steps = proto.compress_steps * u64::from(refine) + shear_steps;
    Ok(RunResult {
        spec: spec.clone(),
        protocol: proto.clone(),
        p_hat: p / kn,
        p_hat_contact: tot.pc / tot.n / kn,
        p_hat_kinetic: tot.pk / tot.n / kn,
        z: tot.z / tot.n,
        mc_fallback_share: if tot.mc_contacts > 0 {
            tot.mc_fallbacks as f64 / tot.mc_contacts as f64
        } else {
            f64::NAN
        },
        shear_stress_hat: -sxy / kn,
        mu_eff: -sxy / p,
        steady: steady_at.is_some(),
        strain_steady: steady_at.map_or(f64::NAN, |s| (s + 1) as f64 * proto.window),
        strain_avg_from: from as f64 * proto.window,
        strain_avg_to: to as f64 * proto.window,
        window_p_hat: windows.iter().map(|a| a.p() / kn).collect(),
        p_hat_rel_err: rel_err,
        gamma_dot: gdot,
        dt,
        k_n: kn,
        steps,
        wall_s: wall,
        particle_steps_per_s: (spec.n as u64 * steps) as f64 / wall,
        stopped_at_full_step: None,
    })
}

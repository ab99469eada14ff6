//! `mcdem study shear`: simple shear with Lees–Edwards boundaries over a (φ, μ, ν, γ̂) grid with the
//! advanced multi-contact law (Ghods et al. 2022, Section 4 and App. D), run in-process with the
//! standalone engine, one run per thread.
//!
//! One run: N equal spheres placed by random sequential addition at φ₀ = min(φ, 0.3) in a periodic
//! cube, compressed affinely to φ (box and positions scaled together, no shear), then sheared at
//! constant volume at γ̇ = γ̂ √(k_n/ρ) / d. The shear runs in strain windows; the steady state is
//! reached when the mean pressure of the last `block` windows differs from that of the `block`
//! windows before by less than a tolerance (not before a minimum strain); the last block and
//! `avg_windows` further windows are averaged.
//!
//! Results: one JSON file per finished run in `DIR/runs/` (a restarted study skips those runs),
//! `DIR/runs.csv`, the Eq. 8 fit `DIR/response_surface.csv` next to Tables D.1/D.2, plots and
//! `DIR/report.md`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::fit;
use crate::engine::{Closure, Domain, World};
use crate::physics::ghods2022::MprTest;
use crate::physics::hertz::Tangential;
use crate::physics::{Material, Vec3};
use crate::validate::plot::{self, Chart, Series};
use crate::validate::uniaxial::calibrated;

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
        )
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
}

fn nan() -> f64 {
    f64::NAN
}

/// JSON has no NaN: serde_json writes it as null; read null back as NaN.
fn null_is_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

use crate::rng::SplitMix64 as Rng;

/// Random sequential addition of n non-overlapping spheres of diameter d in a periodic cube of
/// side l (cell grid of side ≥ d).
fn random_positions(n: usize, l: f64, d: f64, rng: &mut Rng) -> Result<Vec<Vec3>, String> {
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

/// A World at φ (after the affine compression), not yet sheared.
fn prepare(spec: &RunSpec, compress_steps: u64) -> Result<(World, f64), String> {
    prepare_sorted(spec, compress_steps, true)
}

/// [`prepare`], with or without spatial sorting (the cost measurement times both).
fn prepare_sorted(spec: &RunSpec, compress_steps: u64, sort: bool) -> Result<(World, f64), String> {
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
    w.dt = time_step(spec.nu);
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
        w.step().map_err(|e| format!("compression: {e}"))?;
    }
    if let Some(dom) = w.domain.as_mut() {
        dom.hi = Vec3::repeat(l);
    }
    Ok((w, l))
}

#[derive(Default, Clone, Copy)]
struct Acc {
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

fn sample(w: &World) -> Acc {
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
fn start_shear(w: &mut World, gdot: f64, l: f64) {
    if let Some(dom) = w.domain.as_mut() {
        dom.le_vjump = gdot * l;
    }
    let dom = w.domain.expect("domain");
    for i in 0..w.p.len() {
        let u = dom.streaming_vx(w.p.x[i].y);
        w.p.v[i].x += u;
    }
}

/// Runs one grid point single-threaded (the caller decides the thread pool).
pub fn run_one(spec: &RunSpec, proto: &Protocol) -> Result<RunResult, String> {
    let t0 = Instant::now();
    let (mut w, l) = prepare(spec, proto.compress_steps)?;
    let kn = k_n(spec.nu);
    let gdot = spec.gamma_hat / time_unit(spec.nu);
    let dt = w.dt;
    start_shear(&mut w, gdot, l);
    let steps_per_window = (proto.window / (gdot * dt)).ceil().max(1.0) as u64;
    let every = (steps_per_window / proto.samples_per_window.max(1) as u64).max(1);
    let mut windows: Vec<Acc> = Vec::new();
    let mut steady_at: Option<usize> = None;
    let mut shear_steps = 0u64;
    loop {
        let mut acc = Acc::default();
        w.mc_kernel_contacts = 0;
        w.mc_kernel_fallbacks = 0;
        for s in 1..=steps_per_window {
            w.step().map_err(|e| format!("shear: {e}"))?;
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
    let steps = proto.compress_steps + shear_steps;
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
    })
}

/// The parameter grid of a study.
#[derive(Debug, Clone)]
pub struct Grid {
    pub name: String,
    pub phis: Vec<f64>,
    pub mus: Vec<f64>,
    pub nus: Vec<f64>,
    pub gamma_hats: Vec<f64>,
    pub n: usize,
    /// γ of Eq. 2 for every ν; None (the default): each ν's value from the recorded calibration
    /// (`validation/reference/calibration_mcdem.csv`, the paper's Fig. 5 procedure).
    pub gamma_mc: Option<f64>,
    /// MPR of Eq. 3 for every ν; None: from the recorded calibration, as γ.
    pub mpr: Option<f64>,
    pub restitution: f64,
    pub protocol: Protocol,
    /// Cost-vs-N measurement: sizes and shear steps timed per size (empty: none).
    pub cost_sizes: Vec<usize>,
    pub cost_steps: u64,
}

impl Grid {
    /// A sub-grid for a few minutes on two cores.
    pub fn quick() -> Self {
        Grid {
            name: "quick".into(),
            phis: vec![0.55, 0.6, 0.65, 0.7, 0.75, 0.8],
            mus: vec![0.0, 0.5],
            nus: vec![0.25, 0.5],
            gamma_hats: vec![1e-3, 4e-3],
            n: 250,
            gamma_mc: None,
            mpr: None,
            restitution: RESTITUTION,
            protocol: Protocol::quick(),
            cost_sizes: vec![250, 500, 1000, 2000],
            cost_steps: 300,
        }
    }

    /// The paper's grid (Section 4, App. D).
    pub fn full() -> Self {
        Grid {
            name: "full".into(),
            phis: vec![0.625, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9],
            mus: vec![0.0, 0.1, 0.3, 0.5, 1.0],
            nus: vec![0.25, 0.3, 0.35, 0.4, 0.45, 0.5],
            gamma_hats: vec![1e-3, 3e-3, 1e-2],
            n: 2000,
            gamma_mc: None,
            mpr: None,
            restitution: RESTITUTION,
            protocol: Protocol::full(),
            cost_sizes: vec![500, 2000, 8000, 20000],
            cost_steps: 500,
        }
    }

    /// (γ, MPR) of the advanced MC law at ν: the explicit values, else the recorded calibration's.
    pub fn law(&self, nu: f64) -> Result<(f64, f64), String> {
        let cal = calibrated(nu);
        let pick = |given: Option<f64>, from_cal: Option<f64>, what: &str| {
            given.or(from_cal).ok_or_else(|| {
                format!("no recorded calibration for nu = {nu} to take {what} from: give it with --{what}")
            })
        };
        Ok((pick(self.gamma_mc, cal.map(|l| l.gamma), "gamma")?, pick(self.mpr, cal.map(|l| l.mpr), "mpr")?))
    }

    pub fn specs(&self) -> Result<Vec<RunSpec>, String> {
        let mut v = Vec::new();
        for &mu in &self.mus {
            for &nu in &self.nus {
                let (gamma_mc, mpr) = self.law(nu)?;
                for &phi in &self.phis {
                    for &gamma_hat in &self.gamma_hats {
                        v.push(RunSpec {
                            phi,
                            mu,
                            nu,
                            gamma_hat,
                            n: self.n,
                            gamma_mc,
                            mpr,
                            restitution: self.restitution,
                            seed: 1,
                        });
                    }
                }
            }
        }
        Ok(v)
    }
}

/// Study options.
#[derive(Debug, Clone)]
pub struct Options {
    pub grid: Grid,
    pub out: PathBuf,
    /// Runs side by side (each single-threaded).
    pub threads: usize,
    /// Measure cost vs N only: no grid run is started (finished ones are still reported).
    pub cost_only: bool,
}

/// What a study call did.
#[derive(Debug, Clone, Default)]
pub struct Summary {
    pub ran: usize,
    pub skipped: usize,
    pub failed: Vec<(String, String)>,
    pub results: Vec<RunResult>,
    pub surface: Vec<SurfaceRow>,
    /// Per μ: fitted φ_c and the lower end of its search interval.
    pub phi_c: BTreeMap<String, (f64, f64)>,
    pub cost: Vec<CostRow>,
}

/// Paper Table D.1 (α) and D.2 (β): rows μ = 0, 0.1, 0.3, 0.5, 1; columns ν = 0.25 … 0.5.
pub const PAPER_MU: [f64; 5] = [0.0, 0.1, 0.3, 0.5, 1.0];
pub const PAPER_NU: [f64; 6] = [0.25, 0.30, 0.35, 0.40, 0.45, 0.50];
pub const PAPER_ALPHA: [[f64; 6]; 5] = [
    [0.104277, 0.118771, 0.141813, 0.21954, 0.453046, 0.916128],
    [0.110574, 0.123689, 0.133818, 0.167847, 0.193596, 0.221763],
    [0.139061, 0.156818, 0.168427, 0.212168, 0.25459, 0.325325],
    [0.145432, 0.163232, 0.172328, 0.215745, 0.262769, 0.358336],
    [0.135648, 0.151223, 0.162276, 0.201806, 0.247903, 0.354467],
];
pub const PAPER_BETA: [[f64; 6]; 5] = [
    [0.451572, 0.47525, 0.509283, 0.615447, 0.7912, 0.916196],
    [0.516353, 0.543197, 0.556984, 0.594151, 0.62764, 0.649442],
    [0.666142, 0.695518, 0.708862, 0.752943, 0.806323, 0.874100],
    [0.702005, 0.730395, 0.735797, 0.779424, 0.840925, 0.939593],
    [0.650966, 0.683512, 0.701467, 0.744274, 0.810227, 0.929334],
];

/// Paper (α, β) at (μ, ν), when the tables have that point.
pub fn paper_values(mu: f64, nu: f64) -> Option<(f64, f64)> {
    let i = PAPER_MU.iter().position(|m| (m - mu).abs() < 1e-9)?;
    let j = PAPER_NU.iter().position(|n| (n - nu).abs() < 1e-9)?;
    Some((PAPER_ALPHA[i][j], PAPER_BETA[i][j]))
}

/// One row of the response surface.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceRow {
    pub mu: f64,
    pub nu: f64,
    pub phi_c: f64,
    pub alpha: f64,
    pub beta: f64,
    pub alpha_paper: f64,
    pub beta_paper: f64,
    /// Quasi-static points above jamming used in the fit.
    pub points: usize,
    /// RMS of the log residuals.
    pub rms_log: f64,
}

/// Cost-vs-N measurement.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CostRow {
    pub n: usize,
    pub steps: u64,
    pub seconds: f64,
    pub particle_steps_per_s: f64,
    pub seconds_per_step: f64,
    /// The same run with spatial sorting off (particles in creation order), timed right after:
    /// what the sorting buys at this N.
    pub unsorted_seconds_per_step: f64,
    pub phi: f64,
    pub mu: f64,
    pub nu: f64,
    pub gamma_hat: f64,
}

fn read_json<T: for<'a> Deserialize<'a>>(path: &Path) -> Option<T> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

fn write_atomic(path: &Path, text: &str) -> Result<(), String> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn single_thread<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, String> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| e.to_string())?;
    Ok(pool.install(f))
}

/// How the report states the law's (γ, MPR): given values, or the calibration's per ν.
fn law_text(g: &Grid) -> String {
    let per_nu: Vec<String> = g
        .nus
        .iter()
        .filter_map(|&nu| g.law(nu).ok().map(|(ga, m)| format!("ν = {nu}: γ = {ga}, MPR = {m}")))
        .collect();
    match (g.gamma_mc, g.mpr) {
        (Some(ga), Some(m)) => format!("γ = {ga}, MPR = {m} at every ν"),
        _ => format!(
            "γ and MPR per ν{} — {}",
            if g.gamma_mc.is_some() || g.mpr.is_some() {
                " (one of them given, the other calibrated)"
            } else {
                " from the recorded calibration (validation/reference/calibration_mcdem.csv)"
            },
            per_nu.join("; ")
        ),
    }
}

/// Runs (or resumes) the study and writes every output into `opts.out`.
pub fn run(opts: &Options, say: &(dyn Fn(&str) + Sync)) -> Result<Summary, String> {
    let runs_dir = opts.out.join("runs");
    std::fs::create_dir_all(&runs_dir).map_err(|e| format!("cannot create {}: {e}", runs_dir.display()))?;
    let specs = opts.grid.specs()?;
    let proto = &opts.grid.protocol;
    let mut done: Vec<RunResult> = Vec::new();
    let mut todo: Vec<RunSpec> = Vec::new();
    let mut failed = Vec::new();
    for s in specs {
        let key = s.key();
        if let Ok(e) = std::fs::read_to_string(runs_dir.join(format!("{key}.failed"))) {
            // A run that stopped (deterministic): not retried; delete the file to retry it.
            failed.push((key, e.trim().to_string()));
            continue;
        }
        match read_json::<RunResult>(&runs_dir.join(format!("{key}.json"))) {
            Some(r) if r.spec == s && &r.protocol == proto => done.push(r),
            _ => todo.push(s),
        }
    }
    if opts.cost_only {
        todo.clear();
    }
    let skipped = done.len() + failed.len();
    let total = todo.len();
    say(&format!(
        "shear study '{}': {} runs to do, {} already finished in {}",
        opts.grid.name,
        total,
        skipped,
        runs_dir.display()
    ));
    // Longest first (slow shear rates), so the two threads finish together.
    todo.sort_by(|a, b| a.gamma_hat.total_cmp(&b.gamma_hat).then(b.phi.total_cmp(&a.phi)));
    // Exactly `threads` runs at a time: plain worker threads take the next run from a shared
    // index, and each runs it inside its own one-thread pool (the engine's pair loop then stays
    // serial). A rayon pool of pools would let a waiting worker start further runs.
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let outcomes: Vec<Result<RunResult, (String, String)>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..opts.threads.max(1))
            .map(|_| {
                scope.spawn(|| -> Vec<Result<RunResult, (String, String)>> {
                    let mut mine = Vec::new();
                    let pool = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                        Ok(p) => p,
                        Err(e) => {
                            mine.push(Err(("thread pool".to_string(), e.to_string())));
                            return mine;
                        }
                    };
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(s) = todo.get(i) else { break };
                        let r = pool.install(|| run_one(s, proto));
                        let k = finished.fetch_add(1, Ordering::Relaxed) + 1;
                        mine.push(finish(s, r, k, total, &runs_dir, say));
                    }
                    mine
                })
            })
            .collect();
        workers.into_iter().flat_map(|w| w.join().unwrap_or_default()).collect()
    });
    let ran = outcomes.iter().filter(|o| o.is_ok()).count();
    for o in outcomes {
        match o {
            Ok(r) => done.push(r),
            Err(e) => failed.push(e),
        }
    }
    done.sort_by(|a, b| {
        (a.spec.mu, a.spec.nu, a.spec.phi, a.spec.gamma_hat)
            .partial_cmp(&(b.spec.mu, b.spec.nu, b.spec.phi, b.spec.gamma_hat))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let cost = cost_rows(opts, say)?;
    let (surface, phi_c) = response_surface(&opts.grid, &done);
    write_outputs(opts, &done, &failed, &surface, &phi_c, &cost)?;
    Ok(Summary { ran, skipped, failed, results: done, surface, phi_c, cost })
}

/// Stores a finished run (JSON) and reports it.
fn finish(
    s: &RunSpec,
    r: Result<RunResult, String>,
    k: usize,
    total: usize,
    runs_dir: &Path,
    say: &(dyn Fn(&str) + Sync),
) -> Result<RunResult, (String, String)> {
    match r {
        Ok(r) => {
            let text = serde_json::to_string_pretty(&r).map_err(|e| (s.key(), e.to_string()))?;
            write_atomic(&runs_dir.join(format!("{}.json", s.key())), &text).map_err(|e| (s.key(), e))?;
            say(&format!(
                "[{k}/{total}] φ {:.3} μ {} ν {} γ̂ {:.1e}: p̂ {:.4e} (kin {:.2e}) Z {:.2} {} strain {:.2}, {:.1} s, {:.2e} particle-steps/s",
                s.phi,
                s.mu,
                s.nu,
                s.gamma_hat,
                r.p_hat,
                r.p_hat_kinetic,
                r.z,
                if r.steady { "steady at" } else { "NOT steady by" },
                if r.steady { r.strain_steady } else { r.strain_avg_to },
                r.wall_s,
                r.particle_steps_per_s
            ));
            Ok(r)
        }
        Err(e) => {
            say(&format!("[{k}/{total}] {} failed: {e}", s.key()));
            let _ = write_atomic(&runs_dir.join(format!("{}.failed", s.key())), &format!("{e}\n"));
            Err((s.key(), e))
        }
    }
}

/// Cost per particle-step at growing N (one grid point, single thread, short shear after a short
/// compression; only the shear steps are timed). Cached in DIR/cost/.
fn cost_rows(opts: &Options, say: &(dyn Fn(&str) + Sync)) -> Result<Vec<CostRow>, String> {
    let g = &opts.grid;
    if g.cost_sizes.is_empty() {
        return Ok(Vec::new());
    }
    let dir = opts.out.join("cost");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let (phi, mu, nu, gamma_hat) = (0.7, 0.5, 0.5, 1e-3);
    let (gamma_mc, mpr) = g.law(nu)?;
    let mut rows = Vec::new();
    for &n in &g.cost_sizes {
        let path = dir.join(format!("n{n}_steps{}.json", g.cost_steps));
        if let Some(r) = read_json::<CostRow>(&path) {
            rows.push(r);
            continue;
        }
        let spec = RunSpec { phi, mu, nu, gamma_hat, n, gamma_mc, mpr, restitution: g.restitution, seed: 7 };
        let row = single_thread(|| -> Result<CostRow, String> {
            // Both worlds side by side, timed in alternating chunks so that a slow spell of a
            // shared machine hits both; at least 2e6 particle-steps each, so small N is timed
            // over more than a few milliseconds.
            let steps = g.cost_steps.max(2_000_000 / n as u64);
            let mut worlds = Vec::new();
            for sort in [true, false] {
                let (mut w, l) = prepare_sorted(&spec, 1000, sort)?;
                start_shear(&mut w, gamma_hat / time_unit(nu), l);
                for _ in 0..20 {
                    w.step().map_err(|e| e.to_string())?;
                }
                worlds.push(w);
            }
            const CHUNKS: u64 = 5;
            let mut secs_of = [0.0; 2];
            for c in 0..CHUNKS {
                let todo = steps * (c + 1) / CHUNKS - steps * c / CHUNKS;
                for (w, t) in worlds.iter_mut().zip(secs_of.iter_mut()) {
                    let t0 = Instant::now();
                    for _ in 0..todo {
                        w.step().map_err(|e| e.to_string())?;
                    }
                    *t += t0.elapsed().as_secs_f64();
                }
            }
            let [secs, unsorted] = secs_of;
            Ok(CostRow {
                unsorted_seconds_per_step: unsorted / steps as f64,
                n,
                steps,
                seconds: secs,
                particle_steps_per_s: (n as u64 * steps) as f64 / secs,
                seconds_per_step: secs / steps as f64,
                phi,
                mu,
                nu,
                gamma_hat,
            })
        })??;
        say(&format!(
            "cost N = {n}: {:.3e} particle-steps/s ({:.3e} s per step; {:.3e} without spatial sorting)",
            row.particle_steps_per_s, row.seconds_per_step, row.unsorted_seconds_per_step
        ));
        write_atomic(&path, &serde_json::to_string_pretty(&row).map_err(|e| e.to_string())?)?;
        rows.push(row);
    }
    Ok(rows)
}

/// Is a (μ, ν, φ) point quasi-static? With two or more shear rates: the pressure grows slower
/// than γ̂^0.5 between the two slowest (inertial flow gives γ̂²). With one rate: the inertial
/// number test p̂/γ̂² = p/(ρ d² γ̇²) > 10³.
fn quasi_static(runs: &[&RunResult]) -> Option<f64> {
    let mut rs: Vec<&&RunResult> = runs.iter().collect();
    rs.sort_by(|a, b| a.spec.gamma_hat.total_cmp(&b.spec.gamma_hat));
    let slow = rs.first()?;
    let qs = if let Some(s) = rate_exponent(runs) {
        s < 0.5
    } else {
        slow.p_hat / slow.spec.gamma_hat.powi(2) > 1e3
    };
    (qs && slow.p_hat > 0.0).then_some(slow.p_hat)
}

/// d ln p̂ / d ln γ̂ between the two slowest rates of one (μ, ν, φ) point (None with one rate).
fn rate_exponent(runs: &[&RunResult]) -> Option<f64> {
    let mut rs: Vec<&&RunResult> = runs.iter().collect();
    rs.sort_by(|a, b| a.spec.gamma_hat.total_cmp(&b.spec.gamma_hat));
    let (slow, fast) = (rs.first()?, rs.get(1)?);
    Some((fast.p_hat / slow.p_hat).ln() / (fast.spec.gamma_hat / slow.spec.gamma_hat).ln())
}

/// Lower end of the φ_c search for one μ: the densest φ (any ν) that is clearly inertial
/// (p̂ ∝ γ̂^s with s ≥ 1.5 between the two slowest rates); 0.5 when there is none.
pub fn phi_c_floor(results: &[RunResult], mu: f64) -> f64 {
    let mut groups: BTreeMap<(i64, i64), Vec<&RunResult>> = BTreeMap::new();
    for r in results.iter().filter(|r| key3(r.spec.mu) == key3(mu)) {
        groups.entry((key3(r.spec.nu), key3(r.spec.phi))).or_default().push(r);
    }
    groups
        .values()
        .filter(|runs| rate_exponent(runs).is_some_and(|s| s >= 1.5))
        .map(|runs| runs[0].spec.phi)
        .fold(0.5, f64::max)
}

type PointMap = BTreeMap<(i64, i64), Vec<(f64, f64)>>;

fn key3(x: f64) -> i64 {
    (x * 1000.0).round() as i64
}

/// Quasi-static points above jamming per (μ, ν): (φ, p̂ at the slowest rate).
fn qs_points(results: &[RunResult]) -> PointMap {
    let mut groups: BTreeMap<(i64, i64, i64), Vec<&RunResult>> = BTreeMap::new();
    for r in results {
        groups.entry((key3(r.spec.mu), key3(r.spec.nu), key3(r.spec.phi))).or_default().push(r);
    }
    let mut pts: PointMap = BTreeMap::new();
    for ((mu, nu, _), runs) in groups {
        if let Some(p) = quasi_static(&runs) {
            pts.entry((mu, nu)).or_default().push((runs[0].spec.phi, p));
        }
    }
    pts
}

/// Eq. 8 per (μ, ν), φ_c shared by all ν of one μ.
pub fn response_surface(
    grid: &Grid,
    results: &[RunResult],
) -> (Vec<SurfaceRow>, BTreeMap<String, (f64, f64)>) {
    let pts = qs_points(results);
    // (μ, ν) with at least one finished run: a sub-grid study leaves the others without a row
    // (their stopped runs are listed in the report; a (μ, ν) with finished runs but no
    // quasi-static point still gets its row, with 0 points).
    let ran: std::collections::BTreeSet<(i64, i64)> =
        results.iter().map(|r| (key3(r.spec.mu), key3(r.spec.nu))).collect();
    let mut rows = Vec::new();
    let mut phi_c = BTreeMap::new();
    for &mu in &grid.mus {
        let sets: Vec<(f64, Vec<(f64, f64)>)> = grid
            .nus
            .iter()
            .map(|&nu| (nu, pts.get(&(key3(mu), key3(nu))).cloned().unwrap_or_default()))
            .collect();
        let usable: Vec<&(f64, Vec<(f64, f64)>)> = sets.iter().filter(|s| s.1.len() >= 3).collect();
        let floor = phi_c_floor(results, mu);
        let fitted = fit::shared_phi_c(&usable.iter().map(|s| s.1.clone()).collect::<Vec<_>>(), floor);
        if let Some((pc, _)) = &fitted {
            phi_c.insert(format!("{mu}"), (*pc, floor));
        }
        for (nu, set) in &sets {
            if !ran.contains(&(key3(mu), key3(*nu))) {
                continue;
            }
            let (a_p, b_p) = paper_values(mu, *nu).unwrap_or((f64::NAN, f64::NAN));
            let mut row = SurfaceRow {
                mu,
                nu: *nu,
                phi_c: f64::NAN,
                alpha: f64::NAN,
                beta: f64::NAN,
                alpha_paper: a_p,
                beta_paper: b_p,
                points: set.len(),
                rms_log: f64::NAN,
            };
            if let Some((pc, fits)) = &fitted {
                if let Some(k) = usable.iter().position(|u| u.0 == *nu) {
                    row.phi_c = *pc;
                    row.alpha = fits[k].alpha;
                    row.beta = fits[k].beta;
                    row.rms_log = (fits[k].sse / set.len() as f64).sqrt();
                }
            }
            rows.push(row);
        }
    }
    (rows, phi_c)
}

fn f(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.6e}")
    } else {
        "nan".into()
    }
}

fn rel(a: f64, b: f64) -> String {
    if a.is_finite() && b.is_finite() && b != 0.0 {
        format!("{:+.0} %", 100.0 * (a - b) / b)
    } else {
        "–".into()
    }
}

fn write_outputs(
    opts: &Options,
    results: &[RunResult],
    failed: &[(String, String)],
    surface: &[SurfaceRow],
    phi_c: &BTreeMap<String, (f64, f64)>,
    cost: &[CostRow],
) -> Result<(), String> {
    let out = &opts.out;
    let w = |name: &str, text: &str| write_atomic(&out.join(name), text);
    // runs.csv
    let mut csv = String::from(
        "phi,mu,nu,gamma_hat,n,gamma_mc,mpr,restitution,p_hat,p_hat_contact,p_hat_kinetic,z,shear_stress_hat,mu_eff,steady,strain_steady,strain_avg_from,strain_avg_to,p_hat_rel_err,mc_fallback_share,gamma_dot,dt,k_n,steps,wall_s,particle_steps_per_s\n",
    );
    for r in results {
        let s = &r.spec;
        let _ = writeln!(
            csv,
            "{},{},{},{:e},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.4e}",
            s.phi,
            s.mu,
            s.nu,
            s.gamma_hat,
            s.n,
            s.gamma_mc,
            s.mpr,
            s.restitution,
            f(r.p_hat),
            f(r.p_hat_contact),
            f(r.p_hat_kinetic),
            f(r.z),
            f(r.shear_stress_hat),
            f(r.mu_eff),
            r.steady,
            f(r.strain_steady),
            r.strain_avg_from,
            r.strain_avg_to,
            f(r.p_hat_rel_err),
            f(r.mc_fallback_share),
            f(r.gamma_dot),
            f(r.dt),
            f(r.k_n),
            r.steps,
            r.wall_s,
            r.particle_steps_per_s
        );
    }
    // Run tables only once the grid has run (a cost-only call before any grid run has none); the
    // report uses the same test.
    let grid_ran = !(results.is_empty() && failed.is_empty());
    if grid_ran {
        w("runs.csv", &csv)?;
    }
    let mut rs = String::from("mu,nu,phi_c,alpha,beta,alpha_paper,beta_paper,points,rms_log\n");
    for r in surface {
        let _ = writeln!(
            rs,
            "{},{},{},{},{},{},{},{},{}",
            r.mu,
            r.nu,
            f(r.phi_c),
            f(r.alpha),
            f(r.beta),
            f(r.alpha_paper),
            f(r.beta_paper),
            r.points,
            f(r.rms_log)
        );
    }
    if grid_ran {
        w("response_surface.csv", &rs)?;
    }
    let mut cs =
        String::from("n,steps,seconds,particle_steps_per_s,seconds_per_step,unsorted_seconds_per_step\n");
    for c in cost {
        let _ = writeln!(
            cs,
            "{},{},{},{},{},{}",
            c.n, c.steps, c.seconds, c.particle_steps_per_s, c.seconds_per_step, c.unsorted_seconds_per_step
        );
    }
    if !cost.is_empty() {
        w("cost.csv", &cs)?;
    }
    let plots = plots(opts, results, surface, cost)?;
    w("report.md", &report(opts, results, failed, surface, phi_c, cost, &plots))
}

fn plots(
    opts: &Options,
    results: &[RunResult],
    surface: &[SurfaceRow],
    cost: &[CostRow],
) -> Result<Vec<String>, String> {
    let g = &opts.grid;
    let mut names = Vec::new();
    let mut draw = |name: String, chart: Chart| -> Result<(), String> {
        plot::draw(&opts.out.join(&name), &chart)?;
        names.push(name);
        Ok(())
    };
    // Figs. 8–10 style: p̂, kinetic p̂ and Z against γ̂, one curve per φ, per (μ, ν).
    for &mu in &g.mus {
        for &nu in &g.nus {
            let sel: Vec<&RunResult> = results
                .iter()
                .filter(|r| key3(r.spec.mu) == key3(mu) && key3(r.spec.nu) == key3(nu))
                .collect();
            if sel.is_empty() {
                continue;
            }
            let series = |q: &dyn Fn(&RunResult) -> f64| -> Vec<Series> {
                g.phis
                    .iter()
                    .filter_map(|&phi| {
                        let mut pts: Vec<(f64, f64)> = sel
                            .iter()
                            .filter(|r| key3(r.spec.phi) == key3(phi))
                            .map(|r| (r.spec.gamma_hat, q(r)))
                            .collect();
                        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                        (!pts.is_empty()).then(|| Series {
                            label: format!("φ = {phi}"),
                            points: pts,
                            markers: g.gamma_hats.len() < 2,
                            thin: false,
                        })
                    })
                    .collect()
            };
            for (stem, ylabel, q, logy) in [
                ("p_vs_rate", "p / k_n", (&|r: &RunResult| r.p_hat) as &dyn Fn(&RunResult) -> f64, true),
                ("pkin_vs_rate", "kinetic p / k_n", &|r: &RunResult| r.p_hat_kinetic, true),
                ("z_vs_rate", "Z", &|r: &RunResult| r.z, false),
            ] {
                let title = format!("{ylabel} vs shear rate, μ = {mu}, ν = {nu}");
                draw(
                    format!("{stem}_mu{mu}_nu{nu}.png"),
                    Chart {
                        title: &title,
                        x_label: "shear rate γ̇ d / √(k_n/ρ)",
                        y_label: ylabel,
                        log_x: true,
                        log_y: logy,
                        series: series(q),
                    },
                )?;
            }
        }
    }
    // Figs. 11–12 style: quasi-static p̂ vs φ per μ (one curve per ν, with the Eq. 8 fit).
    let pts = qs_points(results);
    for &mu in &g.mus {
        let mut series = Vec::new();
        for &nu in &g.nus {
            if let Some(p) = pts.get(&(key3(mu), key3(nu))) {
                series.push(Series {
                    label: format!("ν = {nu}"),
                    points: p.clone(),
                    markers: true,
                    thin: false,
                });
            }
            if let Some(r) = surface.iter().find(|r| r.mu == mu && r.nu == nu && r.alpha.is_finite()) {
                let hi = g.phis.iter().copied().fold(0.0, f64::max);
                // From a little below the first fitted point (not from φ_c, where the curve dives).
                let first =
                    pts.get(&(key3(mu), key3(nu))).map_or(hi, |p| p.iter().map(|q| q.0).fold(hi, f64::min));
                let lo = (first - 0.02).max(r.phi_c + 0.1 * (first - r.phi_c));
                let line: Vec<(f64, f64)> = (0..=60)
                    .map(|k| {
                        let phi = lo + (hi - lo) * k as f64 / 60.0;
                        (phi, r.alpha * (phi - r.phi_c).powf(r.beta))
                    })
                    .collect();
                series.push(Series {
                    label: format!("fit ν = {nu}: α {:.3} β {:.3}", r.alpha, r.beta),
                    points: line,
                    markers: false,
                    thin: true,
                });
            }
        }
        if series.is_empty() {
            continue;
        }
        let title = format!("quasi-static p / k_n vs φ, μ = {mu}");
        draw(
            format!("p_vs_phi_mu{mu}.png"),
            Chart { title: &title, x_label: "φ", y_label: "p / k_n", log_x: false, log_y: true, series },
        )?;
    }
    // Fig. 12 style: α and β vs ν, ours (markers) and the paper's (lines); nothing to show before
    // any grid run finished (a cost-only call).
    let fitted = !results.is_empty();
    for (name, which) in [("alpha", 0usize), ("beta", 1usize)].into_iter().filter(|_| fitted) {
        let mut series = Vec::new();
        for &mu in &g.mus {
            let ours: Vec<(f64, f64)> = surface
                .iter()
                .filter(|r| r.mu == mu)
                .map(|r| (r.nu, if which == 0 { r.alpha } else { r.beta }))
                .filter(|p| p.1.is_finite())
                .collect();
            if !ours.is_empty() {
                series.push(Series {
                    label: format!("μ = {mu} (this study)"),
                    points: ours,
                    markers: true,
                    thin: false,
                });
            }
            if let Some(i) = PAPER_MU.iter().position(|m| (m - mu).abs() < 1e-9) {
                let tab = if which == 0 { &PAPER_ALPHA } else { &PAPER_BETA };
                series.push(Series {
                    label: format!("μ = {mu} (paper)"),
                    points: PAPER_NU.iter().zip(tab[i].iter()).map(|(a, b)| (*a, *b)).collect(),
                    markers: false,
                    thin: true,
                });
            }
        }
        let title = format!("Eq. 8 {name} vs ν");
        draw(
            format!("{name}_vs_nu.png"),
            Chart { title: &title, x_label: "ν", y_label: name, log_x: false, log_y: false, series },
        )?;
    }
    if !cost.is_empty() {
        let per = cost.iter().map(|c| (c.n as f64, c.seconds_per_step)).collect::<Vec<_>>();
        let n0 = per[0];
        let linear = per.iter().map(|p| (p.0, n0.1 * p.0 / n0.0)).collect();
        draw(
            "cost_vs_n.png".into(),
            Chart {
                title: "wall time per step vs N (one thread)",
                x_label: "N",
                y_label: "s per step",
                log_x: true,
                log_y: true,
                series: vec![
                    Series {
                        label: "with spatial sorting (default)".into(),
                        points: per,
                        markers: true,
                        thin: false,
                    },
                    Series {
                        label: "without spatial sorting".into(),
                        points: cost.iter().map(|c| (c.n as f64, c.unsorted_seconds_per_step)).collect(),
                        markers: true,
                        thin: true,
                    },
                    Series {
                        label: "∝ N from the smallest N".into(),
                        points: linear,
                        markers: false,
                        thin: true,
                    },
                ],
            },
        )?;
    }
    Ok(names)
}

fn report(
    opts: &Options,
    results: &[RunResult],
    failed: &[(String, String)],
    surface: &[SurfaceRow],
    phi_c: &BTreeMap<String, (f64, f64)>,
    cost: &[CostRow],
    plots: &[String],
) -> String {
    let g = &opts.grid;
    let p = &g.protocol;
    let mut s = String::new();
    let _ = writeln!(s, "# Simple shear study ({} grid)\n", g.name);
    let list = |v: &[f64]| v.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(", ");
    let _ = writeln!(
        s,
        "Grid: φ ∈ {{{}}}, μ ∈ {{{}}}, ν ∈ {{{}}}, γ̂ ∈ {{{}}}.\n",
        list(&g.phis),
        list(&g.mus),
        list(&g.nus),
        list(&g.gamma_hats)
    );
    let _ = writeln!(
        s,
        "Advanced MC ({}, abs test), E = {} Pa, ρ = {} kg/m³, d = {} m, e = {}, N = {}. \
         k_n = 2E/(3(1−ν²)), p̂ = p/k_n, γ̂ = γ̇ d/√(k_n/ρ). Step = Hertz contact time at δ = {} d / {}. \
         MC fallback share: of the contacts the multi-contact kernel saw (particles with two or more contacts), \
         the share whose correction the Eq. 3 cap switched off. \
         Start: random sequential addition at φ = {}, affine compression to φ in {} steps, then Lees–Edwards shear. \
         Windows of strain {}; steady when the mean p of the last {} windows differs from that of the {} before by ≤ {} % \
         (not before strain {}; give up at {} and average the last windows); the last block and {} more windows are averaged.\n",
        law_text(g),
        YOUNGS_MODULUS,
        DENSITY,
        DIAMETER,
        g.restitution,
        g.n,
        DT_OVERLAP,
        DT_PER_CONTACT,
        PHI_START,
        p.compress_steps,
        p.window,
        p.block,
        p.block,
        100.0 * p.tol,
        p.strain_min,
        p.strain_max,
        p.avg_windows
    );
    let _ = writeln!(
        s,
        "No LIGGGHTS cross-check: LIGGGHTS 3.8's route to simple shear (triclinic box + `fix deform … remap v`) \
         creates no periodic ghost atoms in a triclinic box, so contacts across periodic boundaries are lost \
         without an error (`liggghts_inputs/triclinic_ghost_probe.in`, tested in tests/liggghts.rs). The shear \
         runs on the standalone engine only; its Lees–Edwards contacts are tested against plain pairs at the \
         image positions (tests/dem_shear.rs).\n"
    );
    let total_wall: f64 = results.iter().map(|r| r.wall_s).sum();
    let _ = writeln!(
        s,
        "{} runs finished, {} stopped (listed below), {} reached the steady state; summed run wall time {:.0} s.\n",
        results.len(),
        failed.len(),
        results.iter().filter(|r| r.steady).count(),
        total_wall
    );
    if results.is_empty() && failed.is_empty() {
        let _ = writeln!(s, "No grid run has finished here yet (a cost-only call): no response surface.");
    } else {
        let _ = writeln!(s, "## Response surface (Eq. 8, quasi-static points above jamming)\n");
        let _ = writeln!(
            s,
            "A (μ, ν, φ) point is quasi-static when p̂ grows slower than γ̂^0.5 between the two slowest rates \
             (one rate only: p̂/γ̂² > 10³); its slowest-rate p̂ enters the fit. φ_c is shared by all ν of one μ.\n"
        );
        let _ = writeln!(
            s,
            "φ_c is searched between the densest clearly inertial φ of that μ (p̂ ∝ γ̂^s with s ≥ 1.5; 0.5 if none) \
             and the loosest quasi-static φ.\n"
        );
        let _ = writeln!(s, "| μ | fitted φ_c | search from |\n|---|---|---|");
        for (mu, (pc, lo)) in phi_c {
            let _ = writeln!(s, "| {mu} | {pc:.4} | {lo} |");
        }
        let _ = writeln!(
            s,
            "\n| μ | ν | points | α | α paper | Δα | β | β paper | Δβ | rms log residual |\n|---|---|---|---|---|---|---|---|---|---|"
        );
        for r in surface {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.4} | {:.4} | {} | {:.4} | {:.4} | {} | {:.3} |",
                r.mu,
                r.nu,
                r.points,
                r.alpha,
                r.alpha_paper,
                rel(r.alpha, r.alpha_paper),
                r.beta,
                r.beta_paper,
                rel(r.beta, r.beta_paper),
                r.rms_log
            );
        }
        let _ = writeln!(s, "\n## Runs\n");
        let _ = writeln!(
            s,
            "| μ | ν | φ | γ̂ | p̂ | contact p̂ | kinetic p̂ | Z | −σ̂_xy | μ_eff | MC fallback share | steady at strain | averaged strain | rel. err | wall s | particle-steps/s |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
        );
        for r in results {
            let q = &r.spec;
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.1e} | {:.3e} | {:.3e} | {:.2e} | {:.2} | {:.2e} | {:.3} | {:.3} | {} | {:.2}–{:.2} | {:.2} | {:.1} | {:.2e} |",
                q.mu,
                q.nu,
                q.phi,
                q.gamma_hat,
                r.p_hat,
                r.p_hat_contact,
                r.p_hat_kinetic,
                r.z,
                r.shear_stress_hat,
                r.mu_eff,
                r.mc_fallback_share,
                if r.steady { format!("{:.2}", r.strain_steady) } else { "not steady".into() },
                r.strain_avg_from,
                r.strain_avg_to,
                r.p_hat_rel_err,
                r.wall_s,
                r.particle_steps_per_s
            );
        }
        if !failed.is_empty() {
            let _ = writeln!(s, "\n## Runs that stopped\n\n| run | cause |\n|---|---|");
            for (k, e) in failed {
                let _ = writeln!(s, "| {k} | {} |", e.replace('|', "/"));
            }
        }
    }
    if !cost.is_empty() {
        let _ = writeln!(
            s,
            "\n## Cost vs N\n\nφ = {}, μ = {}, ν = {}, γ̂ = {:e}, one thread, after a short compression. Per N, the run \
             with spatial sorting (the default) and the same run without it are timed side by side in five \
             alternating chunks, {}–{} shear steps in all (at least 2·10⁶ particle-steps).\n",
            cost[0].phi,
            cost[0].mu,
            cost[0].nu,
            cost[0].gamma_hat,
            cost.iter().map(|c| c.steps).min().unwrap_or(0),
            cost.iter().map(|c| c.steps).max().unwrap_or(0)
        );
        let _ = writeln!(
            s,
            "| N | s per step | particle-steps/s | per-particle cost / smallest N | without spatial sorting: s per step | its per-particle cost / smallest N |\n|---|---|---|---|---|---|"
        );
        let base = cost[0].seconds_per_step / cost[0].n as f64;
        let base_u = cost[0].unsorted_seconds_per_step / cost[0].n as f64;
        for c in cost {
            let _ = writeln!(
                s,
                "| {} | {:.3e} | {:.3e} | {:.2} | {:.3e} | {:.2} |",
                c.n,
                c.seconds_per_step,
                c.particle_steps_per_s,
                c.seconds_per_step / c.n as f64 / base,
                c.unsorted_seconds_per_step,
                c.unsorted_seconds_per_step / c.n as f64 / base_u
            );
        }
    }
    let _ = writeln!(s, "\n## Plots\n");
    for p in plots {
        let _ = writeln!(s, "![{p}]({p})");
    }
    s
}

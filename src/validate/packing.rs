//! The project's own 514-sphere hydrogel packing, so that the `uniaxial` case runs with nothing
//! but cargo (the Debian example's packing comes with the `liggghts-doc` package).
//!
//! How it is made (`mcdem packing hydrogel --seed S --out FILE`): 514 diameters drawn from a
//! normal distribution with the Debian packing's mean and standard deviation (21.49 mm, 1.20 mm),
//! truncated at ±2.7 SD as that packing is (18.17 … 24.56 mm), then scaled by one common factor so
//! that the solid volume equals the Debian packing's (2.695884e-3 m³): φ at a given piston height,
//! and the piston path of the case, are then the same for both packings. The spheres are placed by
//! random sequential addition in the case's box up to 0.40 m (φ ≈ 0.10), and settle under gravity
//! with Hertz (`validation/cases/uniaxial/settle.in`, restitution 0.3, no friction) for 0.8 s;
//! then the case's piston comes down to its start height (0.1676 m) and rests there 0.3 s, so that
//! no sphere stands above it (the Debian packing's top is also at the piston). The final state is
//! written as a LIGGGHTS data file. The same seed gives the same file on every machine.

use std::fmt::Write as _;
use std::path::Path;

use crate::nonlocal::uniaxial::{HYDROGEL_LX, HYDROGEL_LY, HYDROGEL_SOLID_VOLUME};
use crate::outputs::Frame;
use crate::physics::Vec3;
use crate::rng::SplitMix64;

/// Spheres in the packing.
pub const COUNT: usize = 514;
/// Diameter distribution of the Debian packing: mean, standard deviation, truncation [m].
const D_MEAN: f64 = 0.02149;
const D_SD: f64 = 0.001198;
const D_TRUNCATE_SD: f64 = 2.7;
/// Top of the loose column [m] (the data file's box reaches 0.4101 m).
const Z_TOP: f64 = 0.40;
/// Particle density of the hydrogel decks [kg/m³].
const DENSITY: f64 = 11.5;

/// The committed packing, `validation/cases/uniaxial/packing_514.data` (read where the decks of
/// `liggghts_inputs/` are read from: this tree).
pub fn shipped() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("validation/cases/uniaxial/packing_514.data")
}

/// Diameters and centres of the loose random packing for `seed`.
pub fn loose(seed: u64) -> Result<Vec<(f64, Vec3)>, String> {
    let mut rng = SplitMix64(seed ^ 0x4879_6472_6f67_656c);
    let mut d: Vec<f64> = Vec::with_capacity(COUNT);
    while d.len() < COUNT {
        let z = rng.normal();
        if z.abs() <= D_TRUNCATE_SD {
            d.push(D_MEAN + D_SD * z);
        }
    }
    let volume: f64 = d.iter().map(|x| std::f64::consts::PI / 6.0 * x.powi(3)).sum();
    let scale = (HYDROGEL_SOLID_VOLUME / volume).cbrt();
    for x in &mut d {
        *x *= scale;
    }
    // Largest first: random sequential addition places big spheres while there is room.
    d.sort_by(|a, b| b.total_cmp(a));
    let mut placed: Vec<(f64, Vec3)> = Vec::with_capacity(COUNT);
    for &di in &d {
        let r = 0.5 * di;
        let mut tries = 0;
        loop {
            tries += 1;
            if tries > 100_000 {
                return Err(format!(
                    "packing: no room for sphere {} of {COUNT} after 1e5 tries",
                    placed.len() + 1
                ));
            }
            let u = |lo: f64, hi: f64, t: f64| lo + (hi - lo) * t;
            let x = Vec3::new(
                u(r, HYDROGEL_LX - r, rng.uniform()),
                u(r, HYDROGEL_LY - r, rng.uniform()),
                u(r, Z_TOP - r, rng.uniform()),
            );
            if placed.iter().all(|(dj, xj)| (x - xj).norm() >= r + 0.5 * dj) {
                placed.push((di, x));
                break;
            }
        }
    }
    Ok(placed)
}

/// A LIGGGHTS data file of the case's box (atom type 1, the hydrogel density), with velocities
/// when given. `title` becomes its first line.
pub fn data_file(title: &str, spheres: &[Placed], velocities: Option<&[Vec3]>) -> String {
    let mut text = format!(
        "{title}\n\n{} atoms\n\n2 atom types\n\n-0.0101 0.1701 xlo xhi\n-0.0101 0.1701 ylo yhi\n-0.0101 0.4101 zlo zhi\n\nAtoms\n\n",
        spheres.len()
    );
    for (id, d, x) in spheres {
        let _ = writeln!(text, "{id} 1 {d:.12e} {DENSITY} {:.12e} {:.12e} {:.12e}", x.x, x.y, x.z);
    }
    if let Some(v) = velocities {
        text.push_str("\nVelocities\n\n");
        for ((id, _, _), v) in spheres.iter().zip(v) {
            let _ = writeln!(text, "{id} {:.12e} {:.12e} {:.12e} 0 0 0", v.x, v.y, v.z);
        }
    }
    text
}

/// A sphere of a packing: atom id, diameter [m], centre [m].
pub type Placed = (i64, f64, Vec3);

/// The spheres and velocities of the last frame of a dump with columns id radius x y z vx vy vz.
pub fn from_frame(f: &Frame, what: &Path) -> Result<(Vec<Placed>, Vec<Vec3>), String> {
    let col = |n: &str| f.column(n).ok_or_else(|| format!("{}: no column {n}", what.display()));
    let (ci, cr) = (col("id")?, col("radius")?);
    let (cx, cy, cz) = (col("x")?, col("y")?, col("z")?);
    let (cvx, cvy, cvz) = (col("vx")?, col("vy")?, col("vz")?);
    let spheres =
        f.rows.iter().map(|r| (r[ci] as i64, 2.0 * r[cr], Vec3::new(r[cx], r[cy], r[cz]))).collect();
    let v = f.rows.iter().map(|r| Vec3::new(r[cvx], r[cvy], r[cvz])).collect();
    Ok((spheres, v))
}

/// What `make` reports about the packing it wrote.
#[derive(Debug, Clone, Copy)]
pub struct Stats {
    pub diameter_mean: f64,
    pub diameter_sd: f64,
    pub diameter_min: f64,
    pub diameter_max: f64,
    /// Highest sphere top [m].
    pub top: f64,
    /// Solid fraction below the highest sphere top.
    pub phi_below_top: f64,
    /// Mean number of overlapping neighbours and walls per sphere.
    pub contacts_per_sphere: f64,
    pub kinetic_energy: f64,
}

/// Statistics of a packing (sizes, height, φ below the top, contacts with neighbours and the five
/// walls of the box).
pub fn stats(spheres: &[Placed], v: &[Vec3]) -> Stats {
    let n = spheres.len() as f64;
    let d: Vec<f64> = spheres.iter().map(|s| s.1).collect();
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    let top = spheres.iter().map(|s| s.2.z + 0.5 * s.1).fold(f64::MIN, f64::max);
    let volume: f64 = d.iter().map(|x| std::f64::consts::PI / 6.0 * x.powi(3)).sum();
    let mut contacts = 0usize;
    for (k, a) in spheres.iter().enumerate() {
        for b in &spheres[k + 1..] {
            if (a.2 - b.2).norm() < 0.5 * (a.1 + b.1) {
                contacts += 2;
            }
        }
        let r = 0.5 * a.1;
        let x = a.2;
        contacts += [x.z < r, x.x < r, HYDROGEL_LX - x.x < r, x.y < r, HYDROGEL_LY - x.y < r]
            .iter()
            .filter(|&&c| c)
            .count();
    }
    let mass = |d: f64| DENSITY * std::f64::consts::PI / 6.0 * d.powi(3);
    Stats {
        diameter_mean: mean,
        diameter_sd: sd,
        diameter_min: d.iter().copied().fold(f64::MAX, f64::min),
        diameter_max: d.iter().copied().fold(f64::MIN, f64::max),
        top,
        phi_below_top: volume / (HYDROGEL_LX * HYDROGEL_LY * top),
        contacts_per_sphere: contacts as f64 / n,
        kinetic_energy: spheres.iter().zip(v).map(|(s, v)| 0.5 * mass(s.1) * v.norm_squared()).sum(),
    }
}

/// Makes the packing for `seed` (loose placement, then the settling deck) and writes it to `out`.
pub fn make(seed: u64, out: &Path) -> Result<Stats, String> {
    let scratch = crate::harness::runner::Scratch::new()?;
    let dir = &scratch.0;
    let loose_spheres: Vec<Placed> =
        loose(seed)?.into_iter().enumerate().map(|(k, (d, x))| (k as i64 + 1, d, x)).collect();
    let loose_path = dir.join("loose.data");
    let title = format!("LIGGGHTS data file: loose random hydrogel packing, seed {seed}");
    std::fs::write(&loose_path, data_file(&title, &loose_spheres, None))
        .map_err(|e| format!("cannot write {}: {e}", loose_path.display()))?;
    let state = dir.join("settled.dump");
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("validation/cases/uniaxial/settle.in");
    let opts = crate::deck::Options {
        vars: vec![
            ("loose".into(), loose_path.display().to_string()),
            ("state".into(), state.display().to_string()),
            ("dir".into(), crate::harness::runner::decks_dir().display().to_string()),
        ],
        log: Some("none".into()),
        quiet: true,
        ..Default::default()
    };
    crate::deck::run_file_checked(&deck, &opts)
        .map_err(|e| format!("settling the packing: {}", e.message))?;
    let frames = crate::outputs::read_dump(&state)?;
    let last = frames.last().ok_or_else(|| format!("{}: no frame", state.display()))?;
    let (spheres, v) = from_frame(last, &state)?;
    let s = stats(&spheres, &v);
    let title = format!(
        "LIGGGHTS data file: mcdem's own 514-sphere hydrogel packing (mcdem packing hydrogel --seed {seed}; \
         validation/cases/uniaxial/README.md)"
    );
    std::fs::write(out, data_file(&title, &spheres, Some(&v)))
        .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    Ok(s)
}

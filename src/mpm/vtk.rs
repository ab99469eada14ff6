//! VTK snapshots of an MPM run (`mcdem mpm SCENE --vtk-every N`), for ParaView and other VTK
//! readers: legacy ASCII files (version 5.1, written with the helpers the DEM's `dump custom/vtk`
//! uses, [`crate::vtk_legacy`]) in `OUT/vtk/`:
//!
//! - `points_STEP.vtk`: `POLYDATA`, one vertex per material point (z = 0 in 2-D), bodies one after
//!   the other in the order of `points.csv`, with the `POINT_DATA` arrays `body` (int), `volume`,
//!   `J` (= V/V⁰ = det F), `gamma_eq` (Eq. 24), the Cauchy stress components `sigma_xx sigma_yy
//!   sigma_xy` (3-D: also `sigma_zz sigma_xz sigma_yz`) and the vector `velocity`;
//! - `walls_STEP.vtk` (scenes with walls): each wall at its current position as a segment (2-D) or
//!   a rectangle (3-D) spanning the points and the other walls, with the `CELL_DATA` arrays `wall`
//!   (its index in the scene), `normal`, `velocity` and `load` (the force the bodies exert on it
//!   along its axis in the step, as in history.csv; 0 at step 0);
//! - `points.vtk.series`, `walls.vtk.series`: ParaView's file-series index (JSON: each file with its
//!   time t = step·Δt), rewritten after every snapshot, so opening it gives the whole run with its
//!   real times. (ParaView's `.pvd` reader only takes XML VTK files, not legacy ones.)
//!
//! Snapshots are taken at step 0, every N steps and at the last step.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::compaction::equivalent_strain;
use super::implicit::{Body, Wall};
use crate::physics::Vec3;
use crate::vtk_legacy::{array, double, header, points_and_cells, write_file};

const TITLE: &str = "mcdem mpm";

/// The snapshot writer of one run.
#[derive(Debug)]
pub struct Snapshots {
    dir: PathBuf,
    every: usize,
    /// (file name, time) of every snapshot written.
    points: Vec<(String, f64)>,
    walls: Vec<(String, f64)>,
}

impl Snapshots {
    /// Snapshots every `every` steps into `out/vtk` (created here).
    pub fn new(out: &Path, every: usize) -> Result<Self, String> {
        if every == 0 {
            return Err("--vtk-every must be at least 1 (a snapshot every N steps), got 0".into());
        }
        let dir = out.join("vtk");
        std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        Ok(Snapshots { dir, every, points: Vec::new(), walls: Vec::new() })
    }

    /// Whether step `step` of a run of `last` steps gets a snapshot.
    pub fn due(&self, step: usize, last: usize) -> bool {
        step % self.every == 0 || step == last
    }

    /// Writes the points (and walls) at `step`, time `t`; `load[w]`: the load on wall w in the step.
    pub fn write<const D: usize>(
        &mut self,
        step: usize,
        t: f64,
        bodies: &[Body<D>],
        walls: &[Wall],
        load: &[f64],
    ) -> Result<(), String> {
        let name = format!("points_{step}.vtk");
        write_file(&self.dir.join(&name), &points_text(bodies))?;
        self.points.push((name, t));
        write_file(&self.dir.join("points.vtk.series"), &series(&self.points))?;
        if !walls.is_empty() {
            let name = format!("walls_{step}.vtk");
            write_file(&self.dir.join(&name), &walls_text(bodies, walls, load))?;
            self.walls.push((name, t));
            write_file(&self.dir.join("walls.vtk.series"), &series(&self.walls))?;
        }
        Ok(())
    }
}

/// ParaView's file-series index: `{"file-series-version": "1.0", "files": [{"name", "time"}…]}`.
fn series(files: &[(String, f64)]) -> String {
    let mut s = String::from("{\n  \"file-series-version\" : \"1.0\",\n  \"files\" : [\n");
    for (k, (name, t)) in files.iter().enumerate() {
        let sep = if k + 1 < files.len() { "," } else { "" };
        let _ = writeln!(s, "    {{ \"name\" : \"{name}\", \"time\" : {t} }}{sep}");
    }
    s.push_str("  ]\n}\n");
    s
}

fn to3<const D: usize>(x: &nalgebra::SVector<f64, D>) -> Vec3 {
    Vec3::from_fn(|a, _| if a < D { x[a] } else { 0.0 })
}

fn points_text<const D: usize>(bodies: &[Body<D>]) -> String {
    let n: usize = bodies.iter().map(|b| b.points.len()).sum();
    let mut s = String::with_capacity(300 * (n + 4));
    s.push_str(&header(TITLE));
    s.push_str("DATASET POLYDATA\n");
    let pts: Vec<Vec3> = bodies.iter().flat_map(|b| b.points.x.iter().map(to3)).collect();
    points_and_cells(&mut s, &pts, "VERTICES", 1);
    // Stress components: (name, i, j).
    let mut comps = vec![("sigma_xx", 0, 0), ("sigma_yy", 1, 1), ("sigma_xy", 0, 1)];
    if D == 3 {
        comps.extend([("sigma_zz", 2, 2), ("sigma_xz", 0, 2), ("sigma_yz", 1, 2)]);
    }
    let _ = writeln!(s, "POINT_DATA {n}\nFIELD FieldData {}", 5 + comps.len());
    let _ = writeln!(s, "body 1 {n} int");
    array(
        &mut s,
        bodies.iter().enumerate().flat_map(|(b, body)| (0..body.points.len()).map(move |_| b.to_string())),
    );
    let scalar = |s: &mut String, name: &str, f: &dyn Fn(&Body<D>, usize) -> f64| {
        let _ = writeln!(s, "{name} 1 {n} double");
        array(s, bodies.iter().flat_map(|b| (0..b.points.len()).map(move |p| double(f(b, p)))));
    };
    scalar(&mut s, "volume", &|b, p| b.points.vol[p]);
    scalar(&mut s, "J", &|b, p| b.points.vol[p] / b.points.vol0[p]);
    scalar(&mut s, "gamma_eq", &|b, p| equivalent_strain(&b.points.f[p]));
    for (name, i, j) in comps {
        scalar(&mut s, name, &|b, p| b.points.sigma[p][(i, j)]);
    }
    let _ = writeln!(s, "velocity 3 {n} double");
    array(
        &mut s,
        bodies.iter().flat_map(|b| {
            b.points.v.iter().flat_map(|v| to3(v).iter().map(|c| double(*c)).collect::<Vec<_>>())
        }),
    );
    s
}

/// The walls as segments (2-D) or rectangles (3-D) over the box of the points and the walls.
fn walls_text<const D: usize>(bodies: &[Body<D>], walls: &[Wall], load: &[f64]) -> String {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for x in bodies.iter().flat_map(|b| b.points.x.iter()) {
        for a in 0..D {
            lo[a] = lo[a].min(x[a]);
            hi[a] = hi[a].max(x[a]);
        }
    }
    let span = (0..D).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    for a in 0..D {
        // A side with a wall ends at it; a side without one a little beyond the points.
        // (side +1: the wall below the bodies; of several, the innermost).
        let at = |side: f64| walls.iter().filter(move |w| w.axis == a && w.side == side).map(|w| w.position);
        lo[a] = match at(1.0).reduce(f64::max) {
            Some(p) => p.min(lo[a]),
            None => lo[a] - 0.05 * span,
        };
        hi[a] = match at(-1.0).reduce(f64::min) {
            Some(p) => p.max(hi[a]),
            None => hi[a] + 0.05 * span,
        };
    }
    let mut pts = Vec::new();
    for w in walls {
        let others: Vec<usize> = (0..D).filter(|&a| a != w.axis).collect();
        let corner = |c: &[bool]| {
            let mut p = Vec3::zeros();
            p[w.axis] = w.position;
            for (&a, &up) in others.iter().zip(c) {
                p[a] = if up { hi[a] } else { lo[a] };
            }
            p
        };
        if D == 2 {
            pts.extend([corner(&[false]), corner(&[true])]);
        } else {
            pts.extend([
                corner(&[false, false]),
                corner(&[true, false]),
                corner(&[true, true]),
                corner(&[false, true]),
            ]);
        }
    }
    let mut s = header(TITLE);
    s.push_str("DATASET POLYDATA\n");
    let (keyword, per) = if D == 2 { ("LINES", 2) } else { ("POLYGONS", 4) };
    points_and_cells(&mut s, &pts, keyword, per);
    let n = walls.len();
    let _ = writeln!(s, "CELL_DATA {n}\nFIELD FieldData 4\nwall 1 {n} int");
    array(&mut s, (0..n).map(|w| w.to_string()));
    let along = |axis: usize, v: f64| (0..3).map(move |a| double(if a == axis { v } else { 0.0 }));
    let _ = writeln!(s, "normal 3 {n} double");
    array(&mut s, walls.iter().flat_map(|w| along(w.axis, w.side)));
    let _ = writeln!(s, "velocity 3 {n} double");
    array(&mut s, walls.iter().flat_map(|w| along(w.axis, w.velocity)));
    let _ = writeln!(s, "load 1 {n} double");
    array(&mut s, (0..n).map(|w| double(load.get(w).copied().unwrap_or(0.0))));
    s
}

//! `mcdem continuum SCENE.json [--out DIR]`: one sphere between rigid frictionless walls by the
//! finite-element reference. The scene (all fields required unless marked):
//!
//! ```json
//! {"radius": 0.001, "youngs_modulus": 23.3e3, "poisson_ratio": 0.49,
//!  "law": "neo_hookean", "locking": "mean_dilatation", "mesh_level": [1, 2, 3],
//!  "walls": "die", "delta_over_r": {"to": 0.3, "step": 0.01}}
//! ```
//!
//! `law`: `linear` | `neo_hookean`; `locking` (optional, default `mean_dilatation`): `none` |
//! `mean_dilatation`; `mesh_level`: one level or three consecutive ones (then every number gets a
//! Richardson extrapolation and error bar), or instead `mesh_intervals`: intervals per block edge,
//! one value or three with a constant refinement ratio (e.g. `[8, 12, 18]`); `walls`: `plates` | `die`; `delta_over_r`: a list of
//! increasing plate approaches Δ/r or `{"to", "step"}`. Writes `continuum.csv` and
//! `continuum.png` into DIR.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use serde::Deserialize;

use super::octant::intervals;
use super::{richardson, Law, Point, SphereRun, Volumetric, Walls};
use crate::harness::plot::{draw, Chart, Series};

#[derive(Deserialize)]
#[serde(untagged)]
enum Levels {
    One(u32),
    Many(Vec<u32>),
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Steps {
    List(Vec<f64>),
    Range { to: f64, step: f64 },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    radius: f64,
    youngs_modulus: f64,
    poisson_ratio: f64,
    law: String,
    #[serde(default)]
    locking: Option<String>,
    #[serde(default)]
    mesh_level: Option<Levels>,
    #[serde(default)]
    mesh_intervals: Option<Vec<usize>>,
    walls: String,
    delta_over_r: Steps,
}

/// A parsed scene: the run of each mesh level.
pub struct Scene {
    pub runs: Vec<SphereRun>,
}

impl Scene {
    pub fn from_json(text: &str, name: &str) -> Result<Scene, String> {
        let f: SceneFile = serde_json::from_str(text).map_err(|e| format!("{name}: {e}"))?;
        let law = match f.law.as_str() {
            "linear" => Law::Linear,
            "neo_hookean" => Law::NeoHookean,
            o => return Err(format!("{name}: law must be linear or neo_hookean, got '{o}'")),
        };
        let vol = match f.locking.as_deref().unwrap_or("mean_dilatation") {
            "none" => Volumetric::Full,
            "mean_dilatation" => Volumetric::MeanDilatation,
            o => return Err(format!("{name}: locking must be none or mean_dilatation, got '{o}'")),
        };
        let walls = match f.walls.as_str() {
            "plates" => Walls::Plates,
            "die" => Walls::Die,
            o => return Err(format!("{name}: walls must be plates or die, got '{o}'")),
        };
        let meshes: Vec<usize> = match (f.mesh_level, f.mesh_intervals) {
            (Some(lv), None) => {
                let levels = match lv {
                    Levels::One(l) => vec![l],
                    Levels::Many(v) => v,
                };
                if !(levels.len() == 1
                    || (levels.len() == 3 && levels[1] == levels[0] + 1 && levels[2] == levels[1] + 1))
                {
                    return Err(format!(
                        "{name}: mesh_level must be one level or three consecutive levels, got {levels:?}"
                    ));
                }
                if let Some(l) = levels.iter().find(|&&l| l == 0 || l > 6) {
                    return Err(format!("{name}: mesh_level must be 1 to 6, got {l}"));
                }
                levels.iter().map(|&l| intervals(l)).collect()
            }
            (None, Some(n)) => {
                // Richardson needs one refinement ratio: n₂ n₂ = n₁ n₃ exactly, in integers.
                if !(n.len() == 1 || (n.len() == 3 && n[0] < n[1] && n[1] * n[1] == n[0] * n[2])) {
                    return Err(format!(
                        "{name}: mesh_intervals must be one value or three increasing values with a constant ratio (n2*n2 = n1*n3), got {n:?}"
                    ));
                }
                n
            }
            _ => return Err(format!("{name}: give exactly one of mesh_level and mesh_intervals")),
        };
        let delta_over_r = match f.delta_over_r {
            Steps::List(v) => v,
            Steps::Range { to, step } => {
                if !(step > 0.0 && to >= step) {
                    return Err(format!(
                        "{name}: delta_over_r needs 0 < step <= to, got step {step}, to {to}"
                    ));
                }
                let n = (to / step - 1e-9).ceil() as usize;
                (1..=n).map(|i| (i as f64 * step).min(to)).collect()
            }
        };
        let runs = meshes
            .iter()
            .map(|&intervals| SphereRun {
                radius: f.radius,
                youngs_modulus: f.youngs_modulus,
                poisson_ratio: f.poisson_ratio,
                law,
                vol,
                intervals,
                walls,
                delta_over_r: delta_over_r.clone(),
            })
            .collect::<Vec<_>>();
        for r in &runs {
            r.check().map_err(|e| format!("{name}: {e}"))?;
        }
        Ok(Scene { runs })
    }
}

/// Runs the scene at `path`, writing `continuum.csv` and `continuum.png` into `out`.
pub fn run(path: &Path, out: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let scene = Scene::from_json(&text, &path.display().to_string())?;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut curves: Vec<Vec<Point>> = Vec::new();
    for r in &scene.runs {
        let t = Instant::now();
        let pts = r.run(|p| {
            eprintln!(
                "{} intervals delta/r {:.3}: plate {:.5e} Pa, side {:.5e} Pa ({} + {} contact nodes, {:.0} s)",
                r.intervals,
                p.delta_over_r,
                p.plate_stress,
                p.side_stress,
                p.plate_nodes,
                p.side_nodes,
                t.elapsed().as_secs_f64()
            )
        })?;
        curves.push(pts);
    }
    let csv = table(&scene, &curves);
    let file = out.join("continuum.csv");
    std::fs::write(&file, csv).map_err(|e| format!("cannot write {}: {e}", file.display()))?;
    plot(&scene, &curves, &out.join("continuum.png"))?;
    eprintln!("wrote {} and continuum.png", file.display());
    Ok(())
}

/// The CSV: per Δ/r the finest level's stresses, with three levels also the Richardson value,
/// error bar and observed order, then every level's raw stresses.
fn table(scene: &Scene, curves: &[Vec<Point>]) -> String {
    let r0 = &scene.runs[0];
    let mut s = format!(
        "# mcdem continuum: {:?} sphere r = {} m, E = {} Pa, nu = {}, {:?}, walls {:?}, intervals per block edge {:?}\n\
         # stresses = wall force / (2r)^2 [Pa]; side = one side wall; *_err = Richardson error bar (|extrapolated - finest|)\n",
        r0.law,
        r0.radius,
        r0.youngs_modulus,
        r0.poisson_ratio,
        r0.vol,
        r0.walls,
        scene.runs.iter().map(|r| r.intervals).collect::<Vec<_>>()
    );
    s.push_str("delta_over_r,plate_stress_pa,plate_stress_err_pa,side_stress_pa,side_stress_err_pa,plate_order,side_order");
    for r in &scene.runs {
        let _ = write!(s, ",plate_n{0},side_n{0}", r.intervals);
    }
    s.push('\n');
    for (i, p) in curves[0].iter().enumerate() {
        let v: Vec<&Point> = curves.iter().map(|c| &c[i]).collect();
        let (pl, sd) = if v.len() == 3 {
            let q = scene.runs[1].intervals as f64 / scene.runs[0].intervals as f64;
            (
                richardson(v[0].plate_stress, v[1].plate_stress, v[2].plate_stress, q),
                richardson(v[0].side_stress, v[1].side_stress, v[2].side_stress, q),
            )
        } else {
            let one = |x: f64| super::Richardson { value: x, error: f64::NAN, order: f64::NAN };
            (one(v[0].plate_stress), one(v[0].side_stress))
        };
        let _ = write!(
            s,
            "{},{:.6e},{:.3e},{:.6e},{:.3e},{:.2},{:.2}",
            p.delta_over_r, pl.value, pl.error, sd.value, sd.error, pl.order, sd.order
        );
        for q in &v {
            let _ = write!(s, ",{:.6e},{:.6e}", q.plate_stress, q.side_stress);
        }
        s.push('\n');
    }
    s
}

fn plot(scene: &Scene, curves: &[Vec<Point>], path: &Path) -> Result<(), String> {
    let mut series = Vec::new();
    for (r, c) in scene.runs.iter().zip(curves) {
        series.push(Series {
            label: format!("plate, {} intervals", r.intervals),
            points: c.iter().map(|p| (p.delta_over_r, p.plate_stress)).collect(),
            markers: false,
            thin: false,
        });
        if r.walls == Walls::Die {
            series.push(Series {
                label: format!("side, {} intervals", r.intervals),
                points: c.iter().map(|p| (p.delta_over_r, p.side_stress)).collect(),
                markers: false,
                thin: true,
            });
        }
    }
    let title = format!("continuum sphere ({:?}, nu = {})", scene.runs[0].law, scene.runs[0].poisson_ratio);
    draw(
        path,
        &Chart {
            title: &title,
            x_label: "plate approach / r",
            y_label: "wall force / (2r)^2 [Pa]",
            log_x: false,
            log_y: false,
            series,
        },
    )
}

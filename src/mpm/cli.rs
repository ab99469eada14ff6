//! `mcdem mpm SCENE [--out DIR] [--vtk-every N]`: runs a scene and writes `history.csv`,
//! `bodies.csv` (centre and velocity of every body), `points.csv` (final material points), PNG
//! charts and, with `--vtk-every`, VTK snapshots (`vtk/`, see [`super::vtk`]) into DIR.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use super::compaction::{box_walls, domains_past_walls, solid_volume, wall_pair, CompactionLog};
use super::constitutive::{inverse, Constitutive, Law, Mat};
use super::contact::{step_bodies_cut, ContactWorkspace};
use super::grid::Vector;
use super::implicit::WallsOn;
use super::points::Points;
use super::scene::Scene;
use super::vtk::Snapshots;
use crate::harness::plot::{draw, Chart, Series};

/// Plane-strain effective modulus E* = E/(1 − ν²) = 4μ(λ + μ)/(λ + 2μ) of Eq. 19.
pub fn plane_strain_modulus(lambda: f64, mu: f64) -> f64 {
    4.0 * mu * (lambda + mu) / (lambda + 2.0 * mu)
}

/// Hertz line contact of a cylinder between plates, Nezamabadi et al. 2019, Eq. 19:
/// F = (π/4) E* d, d the displacement of the centre (force per unit length).
pub fn eq19_force(lambda: f64, mu: f64, d: f64) -> f64 {
    std::f64::consts::FRAC_PI_4 * plane_strain_modulus(lambda, mu) * d
}

/// Volume averages (weights V⁰) over the points of the Green–Lagrange strain γ = (FᵀF − I)/2 and of
/// the second Piola–Kirchhoff stress S = F⁻¹P, component (a, a) with a the last axis.
pub fn mean_strain_stress<const D: usize>(points: &Points<D>, law: &Law) -> (f64, f64) {
    let a = D - 1;
    let (mut g, mut s, mut v) = (0.0, 0.0, 0.0);
    for (f, v0) in points.f.iter().zip(&points.vol0) {
        let gamma: Mat<D> = (f.transpose() * f - Mat::<D>::identity()) * 0.5;
        let pk1 = <Law as Constitutive<D>>::pk1(law, f).unwrap_or_else(|_| Mat::<D>::zeros());
        let pk2 = inverse(f) * pk1;
        g += v0 * gamma[(a, a)];
        s += v0 * pk2[(a, a)];
        v += v0;
    }
    (g / v, s / v)
}

/// `mcdem mpm-fit`: the compaction laws fitted to the runs in `dirs`, report printed and written
/// with the charts into `out`.
pub fn fit(dirs: &[std::path::PathBuf], out: &Path, phi0: Option<f64>) -> Result<(), String> {
    if let Some(p) = phi0 {
        if !(p > 0.0 && p < 1.0) {
            return Err(format!("--phi0 must lie in (0, 1), got {p}"));
        }
    }
    let runs = dirs.iter().map(|d| super::compaction_fit::read_run(d)).collect::<Result<Vec<_>, _>>()?;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let md = super::compaction_fit::report(&runs, phi0, out)?;
    println!("{md}");
    Ok(())
}

/// Runs the scene at `path`, writing into `out`; `vtk_every`: VTK snapshots every this many steps.
pub fn run(path: &Path, out: &Path, vtk_every: Option<usize>) -> Result<(), String> {
    if vtk_every == Some(0) {
        return Err("--vtk-every must be at least 1 (a snapshot every N steps), got 0".into());
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let scene = Scene::from_json(&text)?;
    // The scene beside its outputs: what was run, and the material `mpm-fit` reads.
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    std::fs::write(out.join("scene.json"), &text).map_err(|e| format!("cannot write scene.json: {e}"))?;
    match scene.dimension {
        2 => run_d::<2>(&scene, out, vtk_every),
        3 => run_d::<3>(&scene, out, vtk_every),
        d => Err(format!("scene: dimension must be 2 or 3, got {d}")),
    }
}

fn run_d<const D: usize>(scene: &Scene, out: &Path, vtk_every: Option<usize>) -> Result<(), String> {
    let mut setup = scene.setup::<D>()?;
    if let Some(c) = &setup.prepared {
        eprintln!(
            "mpm: packing compressed to jamming by DEM in {} steps: top wall at {:.6e} m, largest overlap of the padded discs {:.3e} m (below the gap)",
            c.steps, c.top, c.max_overlap
        );
    }
    let mut vtk = vtk_every.map(|n| Snapshots::new(out, n)).transpose()?;
    if let Some(v) = vtk.as_mut() {
        v.write(0, 0.0, &setup.bodies, &setup.walls, &[])?;
    }
    let (lambda, mu) = setup.bodies[0].law.lame();
    let a = D - 1;
    // Plate pair along the last axis (bottom side +1, top side −1), if the scene has one.
    let plates = wall_pair(&setup.walls, a);
    let gap0 = plates.map(|(b, t)| setup.walls[t].position - setup.walls[b].position);
    let mut csv = String::from(
        "step,time,d,F_top,F_bottom,F_mean,F_eq19,gamma_plates,gamma_mean,S_mean,newton_iterations,contact_iterations,contact_nodes,active_contacts,contact_normal_force,momentum_x,momentum_y,kinetic_energy\n",
    );
    let mut bcsv = String::from("step,time,body,x,y,vx,vy\n");
    let (mut fd, mut f19, mut sg) = (Vec::new(), Vec::new(), Vec::new());
    let mut ws = ContactWorkspace::default();
    // A packing in a box also reports the compaction measures (packing.csv).
    let mut compaction = match box_walls::<D>(&setup.walls) {
        Some(w) if setup.bodies.len() > 1 => Some(CompactionLog::new(w, &setup.walls, &setup.bodies)),
        _ => None,
    };
    // packing.csv is written as it grows (header now, each row as it is recorded).
    if let Some(c) = &compaction {
        std::fs::write(out.join("packing.csv"), &c.csv)
            .map_err(|e| format!("cannot write packing.csv: {e}"))?;
    }
    let started = Instant::now();
    // Steps done and the time left, on a terminal as a bar, elsewhere a line every 10 s.
    let progress = crate::harness::progress::Progress::new("mpm", 1);
    progress.start("steps");
    let mut total_iters = 0;
    let mut cut_steps = 0usize;
    let mut failure = None;
    // Walls on the points: the largest reach of a point's domain past a wall over the run.
    let mut past_walls = f64::NEG_INFINITY;
    // The step at which a packing reached the scene's `until_phi`, if it did.
    let mut reached = None;
    for k in 0..scene.steps {
        let (rep, substeps) = match step_bodies_cut(
            &mut setup.bodies,
            &mut setup.walls,
            &setup.options,
            &setup.contact,
            k,
            &mut ws,
            setup.step_cuts,
        ) {
            Ok(r) => r,
            Err(e) => {
                // Keep what was computed: the history up to the failed step is written first.
                failure = Some(e);
                break;
            }
        };
        progress.fraction("steps", (k + 1) as f64 / scene.steps as f64);
        // Solid filling more than the box is impossible: past Φ = 1 material lies beyond the walls
        // or bodies overlap, a limit of contacts and walls acting on grid nodes (up to half a
        // cell of a body's material can lie past them), so the run stops there.
        if let Some(c) = compaction.as_ref() {
            let phi = c.phi(&setup.bodies, &setup.walls);
            if phi > 1.0 {
                // What is past the walls, against the excess of solid over the box (the rest of
                // the excess, and the voids, must be bodies overlapping).
                let (_, past) = domains_past_walls(&setup.bodies, &setup.walls);
                let vs = solid_volume(&setup.bodies);
                let on = match setup.options.walls_on {
                    WallsOn::Nodes => "contacts and walls act on grid nodes",
                    WallsOn::Points => "walls act on the points' domains, body contacts on grid nodes",
                };
                failure = Some(format!(
                    "step {}: the solid fraction Φ = {phi:.4} exceeds 1: material lies past the walls or bodies overlap ({:.2} % of the solid volume lies past the wall planes, against an excess of {:.2} % over the box); {on}, so this is the resolution's limit (h = {:.3e} m), not the material's; results up to the previous step are kept",
                    k + 1,
                    100.0 * past / vs,
                    100.0 * (1.0 - 1.0 / phi),
                    setup.bodies[0].grid.h
                ));
                break;
            }
            if scene.until_phi.is_some_and(|u| phi >= u) {
                reached = Some((k + 1, phi));
            }
        }
        if substeps > 1 {
            cut_steps += 1;
            eprintln!("mpm: step {k} did not converge with Δt; taken as {substeps} sub-steps");
        }
        total_iters += rep.newton_iterations;
        if setup.options.walls_on == WallsOn::Points {
            past_walls = past_walls.max(domains_past_walls(&setup.bodies, &setup.walls).0);
        }
        if let Some(v) = vtk.as_mut().filter(|v| v.due(k + 1, scene.steps)) {
            let t = (k + 1) as f64 * setup.options.dt;
            v.write(k + 1, t, &setup.bodies, &setup.walls, &rep.wall_load)?;
        }
        if (k + 1) % scene.output_every != 0 && k + 1 != scene.steps && reached.is_none() {
            continue;
        }
        progress.detail("steps", "step", format!("step {} of {}", k + 1, scene.steps));
        if let Some(c) = compaction.as_mut() {
            c.record(k + 1, (k + 1) as f64 * setup.options.dt, &setup.bodies, &setup.walls, &rep);
            // Written as it grows: a long compaction can be followed, and what it reached kept.
            std::fs::write(out.join("packing.csv"), &c.csv)
                .map_err(|e| format!("cannot write packing.csv: {e}"))?;
        }
        let (gm, sm) = mean_strain_stress(&setup.bodies[0].points, &setup.bodies[0].law);
        let (mut d, mut ft, mut fb, mut gp) = (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
        if let (Some((b, t)), Some(g0)) = (plates, gap0) {
            let gap = setup.walls[t].position - setup.walls[b].position;
            // Centre displacement: half the approach of the plates (Fig. 6, symmetric contacts).
            d = 0.5 * (g0 - gap);
            ft = rep.wall_load[t];
            fb = rep.wall_load[b];
            gp = 0.5 * ((gap / g0).powi(2) - 1.0);
        }
        let f19_k = if D == 2 { eq19_force(lambda, mu, d) } else { f64::NAN };
        let t = (k + 1) as f64 * setup.options.dt;
        let mut mom = [0.0; 3];
        let mut kin = 0.0;
        for (b, body) in setup.bodies.iter().enumerate() {
            let p = body.points.momentum();
            let m: f64 = body.points.mass.iter().sum();
            let c = body
                .points
                .mass
                .iter()
                .zip(&body.points.x)
                .fold(Vector::<D>::zeros(), |acc, (m, x)| acc + x * *m)
                / m;
            mom[..D].iter_mut().zip(p.iter()).for_each(|(a, b)| *a += b);
            kin += body.points.kinetic_energy();
            let _ = writeln!(
                bcsv,
                "{},{t:.9e},{b},{:.9e},{:.9e},{:.9e},{:.9e}",
                k + 1,
                c[0],
                c[1],
                p[0] / m,
                p[1] / m
            );
        }
        let _ = writeln!(
            csv,
            "{},{t:.9e},{d:.9e},{ft:.9e},{fb:.9e},{:.9e},{f19_k:.9e},{gp:.9e},{gm:.9e},{sm:.9e},{},{},{},{},{:.9e},{:.9e},{:.9e},{kin:.9e}",
            k + 1,
            0.5 * (ft + fb),
            rep.newton_iterations,
            rep.iterations,
            rep.contact_nodes,
            rep.active_contacts,
            rep.contact_normal_force,
            mom[0],
            mom[1]
        );
        if d.is_finite() {
            fd.push((d, 0.5 * (ft + fb)));
            f19.push((d, f19_k));
            sg.push((-gp, -sm));
        }
        if let Some((step, phi)) = reached {
            eprintln!("mpm: step {step}: the packing reached Φ = {phi:.4} ≥ until_phi; the run ends here");
            break;
        }
    }
    progress.finish("steps");
    drop(progress);
    let wall = started.elapsed().as_secs_f64();
    std::fs::write(out.join("history.csv"), csv).map_err(|e| format!("cannot write history.csv: {e}"))?;
    std::fs::write(out.join("bodies.csv"), bcsv).map_err(|e| format!("cannot write bodies.csv: {e}"))?;
    let mut pts = String::from("body,x,y,z,J,sigma_xx,sigma_yy,sigma_xy,volume\n");
    let mut snap = Vec::new();
    let mut n_points = 0;
    for (body_idx, body) in setup.bodies.iter().enumerate() {
        let b = &body.points;
        n_points += b.len();
        for x in &b.x {
            snap.push((x[0], x[a]));
        }
        for p in 0..b.len() {
            let x = b.x[p];
            let z = if D == 3 { x[2] } else { 0.0 };
            let s = b.sigma[p];
            let _ = writeln!(
                pts,
                "{body_idx},{:.9e},{:.9e},{z:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e}",
                x[0],
                x[1],
                b.vol[p] / b.vol0[p],
                s[(0, 0)],
                s[(1, 1)],
                s[(0, 1)],
                b.vol[p]
            );
        }
    }
    std::fs::write(out.join("points.csv"), pts).map_err(|e| format!("cannot write points.csv: {e}"))?;
    if !fd.is_empty() {
        draw(
            &out.join("force_displacement.png"),
            &Chart {
                title: "Plate force against centre displacement",
                x_label: "d [m]",
                y_label: "F [N/m]",
                log_x: false,
                log_y: false,
                series: vec![
                    Series {
                        label: "MPM (mean of the plates)".into(),
                        points: fd,
                        markers: true,
                        thin: false,
                    },
                    Series { label: "Eq. 19".into(), points: f19, markers: false, thin: false },
                ],
            },
        )?;
        draw(
            &out.join("stress_strain.png"),
            &Chart {
                title: "Mean −S_yy against plate −γ_yy",
                x_label: "−γ_yy",
                y_label: "−S_yy [Pa]",
                log_x: false,
                log_y: false,
                series: vec![Series { label: "MPM".into(), points: sg, markers: true, thin: false }],
            },
        )?;
    }
    draw(
        &out.join("points_final.png"),
        &Chart {
            title: "Material points at the end",
            x_label: "x [m]",
            y_label: "y [m]",
            log_x: false,
            log_y: false,
            series: vec![Series { label: "points".into(), points: snap, markers: true, thin: false }],
        },
    )?;
    if setup.options.walls_on == WallsOn::Points {
        eprintln!(
            "mpm: walls on the points: the largest reach of a point's domain past a wall over the run is {past_walls:.3e} m ({:.3e} h)",
            past_walls / setup.bodies[0].grid.h
        );
    }
    if let Some(e) = failure {
        return Err(format!("{e} (history up to the previous step written to {})", out.display()));
    }
    eprintln!(
        "mpm: {} steps ({cut_steps} of them cut into sub-steps), {} points, {} Newton iterations, {wall:.2} s wall time; outputs in {}",
        reached.map_or(scene.steps, |(step, _)| step),
        n_points,
        total_iters,
        out.display()
    );
    Ok(())
}

//! What the study writes: `runs.csv`, `response_surface.csv`, the plots and `report.md`.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::grid::{law_text, write_atomic, CostRow, Options};
use super::jamming::{key3, Jamming};
use super::jamming_report::{jamming_section, rate_exponent_chart};
use super::paper::{PAPER_ALPHA, PAPER_BETA, PAPER_MU, PAPER_NU};
use super::protocol::{
    time_step, RunResult, DENSITY, DIAMETER, DT_OVERLAP, DT_PER_CONTACT, OUT_OF_RANGE, PHI_START,
    YOUNGS_MODULUS,
};
use super::surface::{qs_points, SurfaceRow};
use crate::harness::plot::{self, Chart, Series};

pub(super) fn f(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.6e}")
    } else {
        "nan".into()
    }
}

pub(super) fn rel(a: f64, b: f64) -> String {
    if a.is_finite() && b.is_finite() && b != 0.0 {
        format!("{:+.0} %", 100.0 * (a - b) / b)
    } else {
        "–".into()
    }
}

pub(super) fn write_outputs(
    opts: &Options,
    results: &[RunResult],
    failed: &[(String, String)],
    surface: &[SurfaceRow],
    phi_c: &BTreeMap<String, (f64, f64)>,
    jam: &[Jamming],
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
        w("stops.csv", &stops_csv(results, failed))?;
    }
    let mut rs = String::from(
        "mu,nu,phi_c,alpha,beta,alpha_paper,beta_paper,points,rms_log,phi_c_data,alpha_data,beta_data,beta_data_min,beta_data_max\n",
    );
    for r in surface {
        let _ = writeln!(
            rs,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.mu,
            r.nu,
            f(r.phi_c),
            f(r.alpha),
            f(r.beta),
            f(r.alpha_paper),
            f(r.beta_paper),
            r.points,
            f(r.rms_log),
            f(r.phi_c_data),
            f(r.alpha_data),
            f(r.beta_data),
            f(r.beta_data_min),
            f(r.beta_data_max)
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
    let mut plots = plots(opts, results, surface, cost)?;
    if let Some(chart_name) = rate_exponent_chart(opts, results)? {
        plots.push(chart_name);
    }
    let fits = Fits { surface, phi_c, jam };
    w("report.md", &report(opts, results, failed, &fits, cost, &plots))
}

pub(super) fn plots(
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

/// The fits the report states: Eq. 8 per (μ, ν), the free φ_c per μ (with the lower end of its
/// search), and φ_c from the rate data per μ.
pub(super) struct Fits<'a> {
    pub surface: &'a [SurfaceRow],
    pub phi_c: &'a BTreeMap<String, (f64, f64)>,
    pub jam: &'a [Jamming],
}

pub(super) fn report(
    opts: &Options,
    results: &[RunResult],
    failed: &[(String, String)],
    fits: &Fits,
    cost: &[CostRow],
    plots: &[String],
) -> String {
    let Fits { surface, phi_c, jam } = *fits;
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
         without an error (`liggghts_inputs/triclinic_ghost_probe.in`, tested in tests/plugin/decks.rs). The shear \
         runs on the standalone engine only; its Lees–Edwards contacts are tested against plain pairs at the \
         image positions (tests/dem/shear.rs).\n"
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
             (one rate only: p̂/γ̂² > 10³); a φ enters the fit of every ν of its μ when it is quasi-static for \
             more than half of the ν that ran there, so all ν of one μ are fitted over the same φ (a ν misses \
             only the φ where its run stopped). The slowest-rate p̂ enters the fit. The free fit's φ_c is shared \
             by all ν of one μ.\n"
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
        s.push_str(&jamming_section(surface, jam));
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
        let rescued: Vec<&RunResult> = results.iter().filter(|r| r.stopped_at_full_step.is_some()).collect();
        if !failed.is_empty() || !rescued.is_empty() {
            let _ = writeln!(
                s,
                "\n## Runs that stopped\n\nA run that stops at the contact law's limit (an overlap reaches a \
                 radius) is run again at Δt/2 (and Δt/4 when the two stops differ). *{OUT_OF_RANGE}*: it stops \
                 again at the same place (the stop converges in Δt), or at every step down to Δt/4, so the \
                 state lies beyond what the law can represent (a result about the model, not a failure). Runs \
                 that finished at Δt/2 or Δt/4 are listed too: their stop at Δt was the step's, and their \
                 results above are from the smaller step. All of them are in stops.csv.\n\n\
                 | run | class | cause |\n|---|---|---|"
            );
            for (k, e) in failed {
                let _ = writeln!(s, "| {k} | {} | {} |", stop_class(e), e.replace('|', "/"));
            }
            for r in rescued {
                let _ = writeln!(
                    s,
                    "| {} | finished at Δt/2 | stopped at shear strain {:.3} with Δt (0: in the compression) |",
                    r.spec.key(),
                    r.stopped_at_full_step.unwrap_or(f64::NAN)
                );
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

/// The class of a stop from the leading words of its message (`protocol::run_one`); a stop recorded
/// before stops were classified has none.
fn stop_class(e: &str) -> &'static str {
    if e.starts_with(OUT_OF_RANGE) {
        OUT_OF_RANGE
    } else {
        "unclassified"
    }
}

/// stops.csv: every run that stopped, and every run that finished only at Δt/2 or Δt/4.
fn stops_csv(results: &[RunResult], failed: &[(String, String)]) -> String {
    let mut s = String::from("run,class,stopped_at_full_step,message\n");
    for (k, e) in failed {
        let _ = writeln!(s, "{k},{},,\"{}\"", stop_class(e), e.replace('"', "'"));
    }
    for r in results.iter().filter(|r| r.stopped_at_full_step.is_some()) {
        // The step it finished at, as a divisor of the study's step (the run keeps its dt).
        let k = (time_step(r.spec.nu) / r.dt).round();
        let at = r.stopped_at_full_step.unwrap_or(f64::NAN);
        let _ = writeln!(s, "{},finished at dt/{k},{at},", r.spec.key());
    }
    s
}

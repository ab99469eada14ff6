//! The report's section on φ_c from the rate data (`jamming`) and the rate-exponent plot.

use std::fmt::Write as _;

use super::grid::Options;
use super::jamming::{jamming, key3, Crossing, Jamming, RatePoint, N_CROSS};
use super::protocol::RunResult;
use super::surface::SurfaceRow;
use crate::harness::plot::{self, Chart, Series};

fn crossing_text(c: Option<Crossing>) -> String {
    match c {
        Some(Crossing::At(x)) => format!("{x:.4}"),
        Some(Crossing::Below(x)) => format!("< {x} (n̄ < {N_CROSS} at the loosest φ)"),
        Some(Crossing::Above(x)) => format!("> {x} (n̄ ≥ {N_CROSS} at every φ)"),
        None => "–".into(),
    }
}

fn num(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".into()
    }
}

/// "## φ_c from the rate data": n̄(φ) per μ, φ_c by both routes, and Eq. 8 at the data-derived
/// φ_c next to the free fit and Tables D.1/D.2.
pub(super) fn jamming_section(surface: &[SurfaceRow], jam: &[Jamming]) -> String {
    let mut s = String::new();
    if jam.is_empty() {
        return s;
    }
    let _ = writeln!(s, "\n## φ_c from the rate data\n");
    let _ = writeln!(
        s,
        "n = d ln p̂ / d ln γ̂ between the two slowest rates, per (μ, ν, φ); n̄ ± sd is its mean and standard \
         deviation over ν. Inertial (Bagnold) flow gives n = 2, the intermediate regime 1, quasi-static flow 0. \
         **Route (a)**: φ_c where n̄ falls through {N_CROSS} (linear interpolation in φ; the same threshold as \
         the quasi-static test); error bar: the largest of half the spread of the crossings of n̄ ∓ sd, the \
         shift of the crossing when n is taken between the next two rates (at finite rate the crossover lies \
         above the γ̂ → 0 jamming point and moves up with the rate, so route (a) estimates φ_c from above), and \
         the difference between interpolating n and ln n (how far the grid spacing resolves the crossing). \
         **Route (b)**: per ν, the β for which p̂^(1/β) is most nearly linear in φ over the quasi-static \
         points, and the φ where that line reaches 0; mean ± sd over ν (the quasi-static branch extrapolated \
         to p̂ = 0, an estimate from below when the branch curves away from a power law far from φ_c). \
         The data-derived φ_c is route (a) where its crossing lies inside the grid, else route (b).\n"
    );
    let phis: Vec<f64> = {
        let mut v: Vec<f64> = jam.iter().flat_map(|j| j.curve.iter().map(|c| c.0)).collect();
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| key3(*a) == key3(*b));
        v
    };
    if !phis.is_empty() {
        let head: Vec<String> = phis.iter().map(|p| format!("φ = {p}")).collect();
        let _ = writeln!(
            s,
            "| μ | {} |\n|---|{}",
            head.join(" | "),
            phis.iter().map(|_| "---|").collect::<String>()
        );
        for j in jam {
            let cells: Vec<String> = phis
                .iter()
                .map(|&p| {
                    j.curve
                        .iter()
                        .find(|c| key3(c.0) == key3(p))
                        .map_or("–".into(), |c| format!("{:.2} ± {:.2}", c.1, c.2))
                })
                .collect();
            let _ = writeln!(s, "| {} | {} |", j.mu, cells.join(" | "));
        }
        let _ = writeln!(s, "\nn̄ ± sd over ν between the two slowest rates.\n");
    }
    let free =
        |mu: f64| surface.iter().find(|r| key3(r.mu) == key3(mu) && r.phi_c.is_finite()).map(|r| r.phi_c);
    let _ = writeln!(
        s,
        "| μ | quasi-static φ (all ν) | (a) n̄ = {N_CROSS} | (a) n̄ ∓ sd | (a) next rate pair | (a) φ_c ± | (b) p̂ → 0: φ_c ± sd (ν) | (b) β of the lines | free fit φ_c | φ_c (data) used |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    for j in jam {
        let spread = j.rate_spread.map_or("–".into(), |(a, b)| format!("{a:.4}–{b:.4}"));
        let (b, b_beta) = j.extrap.map_or(("–".into(), "–".into()), |(m, sd, beta, n)| {
            (format!("{m:.4} ± {sd:.4} ({n} ν)"), format!("{beta:.2}"))
        });
        let used = j.data.map_or("–".into(), |(pc, e, src)| format!("{pc:.4} ± {e:.4} ({src})"));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            j.mu,
            j.qs_phis.iter().map(|p| format!("{p}")).collect::<Vec<_>>().join(", "),
            crossing_text(j.rate),
            spread,
            crossing_text(j.rate_fast),
            if j.rate_err.is_finite() { format!("± {:.4}", j.rate_err) } else { "–".into() },
            b,
            b_beta,
            free(j.mu).map_or("–".into(), |x| format!("{x:.4}")),
            used
        );
    }
    let _ = writeln!(
        s,
        "\nEq. 8 with the free φ_c (above) and with the data-derived φ_c; \"β over φ_c ±\" is the range of β \
         refitted at the ends of φ_c's error bar (the upper end held 0.001 below the loosest quasi-static φ).\n"
    );
    let _ = writeln!(
        s,
        "| μ | ν | points | φ_c (free) | α (free) | β (free) | φ_c (data) | α (data) | β (data) | β over φ_c ± | α paper (D.1) | β paper (D.2) |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in surface {
        let range = if r.beta_data_min.is_finite() {
            format!("{:.2}–{:.2}", r.beta_data_min, r.beta_data_max)
        } else {
            "–".into()
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.mu,
            r.nu,
            r.points,
            num(r.phi_c, 4),
            num(r.alpha, 3),
            num(r.beta, 2),
            num(r.phi_c_data, 4),
            num(r.alpha_data, 3),
            num(r.beta_data, 2),
            range,
            num(r.alpha_paper, 3),
            num(r.beta_paper, 3)
        );
    }
    s
}

/// `rate_exponent_vs_phi.png`: n̄(φ) between the two slowest rates per μ, with its ν spread, and
/// the level of route (a). None for a grid with one rate.
pub(super) fn rate_exponent_chart(opts: &Options, results: &[RunResult]) -> Result<Option<String>, String> {
    let pts: Vec<RatePoint> = results.iter().map(RatePoint::of).collect();
    let mut series = Vec::new();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &mu in &opts.grid.mus {
        let c = jamming(&pts, mu).curve;
        if c.is_empty() {
            continue;
        }
        for p in &c {
            lo = lo.min(p.0);
            hi = hi.max(p.0);
        }
        series.push(Series {
            label: format!("μ = {mu}"),
            points: c.iter().map(|p| (p.0, p.1)).collect(),
            markers: true,
            thin: false,
        });
    }
    if series.is_empty() {
        return Ok(None);
    }
    series.push(Series {
        label: format!("n = {N_CROSS} (route (a))"),
        points: vec![(lo, N_CROSS), (hi, N_CROSS)],
        markers: false,
        thin: true,
    });
    let name = "rate_exponent_vs_phi.png".to_string();
    plot::draw(
        &opts.out.join(&name),
        &Chart {
            title: "rate exponent d ln p̂ / d ln γ̂ (two slowest rates, mean over ν) vs φ",
            x_label: "φ",
            y_label: "n",
            log_x: false,
            log_y: false,
            series,
        },
    )?;
    Ok(Some(name))
}

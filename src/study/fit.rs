//! Eq. 8 of Ghods et al. (2022): p̂ = α |φ − φ_c|^β, fitted above jamming.
//!
//! For a given φ_c the fit is linear in log space (ln p̂ = ln α + β ln(φ − φ_c)); φ_c itself is
//! found by minimising the summed squared log residuals, shared by several data sets (the paper's
//! φ_c depends on μ only, so every ν of one μ shares it).

/// α, β and the sum of squared log residuals of one data set at a fixed φ_c.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerLaw {
    pub alpha: f64,
    pub beta: f64,
    pub sse: f64,
}

/// Least squares of ln p on ln(φ − φ_c); None with fewer than two usable points.
pub fn power_law(points: &[(f64, f64)], phi_c: f64) -> Option<PowerLaw> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|(phi, p)| *phi > phi_c && *p > 0.0)
        .map(|(phi, p)| ((phi - phi_c).ln(), p.ln()))
        .collect();
    if xy.len() < 2 || xy.len() < points.len() {
        return None;
    }
    let n = xy.len() as f64;
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / n;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let beta = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / sxx;
    let a = my - beta * mx;
    let sse = xy.iter().map(|p| (p.1 - a - beta * p.0).powi(2)).sum();
    Some(PowerLaw { alpha: a.exp(), beta, sse })
}

/// Shared-φ_c fit of several data sets (each (φ, p̂) points, at least three per set). φ_c is
/// searched in [lo, min φ − 1e-4]: a scan of 4000 points, then a golden-section refinement.
pub fn shared_phi_c(sets: &[Vec<(f64, f64)>], lo: f64) -> Option<(f64, Vec<PowerLaw>)> {
    if sets.is_empty() || sets.iter().any(|s| s.len() < 3) {
        return None;
    }
    let phi_min = sets.iter().flatten().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = phi_min - 1e-4;
    if hi <= lo {
        return None;
    }
    let cost = |pc: f64| -> f64 {
        let mut s = 0.0;
        for set in sets {
            match power_law(set, pc) {
                Some(f) => s += f.sse,
                None => return f64::INFINITY,
            }
        }
        s
    };
    let n = 4000;
    let h = (hi - lo) / n as f64;
    let (mut best, mut best_c) = (lo, f64::INFINITY);
    for k in 0..=n {
        let pc = lo + k as f64 * h;
        let c = cost(pc);
        if c < best_c {
            best = pc;
            best_c = c;
        }
    }
    // Golden section on the bracket around the best scan point.
    let (mut a, mut b) = ((best - h).max(lo), (best + h).min(hi));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let c1 = b - g * (b - a);
        let c2 = a + g * (b - a);
        if cost(c1) < cost(c2) {
            b = c2;
        } else {
            a = c1;
        }
    }
    let mid = 0.5 * (a + b);
    let pc = if cost(mid) < best_c { mid } else { best };
    let fits = sets.iter().map(|s| power_law(s, pc)).collect::<Option<Vec<_>>>()?;
    Some((pc, fits))
}

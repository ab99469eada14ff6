//! The finite-element continuum reference of the single sphere in the rigid die
//! (`validation/reference/continuum_die_*.csv`, made by `mcdem continuum`, see
//! `validation/reference/README.md` and docs/continuum.md): the plate and side-wall stress of one
//! elastic sphere (r = 1 mm, E = 23.3 kPa) in a rigid frictionless die of side 2r: the finest
//! mesh, with the spread to the two next-finest meshes as error bar (the mesh sequence is not
//! monotone, so Richardson extrapolation does not apply). Embedded, so `mcdem validate` needs no
//! files.
//!
//! The single-particle case measures Hertz, standard and advanced MC and the nonlocal kernels
//! against it, next to the nonlocal reference: plate NRMSE, side NRMSE normalised by the side
//! curve's own mean, and side NRMSE normalised by the plate curve's mean (the scale of the paper's
//! Fig. B.2, where both curves share one axis).

use std::fmt::Write as _;

use crate::harness::runner;

/// A curve of the die: (displacement / r, plate stress [Pa], side-wall stress [Pa]), for the
/// references here and the models of `die`.
pub(super) type Curve = Vec<(f64, f64, f64)>;

/// One reference curve: material law, Poisson ratio and file name, with its points.
pub struct Reference {
    pub law: &'static str,
    pub nu: f64,
    pub file: &'static str,
    /// (Δ/r, plate stress [Pa], its error bar [Pa], side stress [Pa], its error bar [Pa]).
    pub points: Vec<[f64; 5]>,
}

/// The embedded curves: (law, ν, file name, text).
const CURVES: &[(&str, f64, &str, &str)] = &[
    (
        "neo_hookean",
        0.45,
        "continuum_die_neo_hookean_nu0.45.csv",
        include_str!("../../validation/reference/continuum_die_neo_hookean_nu0.45.csv"),
    ),
    (
        "neo_hookean",
        0.49,
        "continuum_die_neo_hookean_nu0.49.csv",
        include_str!("../../validation/reference/continuum_die_neo_hookean_nu0.49.csv"),
    ),
    (
        "neo_hookean",
        0.499,
        "continuum_die_neo_hookean_nu0.499.csv",
        include_str!("../../validation/reference/continuum_die_neo_hookean_nu0.499.csv"),
    ),
];

fn parse(text: &str, file: &str) -> Result<Vec<[f64; 5]>, String> {
    let mut lines = text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header = lines.next().ok_or(format!("{file}: empty"))?;
    if header.trim() != "delta_over_r,plate_stress_pa,plate_err_pa,side_stress_pa,side_err_pa" {
        return Err(format!("{file}: unexpected header '{header}'"));
    }
    lines
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.trim().parse::<f64>().map_err(|_| format!("{file}: bad line '{l}'")))
                .collect::<Result<_, _>>()?;
            <[f64; 5]>::try_from(v).map_err(|_| format!("{file}: expected 5 columns in '{l}'"))
        })
        .collect()
}

/// The embedded reference whose ν is closest to `nu` (Neo-Hookean preferred on a tie).
pub fn closest(nu: f64) -> Result<Reference, String> {
    let (law, rnu, file, text) = CURVES
        .iter()
        .min_by(|a, b| (a.1 - nu).abs().total_cmp(&(b.1 - nu).abs()))
        .ok_or("no continuum reference embedded")?;
    Ok(Reference { law, nu: *rnu, file, points: parse(text, file)? })
}

/// NRMSE of a model against the continuum: plate, side (own mean), side (plate mean).
#[derive(Clone, Copy)]
pub struct Errors {
    pub plate: f64,
    pub side: f64,
    pub side_plate_mean: f64,
}

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

fn mean_abs(a: &[f64]) -> f64 {
    a.iter().map(|x| x.abs()).sum::<f64>() / a.len() as f64
}

impl Reference {
    /// The model interpolated at the reference's Δ/r (points the model does not reach are left
    /// out; every model here runs to 0.3 r, as far as the reference).
    pub fn errors(&self, model: &Curve) -> Errors {
        let plate: Vec<(f64, f64)> = model.iter().map(|p| (p.0, p.1)).collect();
        let side: Vec<(f64, f64)> = model.iter().map(|p| (p.0, p.2)).collect();
        let (mut mp, mut rp, mut ms, mut rs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for p in &self.points {
            if let (Some(a), Some(b)) = (runner::interpolate(&plate, p[0]), runner::interpolate(&side, p[0]))
            {
                mp.push(a);
                rp.push(p[1]);
                ms.push(b);
                rs.push(p[3]);
            }
        }
        if mp.is_empty() {
            return Errors { plate: f64::NAN, side: f64::NAN, side_plate_mean: f64::NAN };
        }
        Errors {
            plate: rms(&mp, &rp) / mean_abs(&rp),
            side: rms(&ms, &rs) / mean_abs(&rs),
            side_plate_mean: rms(&ms, &rs) / mean_abs(&rp),
        }
    }

    /// The reference's own uncertainty on the same scales: RMS error bar over the mean.
    pub fn own_uncertainty(&self) -> Errors {
        let col = |i: usize| self.points.iter().map(|p| p[i]).collect::<Vec<_>>();
        let zero = vec![0.0; self.points.len()];
        let (pe, se) = (rms(&col(2), &zero), rms(&col(4), &zero));
        Errors {
            plate: pe / mean_abs(&col(1)),
            side: se / mean_abs(&col(3)),
            side_plate_mean: se / mean_abs(&col(1)),
        }
    }

    pub fn curve(&self) -> Curve {
        self.points.iter().map(|p| (p[0], p[1], p[3])).collect()
    }

    pub fn name(&self) -> String {
        format!("continuum_{}_nu{}", self.law, self.nu)
    }

    /// The report section: one line per model, then the reference's own error bars.
    pub fn markdown(&self, case_nu: f64, rows: &[(String, Errors)]) -> String {
        let mut md = format!(
            "\nAgainst the finite-element continuum (`validation/reference/{}`: {} ν = {}, the embedded curve closest to the case's ν = {case_nu}; \
             frictionless rigid die, finest mesh with the spread to the two next-finest as error bar (the file's header), Δ/r = {:.2} … {:.2}). \
             Side NRMSE twice: over the side curve's own mean, and over the plate curve's mean (Fig. B.2's common axis):\n\n\
             | model | NRMSE plate | NRMSE side (side mean) | NRMSE side (plate mean) |\n|---|---|---|---|\n",
            self.file,
            self.law,
            self.nu,
            self.points.first().map_or(f64::NAN, |p| p[0]),
            self.points.last().map_or(f64::NAN, |p| p[0]),
        );
        for (name, e) in rows {
            let _ = writeln!(
                md,
                "| {name} | {:.2} % | {:.2} % | {:.2} % |",
                100.0 * e.plate,
                100.0 * e.side,
                100.0 * e.side_plate_mean
            );
        }
        let u = self.own_uncertainty();
        let _ = writeln!(
            md,
            "| (continuum error bars, RMS / mean) | {:.2} % | {:.2} % | {:.2} % |",
            100.0 * u.plate,
            100.0 * u.side,
            100.0 * u.side_plate_mean
        );
        md
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every embedded curve parses, is finite, starts above zero and rises monotonically.
    #[test]
    fn embedded_curves_parse() {
        for (_, nu, file, text) in CURVES {
            let p = parse(text, file).unwrap();
            assert!(p.len() >= 10, "{file}");
            assert!(p.iter().flatten().all(|v| v.is_finite()), "{file}");
            assert!(p.windows(2).all(|w| w[1][0] > w[0][0] && w[1][1] > w[0][1]), "{file}");
            assert_eq!(closest(*nu).unwrap().file, *file);
        }
    }
}

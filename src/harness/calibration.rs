//! The contact laws of the hydrogel deck (`liggghts_inputs/hydrogel.in`) and the recorded per-ν
//! calibration of the advanced multi-contact law, used by the uniaxial validation, the calibration
//! itself and the shear study.

/// The per-ν advanced-MC parameters fitted by `mcdem calibrate` (full mode, kernel `sphere`, the
/// same start states and reference as the uniaxial validation case), recorded in `validation/reference/` and built
/// into the binary so the case needs no file at run time.
const CALIBRATION: &str = include_str!("../../validation/reference/calibration_mcdem.csv");

/// The recorded calibration's law for ν, if it has this ν (columns as `mcdem calibrate` writes
/// them: nu,gamma,mpr,youngs_modulus_pa,nrmse,…; `#` lines are comments).
pub fn calibrated(nu: f64) -> Option<Law> {
    recorded().into_iter().find(|r| (r.nu - nu).abs() < 1e-9).map(|r| r.law)
}

/// Every row of the built-in calibration (checked by this module's test, so it cannot fail).
pub fn recorded() -> Vec<Fitted> {
    parse_calibration(CALIBRATION, "validation/reference/calibration_mcdem.csv")
        .expect("the built-in calibration parses (tested)")
}

/// One row of a calibration file: the Poisson ratio, the fitted law and the NRMSE the fit reached
/// (its residual on the curve it was fitted on).
#[derive(Debug, Clone, Copy)]
pub struct Fitted {
    pub nu: f64,
    pub law: Law,
    pub nrmse: f64,
}

/// The rows of a calibration file in `mcdem calibrate`'s `calibration.csv` format (header naming
/// at least nu, gamma, mpr, youngs_modulus_pa and nrmse; `#` lines are comments). `file` names the
/// text in errors.
pub fn parse_calibration(text: &str, file: &str) -> Result<Vec<Fitted>, String> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty());
    let (_, header) = lines.next().ok_or(format!("{file}: no header line"))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let col =
        |n: &str| names.iter().position(|h| *h == n).ok_or(format!("{file}: the header has no column '{n}'"));
    let c = [col("nu")?, col("gamma")?, col("mpr")?, col("youngs_modulus_pa")?, col("nrmse")?];
    let mut rows = Vec::new();
    for (i, l) in lines {
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        let mut v = [0.0; 5];
        for (k, &ck) in c.iter().enumerate() {
            let x = f.get(ck).ok_or(format!("{file}:{}: missing column '{}'", i + 1, names[ck]))?;
            v[k] = x.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or(format!(
                "{file}:{}: '{}' is not a number: '{x}'",
                i + 1,
                names[ck]
            ))?;
        }
        let [nu, gamma, mpr, e, nrmse] = v;
        if !(0.0..=0.5).contains(&nu) || gamma <= 0.0 || mpr < 0.0 || e <= 0.0 || nrmse < 0.0 {
            return Err(format!(
                "{file}:{}: out of range (nu in [0, 0.5], gamma > 0, mpr >= 0, E > 0, nrmse >= 0)",
                i + 1
            ));
        }
        rows.push(Fitted { nu, law: Law { youngs_modulus: e, ..Law::advanced(gamma, mpr) }, nrmse });
    }
    Ok(rows)
}

/// The hydrogel's Young's modulus [Pa] (paper Table 1).
pub const E_HYDROGEL: f64 = 23.3e3;

/// A contact law of `liggghts_inputs/hydrogel.in` with its parameters.
#[derive(Debug, Clone, Copy)]
pub struct Law {
    /// The deck's `law` variable: 0 mc_advanced, 1 hertz, 2 standard MC.
    pub law: &'static str,
    pub gamma: f64,
    pub mpr: f64,
    /// The particles' Young's modulus [Pa] (the calibration's third parameter).
    pub youngs_modulus: f64,
    /// `geometryTolerance` of `mc_advanced` (0: exact).
    pub geometry_tolerance: f64,
    /// `updateEvery` of `mc_advanced` (1: exact).
    pub update_every: u64,
}

impl Law {
    pub const HERTZ: Law = Law {
        law: "1",
        gamma: 1.0,
        mpr: 0.0,
        youngs_modulus: E_HYDROGEL,
        geometry_tolerance: 0.0,
        update_every: 1,
    };

    pub fn standard(gamma: f64) -> Self {
        Law { law: "2", gamma, mpr: 0.0, ..Self::HERTZ }
    }

    pub fn advanced(gamma: f64, mpr: f64) -> Self {
        Law { law: "0", gamma, mpr, ..Self::HERTZ }
    }
}

#[cfg(test)]
mod tests {
    /// The recorded calibration is built in: every row parses into a valid law, and a ν without a
    /// row has none (the case then runs the App. B values only).
    #[test]
    fn recorded_calibration_parses() {
        let rows = super::recorded();
        assert_eq!(rows.len(), 6);
        for r in rows {
            let law = super::calibrated(r.nu).expect("a row for its own ν");
            assert_eq!(
                (law.gamma, law.mpr, law.youngs_modulus),
                (r.law.gamma, r.law.mpr, r.law.youngs_modulus)
            );
            assert!(r.nrmse > 0.0 && r.nrmse < 0.1, "a fit residual of a few per cent: {}", r.nrmse);
        }
        assert!(super::calibrated(0.123).is_none());
    }

    /// A damaged calibration file stops with its name, line and field.
    #[test]
    fn bad_calibration_names_the_problem() {
        let h = "nu,gamma,mpr,youngs_modulus_pa,nrmse\n";
        let e = super::parse_calibration(&format!("{h}0.5,x,0.1,2e4,0.03\n"), "f.csv").unwrap_err();
        assert!(e.contains("f.csv:2") && e.contains("'gamma'"), "{e}");
        let e = super::parse_calibration("nu,gamma,mpr,youngs_modulus_pa\n", "f.csv").unwrap_err();
        assert!(e.contains("'nrmse'"), "{e}");
        let e = super::parse_calibration(&format!("{h}0.7,1,0.1,2e4,0.03\n"), "f.csv").unwrap_err();
        assert!(e.contains("out of range"), "{e}");
    }
}

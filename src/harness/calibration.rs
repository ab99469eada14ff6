//! The contact laws of the hydrogel deck (`liggghts_inputs/hydrogel.in`) and the recorded per-ν
//! calibration of the advanced multi-contact law, used by the uniaxial validation, the calibration
//! itself and the shear study.

/// The per-ν advanced-MC parameters fitted by `mcdem calibrate` (full mode, kernel `sphere`, the
/// same start states and reference as the uniaxial validation case), recorded in `validation/reference/` and built
/// into the binary so the case needs no file at run time.
const CALIBRATION: &str = include_str!("../../validation/reference/calibration_mcdem.csv");

/// The recorded calibration's law for ν, if it has this ν (columns as `mcdem calibrate` writes
/// them: nu,gamma,mpr,youngs_modulus_pa,…; `#` lines are comments).
pub fn calibrated(nu: f64) -> Option<Law> {
    calibration_rows()
        .into_iter()
        .find(|r| (r.0 - nu).abs() < 1e-9)
        .map(|r| Law { youngs_modulus: r.3, ..Law::advanced(r.1, r.2) })
}

/// (ν, γ, MPR, E) of every recorded calibration row.
fn calibration_rows() -> Vec<(f64, f64, f64, f64)> {
    CALIBRATION
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("nu,") && !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .take(4)
                .map(|x| x.trim().parse().expect("recorded calibration: a number"))
                .collect();
            (v[0], v[1], v[2], v[3])
        })
        .collect()
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
        let rows = super::calibration_rows();
        assert!(!rows.is_empty());
        for (nu, gamma, mpr, e) in rows {
            let law = super::calibrated(nu).expect("a row for its own ν");
            assert_eq!((law.gamma, law.mpr, law.youngs_modulus), (gamma, mpr, e));
            assert!((0.0..=0.5).contains(&nu) && gamma > 0.0 && mpr >= 0.0 && e > 0.0);
        }
        assert!(super::calibrated(0.123).is_none());
    }
}

//! `mcdem contacts FILE`: evaluates the per-particle kernel for one particle described in JSON.
//!
//! ```text
//! in:  {"radius": 0.001, "youngs_modulus": 23300.0, "poisson_ratio": 0.5, "gamma": 0.81, "mpr": 0.11,
//!       "mpr_test": "abs", "contacts": [{"point": [0.0, 0.0, -0.00095], "force": 0.0012}, ...]}
//! out: {"delta": [...], "hertz_fallback": [false, ...]}
//! ```
//! Without `mpr` the kernel is standard MC. Unknown fields are rejected (a typo must not silently
//! fall back to a default).

use serde::{Deserialize, Serialize};

use crate::physics::contact_set::{radius_changes, ContactLoad, McParams};
use crate::physics::ghods2022::{Cap, MprTest};
use crate::physics::Vec3;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ContactIn {
    point: [f64; 3],
    force: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParticleIn {
    radius: f64,
    youngs_modulus: f64,
    poisson_ratio: f64,
    gamma: f64,
    mpr: Option<f64>,
    mpr_test: Option<String>,
    contacts: Vec<ContactIn>,
}

/// Kernel output in input order.
#[derive(Debug, Serialize, PartialEq)]
pub struct ContactsOut {
    pub delta: Vec<f64>,
    pub hertz_fallback: Vec<bool>,
}

/// Parses the JSON particle, validates it and evaluates the kernel. Errors are one line, naming
/// the problem.
pub fn evaluate(json: &str) -> Result<ContactsOut, String> {
    let p: ParticleIn = serde_json::from_str(json).map_err(|e| format!("invalid input JSON: {e}"))?;
    let test = match &p.mpr_test {
        None => MprTest::default(),
        Some(s) => s.parse::<MprTest>()?,
    };
    if p.mpr.is_none() && p.mpr_test.is_some() {
        return Err(
            "mpr_test given without mpr: set mpr for advanced MC, or drop mpr_test for standard MC".into()
        );
    }
    let params = McParams {
        radius: p.radius,
        youngs_modulus: p.youngs_modulus,
        poisson_ratio: p.poisson_ratio,
        gamma: p.gamma,
        cap: p.mpr.map(|mpr| Cap { mpr, test }),
    };
    params.validate().map_err(|e| e.to_string())?;
    let loads: Vec<ContactLoad> =
        p.contacts.iter().map(|c| ContactLoad { point: Vec3::from(c.point), force: c.force }).collect();
    for (i, c) in loads.iter().enumerate() {
        if !c.point.iter().all(|v| v.is_finite()) {
            return Err(format!("contacts[{i}].point is not finite"));
        }
        if !c.force.is_finite() || c.force < 0.0 {
            return Err(format!("contacts[{i}].force = {} must be finite and >= 0 (a magnitude)", c.force));
        }
    }
    let mut delta = vec![0.0; loads.len()];
    let mut fallback = vec![false; loads.len()];
    radius_changes(&params, &loads, &mut delta, &mut fallback).map_err(|e| e.to_string())?;
    Ok(ContactsOut { delta, hertz_fallback: fallback })
}

//! Case `physics_checks`: the contact core against analytic limits and independent formulas
//! (see [`crate::checks`]).

use std::fmt::Write as _;

use super::{CaseResult, Options, Row};

pub fn run(_opts: &Options) -> Result<CaseResult, String> {
    let checks = crate::checks::run_all();
    let mut md = String::from("| check | error | tolerance | result | what |\n|---|---|---|---|---|\n");
    let mut rows = Vec::new();
    for c in &checks {
        let _ = writeln!(
            md,
            "| {} | {:.3e} | {:.3e} | {} | {} |",
            c.name,
            c.error,
            c.tolerance,
            if c.passed { "pass" } else { "FAIL" },
            c.what
        );
        rows.push(Row {
            case: "physics_checks",
            model: "core".into(),
            params: c.name.into(),
            x_name: "check".into(),
            x: 0.0,
            quantity: "error".into(),
            value: c.error,
        });
    }
    Ok(CaseResult {
        name: "physics_checks",
        title: "contact core vs analytic limits".into(),
        passed: checks.iter().all(|c| c.passed),
        targets: Vec::new(),
        rows,
        models: Vec::new(),
        markdown: md,
        wall_time_s: 0.0,
    })
}

//! The contact-set kernel alone (Eq. 2 with and without the cap) for 2, 6 and 12 loaded contacts
//! spread over one sphere: calls per second, timed over a fixed wall-clock budget. The criterion
//! benchmark `benches/contact_kernel.rs` measures the same calls with statistics.

use std::hint::black_box;
use std::time::Instant;

use super::{Options, Report, Row};
use crate::physics::contact_set::{radius_changes, McParams};
use crate::physics::ghods2022::{Cap, MprTest};

pub fn rows(opts: &Options, report: &mut Report, say: &mut dyn FnMut(&str)) {
    let r = 1e-3;
    let budget = if opts.quick { 0.05 } else { 0.5 };
    for n in [2usize, 6, 12] {
        let cs = crate::harness::spread_contacts(n, r, 1e-3);
        let (mut delta, mut fb) = (vec![0.0; n], vec![false; n]);
        for (model, cap) in
            [("kernel_standard", None), ("kernel_advanced", Some(Cap { mpr: 0.11, test: MprTest::Abs }))]
        {
            let p = McParams { radius: r, youngs_modulus: 23.3e3, poisson_ratio: 0.5, gamma: 0.81, cap };
            let t0 = Instant::now();
            let mut calls = 0u64;
            while t0.elapsed().as_secs_f64() < budget {
                for _ in 0..1000 {
                    let _ = radius_changes(black_box(&p), black_box(&cs), &mut delta, &mut fb);
                }
                calls += 1000;
            }
            let secs = t0.elapsed().as_secs_f64();
            report.rows.push(Row {
                engine: "rust",
                model: model.into(),
                scene: format!("kernel_{n}_contacts"),
                n,
                threads: 1,
                particle_steps_per_s: calls as f64 / secs,
                wall_time_s: secs,
                memory_bytes_per_particle: None,
                rounds_particle_steps_per_s: Vec::new(),
            });
        }
        say(&format!("kernel, {n} contacts: done"));
    }
}

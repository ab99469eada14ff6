//! What the validation harness (`validate`), the benchmarks (`bench`) and the studies (`study`)
//! share, so that none of the three imports another: running a deck in a scratch directory
//! ([`runner`]), the report plots ([`plot`]), the progress display of long commands ([`progress`]),
//! the recorded calibration of the hydrogel deck's laws ([`calibration`]) and the many-contact test
//! particle ([`spread_contacts`]).

pub mod calibration;
pub mod plot;
pub mod progress;
pub mod runner;

use crate::physics::contact_set::ContactLoad;
use crate::physics::Vec3;

/// `n` contacts, each carrying `force`, spread evenly over a sphere of radius `r` (Fibonacci
/// lattice), at depth 0.95 r: the standard many-contact particle of the hard cases and benchmarks.
pub fn spread_contacts(n: usize, r: f64, force: f64) -> Vec<ContactLoad> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let rho = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            ContactLoad { point: Vec3::new(rho * phi.cos(), rho * phi.sin(), z) * 0.95 * r, force }
        })
        .collect()
}

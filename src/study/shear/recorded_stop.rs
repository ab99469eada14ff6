//! Stops recorded before the study classified them: a `.failed` file holding only the engine's
//! message of a contact-range stop in the shear at Δt. The run at Δt is deterministic (same seed,
//! same binary path), so its stop need not be run again to be classified: its place follows from
//! the world's step in the message, and only Δt/2 (and Δt/4) are run (`protocol::classify_from`).

use super::protocol::{steps_per_window, time_step, time_unit, Protocol, RunSpec, Stop};
use crate::physics::pair::ContactError;

/// The stop at Δt written in `text`, the `.failed` text of a run stopped before classification:
/// "shear: step N: particle i: contact with particle j: overlap X m reached the particle radius R m
/// (…)". The world's step N counts the compression's `compress_steps` first (the shear's k-th step
/// is N = compress_steps + k, as `protocol::run_refined` steps the world), so the shear strain at the
/// stop is (N − compress_steps) / (steps per window) × window. `None` for any other text: a stop in
/// the compression, another cause, or a text the study wrote after classifying (those begin with
/// the class).
pub fn recorded_stop(spec: &RunSpec, proto: &Protocol, text: &str) -> Option<Stop> {
    let text = text.trim();
    let rest = text.strip_prefix("shear: step ")?;
    let step: u64 = rest.split(':').next()?.trim().parse().ok()?;
    let shear_steps = step.checked_sub(proto.compress_steps).filter(|&k| k > 0)?;
    let overlap = number_after(rest, "overlap ")?;
    let radius = number_after(rest, "reached the particle radius ")?;
    let gdot = spec.gamma_hat / time_unit(spec.nu);
    let spw = steps_per_window(proto, gdot, time_step(spec.nu));
    Some(Stop {
        strain: Some(shear_steps as f64 / spw as f64 * proto.window),
        message: text.to_string(),
        contact: Some(ContactError::OverlapBeyondRadius { overlap, radius }),
    })
}

/// The number (in metres, "X m") that follows `key` in `s`.
fn number_after(s: &str, key: &str) -> Option<f64> {
    let at = s.find(key)? + key.len();
    s[at..].split_whitespace().next()?.parse().ok().filter(|x: &f64| x.is_finite())
}

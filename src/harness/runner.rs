//! Running a deck from `liggghts_inputs/` for a validation case: with the Rust DEM in-process, or
//! with the LIGGGHTS plugin executable (`mcdem-liggghts`) as a child process when it is built.
//! Each run gets its own scratch directory, so cases can run decks side by side.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use crate::deck::DeckFailure;

/// What one deck run produced.
#[derive(Debug, Clone)]
pub struct DeckRun {
    /// Rows of the deck's `fix ave/time` file (first column the time step).
    pub table: Vec<Vec<f64>>,
    pub wall_time_s: f64,
    pub particle_steps_per_s: f64,
}

/// The deck directory of this source tree.
pub fn decks_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs")
}

/// The plugin executable, when it has been built (`--features liggghts`): next to the running
/// executable, or in this tree's `target/release`.
pub fn plugin_exe() -> Option<PathBuf> {
    let beside = std::env::current_exe().ok().map(|p| p.with_file_name("mcdem-liggghts"));
    let tree = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/release/mcdem-liggghts");
    beside.into_iter().chain([tree]).find(|p| p.is_file())
}

/// A private scratch directory, removed when dropped (also when a run fails).
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new() -> Result<Self, String> {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "mcdem-validate-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        Ok(Self(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The variables every run gets: the deck directory and scratch paths for the `out` (ave/time)
/// and `dump` files.
fn standard_vars(scratch: &Path, vars: &[(&str, String)]) -> Vec<(String, String)> {
    let mut all: Vec<(String, String)> = vars.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
    all.push(("dir".into(), decks_dir().display().to_string()));
    all.push(("out".into(), scratch.join("out.txt").display().to_string()));
    all.push(("dump".into(), scratch.join("out.dump").display().to_string()));
    all
}

/// Runs `deck` (a file of `liggghts_inputs/`) with the Rust DEM, in-process and quiet.
pub fn run_rust(deck: &str, vars: &[(&str, String)]) -> Result<DeckRun, DeckFailure> {
    let scratch = Scratch::new().map_err(DeckFailure::other)?;
    let opts = crate::deck::Options {
        vars: standard_vars(&scratch.0, vars),
        log: Some(PathBuf::from("none")),
        progress: false,
        quiet: true,
        ..Default::default()
    };
    let t = Instant::now();
    let summary = crate::deck::run_file_checked(&decks_dir().join(deck), &opts)
        .map_err(|e| e.context(&format!("mcdem run {deck}")))?;
    let wall_time_s = t.elapsed().as_secs_f64();
    let table = crate::outputs::read_ave_time(&scratch.0.join("out.txt")).map_err(DeckFailure::other)?;
    Ok(DeckRun {
        table,
        wall_time_s,
        particle_steps_per_s: summary.particle_steps / summary.loop_seconds.max(1e-12),
    })
}

/// Runs `deck` with the LIGGGHTS plugin executable `exe`; the rate comes from LIGGGHTS's
/// "Loop time of T on P procs for N steps with A atoms" lines.
pub fn run_liggghts(exe: &Path, deck: &str, vars: &[(&str, String)]) -> Result<DeckRun, String> {
    let scratch = Scratch::new()?;
    let mut cmd = Command::new(exe);
    cmd.current_dir(&scratch.0)
        .arg("-in")
        .arg(decks_dir().join(deck))
        .args(["-log", "none", "-echo", "none"]);
    for (k, v) in standard_vars(&scratch.0, vars) {
        cmd.arg("-var").arg(k).arg(v);
    }
    let t = Instant::now();
    let out = cmd.output().map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
    let wall_time_s = t.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() || text.contains("ERROR") {
        let tail: Vec<&str> = text.lines().rev().take(4).collect();
        return Err(format!("{} {deck} failed: {}", exe.display(), tail.join(" | ")));
    }
    let rate = crate::outputs::loop_totals(&text).map_or(0.0, |t| t.rate());
    let table = crate::outputs::read_ave_time(&scratch.0.join("out.txt"))?;
    Ok(DeckRun { table, wall_time_s, particle_steps_per_s: rate })
}

/// Linear interpolation of the points `(x, y)` (x increasing) at `x0`; `None` outside the range.
pub fn interpolate(points: &[(f64, f64)], x0: f64) -> Option<f64> {
    let k = points.windows(2).position(|w| w[0].0 <= x0 && x0 <= w[1].0)?;
    let ((xa, ya), (xb, yb)) = (points[k], points[k + 1]);
    Some(if xb > xa { ya + (yb - ya) * (x0 - xa) / (xb - xa) } else { ya })
}

#[cfg(test)]
mod tests {
    #[test]
    fn interpolation_inside_and_outside() {
        let p = [(0.0, 0.0), (1.0, 2.0), (2.0, 2.0)];
        assert_eq!(super::interpolate(&p, 0.5), Some(1.0));
        assert_eq!(super::interpolate(&p, 2.0), Some(2.0));
        assert_eq!(super::interpolate(&p, 2.5), None);
    }
}

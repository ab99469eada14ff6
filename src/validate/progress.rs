//! Progress of a long validation case: on a terminal a spinner with the case, the time it has run
//! and the time left; elsewhere (logs, CI) a plain line at most every 10 s. The time left comes from
//! the same case's wall time in the previous report in the output directory, when there is one.

use std::io::IsTerminal;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Reports until dropped.
pub struct Ticker {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

/// The wall time [s] of `case` in the previous `summary.json` under `out`, if any and of the same
/// mode.
pub fn previous_wall_time(out: &Path, case: &str, quick: bool) -> Option<f64> {
    let text = std::fs::read_to_string(out.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    if v["quick"].as_bool()? != quick {
        return None;
    }
    v["cases"].as_array()?.iter().find(|c| c["name"] == case)?["wall_time_s"].as_f64()
}

fn left(elapsed: f64, expected: Option<f64>) -> String {
    match expected {
        Some(t) if t > elapsed => format!(", about {:.0} s left (last run {t:.0} s)", t - elapsed),
        Some(t) => format!(", longer than the last run ({t:.0} s)"),
        None => String::new(),
    }
}

impl Ticker {
    pub fn start(case: &str, expected: Option<f64>) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let case = case.to_string();
        let thread = std::thread::spawn(move || {
            let t0 = Instant::now();
            let terminal = std::io::stderr().is_terminal();
            let bar = terminal.then(|| {
                let b = indicatif::ProgressBar::new_spinner();
                b.enable_steady_tick(Duration::from_millis(200));
                b
            });
            let mut next_line = 10.0;
            while !flag.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(200));
                let s = t0.elapsed().as_secs_f64();
                match &bar {
                    Some(b) => b.set_message(format!("validate: {case}: {s:.0} s{}", left(s, expected))),
                    None if s >= next_line => {
                        eprintln!("validate: {case}: running for {s:.0} s{}", left(s, expected));
                        next_line += 10.0;
                    }
                    None => {}
                }
            }
            if let Some(b) = bar {
                b.finish_and_clear();
            }
        });
        Ticker { stop, thread: Some(thread) }
    }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

//! Progress of a long command (`validate`, `calibrate`, `study shear`, `bench`): how many of its
//! n work items are done, which are running, the time elapsed and an estimate of the time left.
//!
//! On a terminal (standard error is one) an indicatif bar `i/n` with the running items, the elapsed
//! time and the estimate; elsewhere (logs, CI) a plain line on standard error at most once per
//! interval (10 s, or `MCDEM_PROGRESS_INTERVAL` seconds), e.g.
//! `validate: 2/5 done, running uniaxial (nu=0.45: hertz), 123 s elapsed, about 300 s left`.
//! A run shorter than the interval prints no such line.
//!
//! The reporter is told about items (start, finish, a detail such as the model a case is on), never
//! about time steps: a background thread draws, so no numerical loop locks or allocates for it.

use std::io::IsTerminal;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Default time between two plain lines [s].
pub const DEFAULT_INTERVAL_S: f64 = 10.0;

/// The environment variable that overrides [`DEFAULT_INTERVAL_S`].
pub const INTERVAL_VAR: &str = "MCDEM_PROGRESS_INTERVAL";

/// The interval between plain lines from the value of [`INTERVAL_VAR`] (`None`: unset): a finite
/// number of seconds > 0, or an error naming the value.
pub fn parse_interval(value: Option<&str>) -> Result<f64, String> {
    let Some(v) = value else { return Ok(DEFAULT_INTERVAL_S) };
    match v.trim().parse::<f64>() {
        Ok(s) if s.is_finite() && s > 0.0 => Ok(s),
        _ => Err(format!("{INTERVAL_VAR}='{v}' is not a number of seconds > 0")),
    }
}

/// The interval from the environment; a bad value is ignored with a warning (progress must never
/// stop a long run before it starts).
fn interval_from_env() -> f64 {
    let v = std::env::var(INTERVAL_VAR).ok();
    parse_interval(v.as_deref()).unwrap_or_else(|e| {
        eprintln!("warning: {e}; using {DEFAULT_INTERVAL_S} s");
        DEFAULT_INTERVAL_S
    })
}

struct Running {
    name: String,
    since: Instant,
    expected: Option<f64>,
    /// (key, text) of what the item is on now, e.g. ("nu=0.45", "nu=0.45: hertz").
    details: Vec<(String, String)>,
    /// The part of the item done, where the item can tell (e.g. fit evaluations made of planned),
    /// and when and at which part it first told: its pace is measured from there, so that a setup
    /// phase before the counted work does not count.
    fraction: Option<(f64, Instant, f64)>,
}

#[derive(Default)]
struct State {
    total: usize,
    done: usize,
    /// Items counted done without being run here (e.g. taken from a journal): no time of theirs.
    skipped: usize,
    /// Wall time of the items finished here [s].
    done_secs: f64,
    running: Vec<Running>,
    /// Expected wall time of named items not started yet (e.g. from the previous report).
    expected: Vec<(String, f64)>,
    /// Most items seen running at once: the parallelism of the estimate.
    width: usize,
    stop: bool,
}

impl State {
    /// The time left [s]: the remaining part of every running item and the whole of every item not
    /// yet started (its expected time, else the mean of the items done here), spread over as many
    /// items as have run at once; and whether a running item has run longer than its estimate
    /// (the time left is then a lower bound). `None` before there is anything to go by.
    fn left(&self, now: Instant) -> Option<(f64, bool)> {
        let ran = self.done - self.skipped.min(self.done);
        let mean = (ran > 0).then(|| self.done_secs / ran as f64);
        let mut work = 0.0;
        let mut over = false;
        for r in &self.running {
            let t = now.duration_since(r.since).as_secs_f64();
            // The item's own pace beats the mean of other items (they may differ).
            let from_pace = r
                .fraction
                .filter(|(f, _, f1)| f > f1)
                .map(|(f, t1, f1)| t + (1.0 - f).max(0.0) * now.duration_since(t1).as_secs_f64() / (f - f1));
            let e = match r.expected.or(from_pace) {
                Some(e) => {
                    over |= t > e;
                    e
                }
                // Without its own estimate an item borrows the mean of the items done; once it has
                // run longer than that mean, the mean says nothing about it (a long case after
                // short ones): the time left is not known.
                None => mean.filter(|&m| t <= m)?,
            };
            work += (e - t).max(0.0);
        }
        let waiting = self.total.saturating_sub(self.done + self.running.len());
        if waiting > 0 {
            // Unstarted named items with a known time count with it; the rest at the mean.
            let known = &self.expected[..self.expected.len().min(waiting)];
            work += known.iter().map(|e| e.1).sum::<f64>();
            let rest = waiting - known.len();
            if rest > 0 {
                work += rest as f64 * mean?;
            }
        }
        Some((work / self.width.max(1) as f64, over))
    }

    /// The running items with their details, e.g. `uniaxial (nu=0.3: hertz; nu=0.5: start state)`.
    fn running_names(&self) -> String {
        let names: Vec<String> = self
            .running
            .iter()
            .map(|r| {
                if r.details.is_empty() {
                    r.name.clone()
                } else {
                    let d: Vec<&str> = r.details.iter().map(|d| d.1.as_str()).collect();
                    format!("{} ({})", r.name, d.join("; "))
                }
            })
            .collect();
        names.join(", ")
    }

    /// `running X, 12 s elapsed, about 30 s left` (the part after the count).
    fn message(&self, elapsed: f64, now: Instant) -> String {
        let mut m = String::new();
        if !self.running.is_empty() {
            m += &format!("running {}, ", self.running_names());
        }
        m += &format!("{elapsed:.0} s elapsed");
        match self.left(now) {
            Some((l, false)) => m += &format!(", about {l:.0} s left"),
            Some((l, true)) => m += &format!(", at least {l:.0} s left (longer than estimated)"),
            None => m += ", time left not known yet",
        }
        m
    }
}

struct Shared {
    label: String,
    state: Mutex<State>,
    wake: Condvar,
    bar: Option<indicatif::ProgressBar>,
    t0: Instant,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic elsewhere must not take the progress display down with it.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The progress reporter of one command; reports from a background thread until dropped.
pub struct Progress {
    shared: Arc<Shared>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Progress {
    /// A reporter for `total` items, its lines and bar prefixed with `label` (the command).
    pub fn new(label: &str, total: usize) -> Self {
        let terminal = std::io::stderr().is_terminal();
        Self::with(label, total, terminal, interval_from_env())
    }

    fn with(label: &str, total: usize, terminal: bool, interval: f64) -> Self {
        let bar = terminal.then(|| {
            let b = indicatif::ProgressBar::new(total as u64);
            b.set_style(
                indicatif::ProgressStyle::with_template("{prefix}: {bar:30} {pos}/{len} {wide_msg}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            b.set_prefix(label.to_string());
            b
        });
        let shared = Arc::new(Shared {
            label: label.to_string(),
            state: Mutex::new(State { total, ..Default::default() }),
            wake: Condvar::new(),
            bar,
            t0: Instant::now(),
        });
        let s = shared.clone();
        let thread = std::thread::spawn(move || draw(&s, interval));
        Progress { shared, thread: Some(thread) }
    }

    /// Sets the expected wall time [s] of item `name` (e.g. from a previous run).
    pub fn expect(&self, name: &str, secs: f64) {
        if secs.is_finite() && secs >= 0.0 {
            self.shared.lock().expected.push((name.to_string(), secs));
        }
    }

    /// Item `name` starts.
    pub fn start(&self, name: &str) {
        let mut s = self.shared.lock();
        // Taken out of the list: the list holds the items not started yet.
        let expected = s.expected.iter().position(|e| e.0 == name).map(|i| s.expected.remove(i).1);
        s.running.push(Running {
            name: name.to_string(),
            since: Instant::now(),
            expected,
            details: Vec::new(),
            fraction: None,
        });
        s.width = s.width.max(s.running.len());
    }

    /// Item `name` is on `text` now for its part `key` (parts of an item may run in parallel, e.g.
    /// one Poisson ratio each); `text` replaces the part's previous one.
    pub fn detail(&self, name: &str, key: &str, text: String) {
        let mut s = self.shared.lock();
        if let Some(r) = s.running.iter_mut().find(|r| r.name == name) {
            match r.details.iter_mut().find(|d| d.0 == key) {
                Some(d) => d.1 = text,
                None => r.details.push((key.to_string(), text)),
            }
        }
    }

    /// Item `name` is `fraction` (0..1) done: when no expected time is known, its time left is
    /// estimated from its pace since its first such report.
    pub fn fraction(&self, name: &str, fraction: f64) {
        let mut s = self.shared.lock();
        if let Some(r) = s.running.iter_mut().find(|r| r.name == name) {
            if fraction.is_finite() {
                let (t1, f1) = r.fraction.map_or((Instant::now(), fraction), |(_, t1, f1)| (t1, f1));
                r.fraction = Some((fraction, t1, f1));
            }
        }
    }

    /// Part `key` of item `name` is finished (its detail is no longer shown).
    pub fn detail_done(&self, name: &str, key: &str) {
        let mut s = self.shared.lock();
        if let Some(r) = s.running.iter_mut().find(|r| r.name == name) {
            r.details.retain(|d| d.0 != key);
        }
    }

    /// Item `name` is finished (whether it succeeded or not).
    pub fn finish(&self, name: &str) {
        let mut s = self.shared.lock();
        if let Some(i) = s.running.iter().position(|r| r.name == name) {
            let r = s.running.remove(i);
            s.done_secs += r.since.elapsed().as_secs_f64();
        }
        s.done += 1;
        if let Some(b) = &self.shared.bar {
            b.set_position(s.done as u64);
        }
    }

    /// `n` items count as done without running here (e.g. results taken from a journal).
    pub fn skip(&self, n: usize) {
        let mut s = self.shared.lock();
        s.done += n;
        s.skipped += n;
        if let Some(b) = &self.shared.bar {
            b.set_position(s.done as u64);
        }
    }

    /// Prints `line` on standard error above the bar (or plainly without one).
    pub fn println(&self, line: &str) {
        self.suspend(|| eprintln!("{line}"));
    }

    /// Runs `f` (which may write to standard error) with the bar hidden.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        match &self.shared.bar {
            Some(b) => b.suspend(f),
            None => f(),
        }
    }
}

/// The reporting thread: on a terminal refreshes the bar 5 times a second; otherwise prints one
/// line per `interval` seconds, the first one `interval` after the start.
fn draw(s: &Shared, interval: f64) {
    let tick = Duration::from_secs_f64(if s.bar.is_some() { 0.2 } else { interval.min(0.25) });
    let mut next_line = interval;
    let mut state = s.lock();
    while !state.stop {
        state = s.wake.wait_timeout(state, tick).map(|r| r.0).unwrap_or_else(|e| e.into_inner().0);
        if state.stop {
            break;
        }
        let now = Instant::now();
        let elapsed = now.duration_since(s.t0).as_secs_f64();
        match &s.bar {
            Some(b) => b.set_message(state.message(elapsed, now)),
            None if elapsed >= next_line => {
                eprintln!(
                    "{}: {}/{} done, {}",
                    s.label,
                    state.done,
                    state.total,
                    state.message(elapsed, now)
                );
                // Never more than one line per interval, even after a stall.
                next_line = elapsed + interval;
            }
            None => {}
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.shared.lock().stop = true;
        self.shared.wake.notify_all();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        if let Some(b) = &self.shared.bar {
            b.finish_and_clear();
        }
    }
}

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Progress").field("label", &self.shared.label).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_values() {
        assert_eq!(parse_interval(None), Ok(DEFAULT_INTERVAL_S));
        assert_eq!(parse_interval(Some(" 0.3 ")), Ok(0.3));
        for bad in ["abc", "0", "-1", "nan", "inf", ""] {
            let e = parse_interval(Some(bad)).unwrap_err();
            assert!(e.contains(INTERVAL_VAR) && e.contains(bad), "{e}");
        }
    }

    #[test]
    fn estimate_from_done_items_and_expected_times() {
        let t0 = Instant::now();
        let mut s = State { total: 4, ..Default::default() };
        assert_eq!(s.left(t0), None);
        // Two items done in 10 s each, one running for 0 s, one waiting: 10 + 10 left, one at a time.
        s.done = 2;
        s.done_secs = 20.0;
        s.width = 1;
        s.running.push(Running {
            name: "c".into(),
            since: t0,
            expected: None,
            details: vec![],
            fraction: None,
        });
        assert_eq!(s.left(t0), Some((20.0, false)));
        // The waiting item's previous time replaces the mean.
        s.expected.push(("d".into(), 100.0));
        assert_eq!(s.left(t0), Some((110.0, false)));
        // A running item past the mean of the others, with no estimate of its own: not known.
        let late = t0 + Duration::from_secs(30);
        assert_eq!(s.left(late), None);
        assert!(s.message(33.0, late).ends_with("time left not known yet"));
        // A running item past its own expected time: the rest is a lower bound.
        s.running[0].expected = Some(20.0);
        assert_eq!(s.left(late), Some((100.0, true)));
        assert!(s.message(33.0, late).ends_with("at least 100 s left (longer than estimated)"));
        s.running[0].details.push(("nu=0.5".into(), "nu=0.5: hertz".into()));
        assert_eq!(s.running_names(), "c (nu=0.5: hertz)");
        assert!(s.message(3.0, t0).starts_with("running c (nu=0.5: hertz), 3 s elapsed, about 120 s left"));
        // The item's own pace: from 0.25 at 10 s to 0.5 at 30 s, so 40 s to go.
        s.running[0].expected = None;
        s.running[0].fraction = Some((0.5, t0 + Duration::from_secs(10), 0.25));
        assert_eq!(s.left(late), Some((140.0, false)));
    }
}

//! The serial-vs-threads timing probe of [`super::PairThreads::Auto`]: when to time steps each way,
//! which of them to time, and when to look again.
//!
//! Threads pay only when the cores are free, so from time to time a window of whole steps is run
//! with and without them and the faster is kept (results are bit-identical either way). The two
//! modes alternate in slices, and each mode's time is the median of its slices, so that a passing
//! disturbance (another process, buffers allocated at their first use) in one slice does not
//! decide: on the hydrogel deck one threaded slice of a window at 191 µs per step against 61–67
//! in the others had made the window choose one core. The first steps of a slice are not timed:
//! after a switch the particles' state sits in the other core's cache (and a parked helper must
//! wake), which a run that keeps one mode does not pay.
//!
//! A choice of threads stands for [`PERIOD`] steps. A choice of one core is looked at again
//! sooner, after [`RETRY`] steps and then twice as long each time up to [`PERIOD`]: the windows
//! at the start of a run are the ones disturbances push towards one core. On the 514-particle
//! hydrogel deck, in two of three logged runs, the threaded slices of the very first window ran
//! at 230–310 µs per step against 45–60 µs in every later window (a transient of the first 50–60
//! steps after the team starts), so the first window chose one core and the run kept it for
//! 5 000 steps, 17 % of a 30 000-step stroke.

/// Steps between two windows after a choice of threads (and the longest wait after one core).
pub const PERIOD: u64 = 5000;
/// Steps to the next window after a first choice of one core.
pub const RETRY: u64 = 1000;
/// Steps timed in each mode per window (slices of [`SLICE`] steps alternating, serial first).
pub const WINDOW: u64 = 50;
pub const SLICE: u64 = 10;
/// Slices per mode in a window.
const SLICES: usize = (WINDOW / SLICE) as usize;
/// Steps at the start of each slice that are not timed.
pub const SETTLE: u64 = 2;

/// Where the probe stands: the window that is running or comes next, and the time of each of its
/// slices so far.
#[derive(Debug, Clone)]
pub struct ThreadProbe {
    /// First step of the current or next window.
    start: u64,
    /// Per mode (one core, threads), the time of each slice [ns].
    slice_ns: [[u64; SLICES]; 2],
    /// Steps from this window to the next if it chooses one core.
    retry: u64,
}

impl Default for ThreadProbe {
    fn default() -> Self {
        ThreadProbe { start: 0, slice_ns: [[0; SLICES]; 2], retry: RETRY }
    }
}

/// What the probe asks of one step inside a window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProbeStep {
    /// Run this step on the threads.
    pub threads: bool,
    /// Time it and pass the time to [`ThreadProbe::record`].
    pub timed: bool,
}

impl ThreadProbe {
    /// The mode of `step` if it falls in a window; `None` keeps the last choice. A run that starts
    /// past a window (a deck continued at a later step) opens one at once.
    pub fn plan(&mut self, step: u64) -> Option<ProbeStep> {
        let mut phase = step.checked_sub(self.start)?;
        if phase >= 2 * WINDOW {
            self.start = step;
            self.slice_ns = [[0; SLICES]; 2];
            phase = 0;
        }
        Some(ProbeStep { threads: (phase / SLICE) % 2 == 1, timed: phase % SLICE >= SETTLE })
    }

    /// Adds the time of a timed step (of the window [`ThreadProbe::plan`] placed it in, which
    /// also says its mode: odd slices run on the threads); at the window's last step returns the
    /// choice (threads when their median slice was faster) and schedules the next window.
    pub fn record(&mut self, step: u64, ns: u64) -> Option<bool> {
        let slice = ((step - self.start) / SLICE) as usize;
        self.slice_ns[slice % 2][slice / 2] += ns;
        if step != self.start + 2 * WINDOW - 1 {
            return None;
        }
        let median = |mut s: [u64; SLICES]| {
            s.sort_unstable();
            s[SLICES / 2]
        };
        let choice = median(self.slice_ns[1]) < median(self.slice_ns[0]);
        let wait = if choice {
            self.retry = RETRY;
            PERIOD
        } else {
            let w = self.retry;
            self.retry = (2 * w).min(PERIOD);
            w
        };
        self.start += wait;
        self.slice_ns = [[0; SLICES]; 2];
        Some(choice)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steps `first`.. through the probe with the given time per step in each mode; returns the
    /// steps at which windows closed, with their choice.
    fn drive(steps: u64, first: u64, serial_ns: u64, threads_ns: impl Fn(u64) -> u64) -> Vec<(u64, bool)> {
        let mut p = ThreadProbe::default();
        let mut out = Vec::new();
        for step in first..first + steps {
            if let Some(s) = p.plan(step) {
                if s.timed {
                    let ns = if s.threads { threads_ns(step) } else { serial_ns };
                    if let Some(c) = p.record(step, ns) {
                        out.push((step, c));
                    }
                }
            }
        }
        out
    }

    #[test]
    fn slices_alternate_and_settle_steps_are_not_timed() {
        let mut p = ThreadProbe::default();
        let plans: Vec<_> = (1..2 * WINDOW).map(|s| p.plan(s).expect("in the first window")).collect();
        assert!(!plans[0].threads && plans[0].timed == (1 >= SETTLE));
        assert!(plans[SLICE as usize - 1].threads && !plans[SLICE as usize - 1].timed);
        assert!(plans[(SLICE + SETTLE) as usize - 1].threads && plans[(SLICE + SETTLE) as usize - 1].timed);
        let timed_threads = plans.iter().filter(|s| s.threads && s.timed).count() as u64;
        assert_eq!(timed_threads, (WINDOW / SLICE) * (SLICE - SETTLE));
    }

    #[test]
    fn threads_stand_for_a_period() {
        let closed = drive(3 * PERIOD, 1, 100, |_| 60);
        let at: Vec<u64> = closed.iter().map(|c| c.0).collect();
        assert_eq!(at, [2 * WINDOW - 1, PERIOD + 2 * WINDOW - 1, 2 * PERIOD + 2 * WINDOW - 1]);
        assert!(closed.iter().all(|c| c.1));
    }

    #[test]
    fn one_core_is_looked_at_again_sooner_and_less_often_each_time() {
        // Threads slower throughout: windows at 0, 1000, 3000, 7000, then every 5000.
        let closed = drive(20_000, 1, 60, |_| 100);
        let starts: Vec<u64> = closed.iter().map(|c| c.0 + 1 - 2 * WINDOW).collect();
        assert_eq!(starts, [0, RETRY, 3 * RETRY, 7 * RETRY, 7 * RETRY + PERIOD, 7 * RETRY + 2 * PERIOD]);
        assert!(closed.iter().all(|c| !c.1));
    }

    #[test]
    fn a_slow_first_window_costs_one_retry_not_a_period() {
        // The threaded steps of the first window are disturbed (start-up), later ones are not.
        let closed = drive(2 * PERIOD, 1, 60, |step| if step < 2 * WINDOW { 250 } else { 50 });
        assert_eq!(closed[0], (2 * WINDOW - 1, false));
        assert_eq!(closed[1], (RETRY + 2 * WINDOW - 1, true));
        // After threads won, the retry interval starts afresh and the next window is a period on.
        assert_eq!(closed[2].0, RETRY + PERIOD + 2 * WINDOW - 1);
    }

    #[test]
    fn one_disturbed_slice_does_not_decide() {
        // Threads faster except in one slice three times as slow as one core (a passing
        // disturbance): the summed time would choose one core, the median chooses threads.
        let disturbed = |step: u64| if (30..40).contains(&step) { 300 } else { 50 };
        assert_eq!(drive(2 * WINDOW, 1, 60, disturbed), [(2 * WINDOW - 1, true)]);
        // Slower in most slices: one core.
        let slow = |step: u64| if step < 70 { 80 } else { 50 };
        assert_eq!(drive(2 * WINDOW, 1, 60, slow), [(2 * WINDOW - 1, false)]);
    }

    #[test]
    fn a_run_starting_at_a_later_step_probes_at_once() {
        let closed = drive(2 * WINDOW, 12_345, 100, |_| 60);
        assert_eq!(closed, [(12_345 + 2 * WINDOW - 1, true)]);
    }
}

//! A fork-join team for short, frequent parallel passes (the DEM's per-step force passes, the
//! nonlocal solver's FIRE force evaluation): the calling thread and `size − 1` helper threads that
//! spin between jobs instead of going to sleep.
//!
//! Why not rayon here: a step of a few hundred particles takes about 100 µs and has two or three
//! threaded passes with serial work in between (integration, neighbour check, wall scan). Between
//! two passes an idle rayon worker yields and then sleeps on a futex, and the next pass has to
//! wake it: on a virtual machine that is an inter-processor interrupt and a reschedule of the
//! sleeping vCPU each time. A profile of the 514-particle hydrogel deck forced onto two threads
//! put 17 % of the samples in the kernel's wake-up path (`_raw_spin_unlock_irqrestore`) and 12 %
//! in a job that spun to keep the worker awake, and two threads were slower than one. The team's
//! helpers spin on an epoch counter while a run is stepping, so handing them a pass costs a
//! cache-line transfer; after [`SPIN_LIMIT`] without work (output, a serial stretch, the end of a
//! run) they park, and the next job unparks them.
//!
//! Every member runs the same closure with its own index; the caller splits the work by that
//! index (disjoint ranges, see [`SplitMut`]), so what each member computes, and the order in which
//! results are combined afterwards, do not depend on timing.

use std::marker::PhantomData;
use std::ops::Range;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a helper spins without work before it parks: far longer than the serial part of a
/// step (tens of microseconds), far shorter than anything a user would notice as a busy core.
pub const SPIN_LIMIT: Duration = Duration::from_millis(2);

/// The job of the current epoch, type-erased: a borrowed closure whose lifetime [`Team::run`]
/// guarantees by not returning before every member is done with it.
type Job = *const (dyn Fn(usize) + Sync);

struct Shared {
    /// Bumped (SeqCst) once per job; helpers run the job when it changes.
    epoch: AtomicU64,
    /// The job of the current epoch (written before the epoch is bumped).
    job: Mutex<Option<SendJob>>,
    /// Helpers still working on the current job.
    pending: AtomicUsize,
    /// Per helper: parked or about to park (SeqCst against `epoch`, so a bump is never missed).
    sleeping: Vec<AtomicBool>,
    /// A helper's job panicked (the panic is re-raised on the caller).
    panicked: AtomicBool,
    stop: AtomicBool,
}

#[derive(Clone, Copy)]
struct SendJob(Job);
// SAFETY: the closure behind the pointer is `Sync`, and it outlives its use (`Team::run`).
unsafe impl Send for SendJob {}

/// The stepping thread (member 0) and its helpers (members 1..size).
pub struct Team {
    shared: Arc<Shared>,
    helpers: Vec<JoinHandle<()>>,
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Team({} members)", self.size())
    }
}

impl Team {
    /// A team of `size` members (at least 1): `size − 1` helper threads are started.
    pub fn new(size: usize) -> Team {
        let size = size.max(1);
        let shared = Arc::new(Shared {
            epoch: AtomicU64::new(0),
            job: Mutex::new(None),
            pending: AtomicUsize::new(0),
            sleeping: (1..size).map(|_| AtomicBool::new(false)).collect(),
            panicked: AtomicBool::new(false),
            stop: AtomicBool::new(false),
        });
        let helpers = (1..size)
            .map(|k| {
                let s = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("mcdem-team-{k}"))
                    .spawn(move || helper(&s, k))
                    .expect("cannot start a thread of the team")
            })
            .collect();
        Team { shared, helpers }
    }

    pub fn size(&self) -> usize {
        self.helpers.len() + 1
    }

    /// Runs `f(k)` for every member k (0 on the calling thread) and returns when all are done.
    /// Of several failures the lowest member's error is returned, as a serial loop over the
    /// members would report first; a panic in any member is re-raised here after all finished.
    pub fn run<E: Send>(&self, f: impl Fn(usize) -> Result<(), E> + Sync) -> Result<(), E> {
        let first_error: Mutex<Option<(usize, E)>> = Mutex::new(None);
        let job = |k: usize| {
            if let Err(e) = f(k) {
                let mut slot = first_error.lock().unwrap_or_else(|p| p.into_inner());
                if slot.as_ref().is_none_or(|(j, _)| k < *j) {
                    *slot = Some((k, e));
                }
            }
        };
        if self.helpers.is_empty() {
            job(0);
        } else {
            let s = &*self.shared;
            let dyn_job: &(dyn Fn(usize) + Sync) = &job;
            // SAFETY: the lifetime is erased only for the helpers' copy of the pointer; this
            // function does not return (nor unwind) before `pending` is 0, i.e. before every
            // helper has finished calling it.
            let erased: Job = unsafe { std::mem::transmute::<&(dyn Fn(usize) + Sync), Job>(dyn_job) };
            *s.job.lock().unwrap_or_else(|p| p.into_inner()) = Some(SendJob(erased));
            s.pending.store(self.helpers.len(), Ordering::SeqCst);
            s.epoch.fetch_add(1, Ordering::SeqCst);
            for (h, sleeping) in self.helpers.iter().zip(&s.sleeping) {
                if sleeping.swap(false, Ordering::SeqCst) {
                    h.thread().unpark();
                }
            }
            let mine = catch_unwind(AssertUnwindSafe(|| job(0)));
            let mut spins = 0u32;
            while s.pending.load(Ordering::Acquire) != 0 {
                spins = spins.wrapping_add(1);
                if spins % 1024 == 0 {
                    // A helper was descheduled: let it have the core.
                    std::thread::yield_now();
                } else {
                    std::hint::spin_loop();
                }
            }
            if let Err(p) = mine {
                resume_unwind(p);
            }
            if s.panicked.swap(false, Ordering::SeqCst) {
                panic!("a thread of the team panicked");
            }
        }
        match first_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
            Some((_, e)) => Err(e),
            None => Ok(()),
        }
    }

    /// [`Team::run`] with every member's equal share of `0..len` ([`share`]) handed to it: the
    /// shape of most passes (particles, pairs, candidates), which split a list into consecutive
    /// ranges. The ranges are disjoint, which is what taking them from a [`SplitMut`] requires.
    pub fn run_shares<E: Send>(
        &self,
        len: usize,
        f: impl Fn(usize, Range<usize>) -> Result<(), E> + Sync,
    ) -> Result<(), E> {
        let size = self.size();
        self.run(|k| f(k, share(len, size, k)))
    }

    /// [`Team::run_shares`] for a pass that cannot fail.
    pub fn for_shares(&self, len: usize, f: impl Fn(usize, Range<usize>) + Sync) {
        let Ok(()) = self.run_shares(len, |k, r| {
            f(k, r);
            Ok::<(), std::convert::Infallible>(())
        });
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        let s = &*self.shared;
        s.stop.store(true, Ordering::SeqCst);
        s.epoch.fetch_add(1, Ordering::SeqCst);
        for h in &self.helpers {
            h.thread().unpark();
        }
        for h in self.helpers.drain(..) {
            let _ = h.join();
        }
    }
}

fn helper(s: &Shared, k: usize) {
    let sleeping = &s.sleeping[k - 1];
    // The epoch the team was created with, not a fresh load: a job may be posted before this
    // thread first runs.
    let mut seen = 0;
    loop {
        let mut idle_since = Instant::now();
        let mut spins = 0u32;
        let epoch = loop {
            let e = s.epoch.load(Ordering::Acquire);
            if e != seen {
                break e;
            }
            spins = spins.wrapping_add(1);
            if spins % 256 != 0 {
                std::hint::spin_loop();
                continue;
            }
            if idle_since.elapsed() < SPIN_LIMIT {
                // With more threads than free cores, let whoever waits for the core have it.
                std::thread::yield_now();
                continue;
            }
            // Park; the SeqCst pair (sleeping, then epoch here; epoch, then sleeping in `run`)
            // guarantees that a job posted meanwhile either is seen now or unparks us.
            sleeping.store(true, Ordering::SeqCst);
            if s.epoch.load(Ordering::SeqCst) == seen {
                std::thread::park();
            }
            sleeping.store(false, Ordering::SeqCst);
            idle_since = Instant::now();
        };
        seen = epoch;
        if s.stop.load(Ordering::SeqCst) {
            return;
        }
        let job = s.job.lock().unwrap_or_else(|p| p.into_inner()).expect("a job is posted with its epoch");
        // SAFETY: `Team::run` keeps the closure alive until `pending` reaches 0 below.
        let f = unsafe { &*job.0 };
        if catch_unwind(AssertUnwindSafe(|| f(k))).is_err() {
            s.panicked.store(true, Ordering::SeqCst);
        }
        s.pending.fetch_sub(1, Ordering::Release);
    }
}

/// A mutable slice whose disjoint ranges are handed to the members of a team (each member takes
/// its own range by index; see the SAFETY notes where ranges are taken).
pub struct SplitMut<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a mut [T]>,
}

// SAFETY: the members take disjoint ranges (the caller's obligation in `range`), so sharing the
// view is sharing `&mut` to separate parts, which `T: Send` allows.
unsafe impl<T: Send> Sync for SplitMut<'_, T> {}
unsafe impl<T: Send> Send for SplitMut<'_, T> {}

impl<'a, T> SplitMut<'a, T> {
    pub fn new(s: &'a mut [T]) -> Self {
        SplitMut { ptr: s.as_mut_ptr(), len: s.len(), _borrow: PhantomData }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The elements `r` of the slice.
    ///
    /// # Safety
    /// No two live ranges taken from one `SplitMut` may overlap.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn range(&self, r: Range<usize>) -> &'a mut [T] {
        assert!(r.start <= r.end && r.end <= self.len, "range {r:?} outside a slice of {}", self.len);
        // SAFETY: in bounds (checked); disjointness is the caller's obligation.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(r.start), r.end - r.start) }
    }
}

/// Member k's share of `0..len` split into `members` consecutive ranges of equal length (the
/// last ones shorter when it does not divide).
pub fn share(len: usize, members: usize, k: usize) -> Range<usize> {
    let size = len.div_ceil(members.max(1));
    (k * size).min(len)..((k + 1) * size).min(len)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_member_runs_once_per_job_and_results_land_in_its_range() {
        for size in [1, 2, 3] {
            let team = Team::new(size);
            let mut data = vec![0u64; 1000];
            for round in 1..=200u64 {
                let view = SplitMut::new(&mut data);
                team.run(|k| {
                    // SAFETY: `share` gives disjoint ranges for distinct k.
                    let part = unsafe { view.range(share(view.len(), size, k)) };
                    part.iter_mut().for_each(|v| *v += round);
                    Ok::<(), ()>(())
                })
                .unwrap();
            }
            assert!(data.iter().all(|&v| v == 200 * 201 / 2), "size {size}");
        }
    }

    /// `for_shares` and `run_shares` hand member k exactly `share(len, size, k)`: together the
    /// ranges cover 0..len once, also when len is not a multiple of the size (or is smaller).
    #[test]
    fn shares_cover_the_list_once() {
        for size in [1, 2, 3] {
            let team = Team::new(size);
            for len in [0, 1, 2, 7, 1000] {
                let mut hits = vec![0u32; len];
                let view = SplitMut::new(&mut hits);
                team.for_shares(len, |k, r| {
                    assert_eq!(r, share(len, size, k));
                    // SAFETY: the shares are disjoint.
                    unsafe { view.range(r) }.iter_mut().for_each(|h| *h += 1);
                });
                assert!(hits.iter().all(|&h| h == 1), "size {size}, len {len}");
                let r = team.run_shares(len, |k, r| if r.is_empty() { Ok(()) } else { Err(k) });
                assert_eq!(r, if len == 0 { Ok(()) } else { Err(0) });
            }
        }
    }

    #[test]
    fn the_lowest_failing_member_is_reported() {
        let team = Team::new(3);
        let r = team.run(|k| if k >= 1 { Err(k) } else { Ok(()) });
        assert_eq!(r, Err(1));
        assert_eq!(team.run(|_| Ok::<(), usize>(())), Ok(()));
    }

    #[test]
    fn parked_helpers_wake_for_the_next_job() {
        let team = Team::new(2);
        let hits = AtomicUsize::new(0);
        for _ in 0..3 {
            std::thread::sleep(SPIN_LIMIT * 3);
            team.run(|_| {
                hits.fetch_add(1, Ordering::SeqCst);
                Ok::<(), ()>(())
            })
            .unwrap();
        }
        assert_eq!(hits.load(Ordering::SeqCst), 6);
    }

    #[test]
    fn a_panicking_helper_is_reported_on_the_caller() {
        let team = Team::new(2);
        let r = catch_unwind(AssertUnwindSafe(|| {
            let _ = team.run(|k| {
                assert!(k == 0, "helper fails");
                Ok::<(), ()>(())
            });
        }));
        assert!(r.is_err());
        // The team still works afterwards.
        assert_eq!(team.run(|_| Ok::<(), ()>(())), Ok(()));
    }
}

//! [`SpinHelper`]: one extra thread that waits hot for the short parallel
//! sections of an iteration.
//!
//! A 2D iteration has parallel sections of a few hundred microseconds (the
//! statistics of the cells that moved, for one) between about a millisecond
//! of sequential mesh work. Rayon's workers fall asleep in such gaps, and
//! waking one cost 100–150 µs on the 2-core VM this was measured on: more
//! than the section saves. The helper instead spins (yielding the core to
//! any other runnable thread) for [`SPIN`] after each job, so a
//! [`join`](SpinHelper::join) costs about a cache-line round trip; then it
//! parks, so a finished or idle run does not keep a core busy.
//!
//! Large batches (3D, first integrations) still go to rayon, which scales
//! past two threads.
//!
//! This is the only `unsafe` code of dsc-seg (whose crate forbids it): the
//! job a helper runs borrows from the caller's stack frame, and
//! [`join`](SpinHelper::join) does not return, nor unwind, before that job
//! has finished.
#![warn(missing_docs)]

use std::cell::Cell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// How long the helper keeps spinning after its last job before it parks.
pub const SPIN: Duration = Duration::from_millis(5);

/// A second thread for [`join`](Self::join), or none (then `join` runs both
/// halves on the caller's thread).
///
/// `Send` but not `Sync`: one owner posts one job at a time.
pub struct SpinHelper {
    worker: Option<Worker>,
    /// Whether a job is in flight: a `join` inside a `join`'s first closure
    /// then runs both of its closures on the caller (not `Sync`: one caller).
    busy: Cell<bool>,
}

struct Worker {
    shared: Arc<Shared>,
    thread: JoinHandle<()>,
}

/// What the owner and the helper thread share.
struct Shared {
    /// The job posted last (slot read by the helper once `posted` changes).
    job: Mutex<Option<Job>>,
    /// Sequence number of the last posted job.
    posted: AtomicU64,
    /// Sequence number of the last finished job.
    finished: AtomicU64,
    /// Whether the helper is parked (or about to park).
    sleeping: AtomicBool,
    stop: AtomicBool,
}

/// A type-erased pointer to a [`Packet`] on the poster's stack.
struct Job {
    packet: *mut (),
    run: unsafe fn(*mut ()),
}

// SAFETY: a `Job` points to a `Packet<B, R>` with `B: Send` and `R: Send`,
// which `join` keeps alive (and does not touch) until the helper has
// finished with it.
unsafe impl Send for Job {}

/// The closure the helper runs and the slot for its outcome.
struct Packet<B, R> {
    work: Option<B>,
    outcome: Option<thread::Result<R>>,
}

/// Runs the packet's closure, catching a panic so that it reaches the caller.
///
/// # Safety
/// `packet` must point to a live `Packet<B, R>` that nothing else accesses.
unsafe fn run_packet<B: FnOnce() -> R, R>(packet: *mut ()) {
    // SAFETY: the caller's contract.
    let packet = unsafe { &mut *(packet as *mut Packet<B, R>) };
    if let Some(work) = packet.work.take() {
        packet.outcome = Some(catch_unwind(AssertUnwindSafe(work)));
    }
}

impl SpinHelper {
    /// A helper thread if this machine has a second core (and the thread
    /// can be started); otherwise no thread.
    pub fn new() -> Self {
        let cores = thread::available_parallelism().map_or(1, |n| n.get());
        if cores < 2 {
            return Self::none();
        }
        Self::with_thread().unwrap_or_else(|_| Self::none())
    }

    /// No helper thread: `join` runs both closures in turn.
    pub fn none() -> Self {
        SpinHelper {
            worker: None,
            busy: Cell::new(false),
        }
    }

    /// A helper thread whatever the number of cores (e.g. for tests of the
    /// two-thread path); an error if the thread cannot be started.
    pub fn with_thread() -> std::io::Result<Self> {
        let shared = Arc::new(Shared {
            job: Mutex::new(None),
            posted: AtomicU64::new(0),
            finished: AtomicU64::new(0),
            sleeping: AtomicBool::new(false),
            stop: AtomicBool::new(false),
        });
        let theirs = Arc::clone(&shared);
        let thread = thread::Builder::new()
            .name("dsc-seg-helper".into())
            .spawn(move || work_loop(&theirs))?;
        Ok(SpinHelper {
            worker: Some(Worker { shared, thread }),
            busy: Cell::new(false),
        })
    }

    /// Whether there is a helper thread.
    pub fn is_threaded(&self) -> bool {
        self.worker.is_some()
    }

    /// Runs `a` on this thread and `b` on the helper, at the same time, and
    /// returns both results (without a helper: `a` then `b`). A panic in
    /// either is resumed here once both have finished.
    ///
    /// The caller waits for `b` without doing other work: `b` must not
    /// wait for a thread pool the caller belongs to (e.g. rayon work posted
    /// from `b` while the caller is one of rayon's workers, all of which
    /// may be waiting so).
    pub fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB + Send,
        RB: Send,
    {
        let Some(worker) = self.worker.as_ref().filter(|_| !self.busy.get()) else {
            let ra = a();
            return (ra, b());
        };
        self.busy.set(true);
        let mut packet = Packet {
            work: Some(b),
            outcome: None,
        };
        let seq = worker.post(Job {
            packet: &mut packet as *mut Packet<B, RB> as *mut (),
            run: run_packet::<B, RB>,
        });
        // Waits for the helper even if `a` unwinds: `packet` lives on this
        // stack frame.
        let wait = WaitFor {
            shared: &worker.shared,
            seq,
            busy: &self.busy,
        };
        let ra = a();
        drop(wait);
        match packet.outcome.take() {
            Some(Ok(rb)) => (ra, rb),
            Some(Err(panic)) => resume_unwind(panic),
            None => unreachable!("the helper ran the posted job"),
        }
    }
}

impl Default for SpinHelper {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for SpinHelper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpinHelper")
            .field("threaded", &self.is_threaded())
            .finish()
    }
}

impl Worker {
    /// Publishes `job` and wakes the helper if it parked; returns the job's
    /// sequence number.
    fn post(&self, job: Job) -> u64 {
        let shared = &self.shared;
        *shared.job.lock().unwrap_or_else(PoisonError::into_inner) = Some(job);
        let seq = shared.posted.load(Ordering::Relaxed) + 1;
        shared.posted.store(seq, Ordering::SeqCst);
        if shared.sleeping.load(Ordering::SeqCst) {
            self.thread.thread().unpark();
        }
        seq
    }
}

impl Drop for SpinHelper {
    fn drop(&mut self) {
        if let Some(worker) = self.worker.take() {
            worker.shared.stop.store(true, Ordering::SeqCst);
            worker.thread.thread().unpark();
            let _ = worker.thread.join();
        }
    }
}

/// Blocks, on drop, until the helper has finished job `seq`; then frees
/// the helper for the next `join`.
struct WaitFor<'a> {
    shared: &'a Shared,
    seq: u64,
    busy: &'a Cell<bool>,
}

impl Drop for WaitFor<'_> {
    fn drop(&mut self) {
        // Yields now and then: should the helper share this core, it runs.
        while self.shared.finished.load(Ordering::Acquire) != self.seq {
            for _ in 0..64 {
                std::hint::spin_loop();
            }
            thread::yield_now();
        }
        self.busy.set(false);
    }
}

/// The helper thread: runs posted jobs; between them spins for [`SPIN`],
/// then parks until the next post (or the stop).
fn work_loop(shared: &Shared) {
    let mut seen = 0;
    let mut last_job = Instant::now();
    loop {
        if shared.stop.load(Ordering::Acquire) {
            return;
        }
        let posted = shared.posted.load(Ordering::Acquire);
        if posted != seen {
            seen = posted;
            let job = shared
                .job
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take();
            if let Some(job) = job {
                // SAFETY: `join` posted a live packet and waits for
                // `finished` before it touches or frees it.
                unsafe { (job.run)(job.packet) };
            }
            shared.finished.store(seen, Ordering::Release);
            last_job = Instant::now();
        } else if last_job.elapsed() < SPIN {
            // Yield: on a busy machine the core goes to whoever needs it.
            thread::yield_now();
        } else {
            shared.sleeping.store(true, Ordering::SeqCst);
            // Re-checked after announcing the sleep: a post that saw
            // `sleeping == false` is seen here (both are SeqCst).
            if shared.posted.load(Ordering::SeqCst) == seen && !shared.stop.load(Ordering::SeqCst) {
                thread::park();
            }
            shared.sleeping.store(false, Ordering::SeqCst);
            last_job = Instant::now();
        }
    }
}

/// A panic payload's message, for tests.
#[cfg(test)]
fn panic_message(p: &(dyn std::any::Any + Send)) -> &str {
    p.downcast_ref::<&str>().copied().unwrap_or("")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn join_returns_both_results_with_and_without_a_thread() {
        for helper in [SpinHelper::with_thread().unwrap(), SpinHelper::none()] {
            let data: Vec<u64> = (0..10_000).collect();
            let (lo, hi) = data.split_at(5_000);
            for round in 0..200 {
                let (a, b) = helper.join(|| lo.iter().sum::<u64>(), || hi.iter().sum::<u64>());
                assert_eq!(a + b, data.iter().sum::<u64>(), "round {round}");
            }
        }
    }

    #[test]
    fn the_helper_writes_through_borrowed_slices() {
        let helper = SpinHelper::with_thread().unwrap();
        let mut out = vec![0u32; 1000];
        let (lo, hi) = out.split_at_mut(500);
        helper.join(
            || lo.iter_mut().for_each(|x| *x = 1),
            || hi.iter_mut().for_each(|x| *x = 2),
        );
        assert!(out[..500].iter().all(|&x| x == 1) && out[500..].iter().all(|&x| x == 2));
    }

    #[test]
    fn a_join_inside_a_join_runs_on_the_caller() {
        let helper = SpinHelper::with_thread().unwrap();
        let outer = thread::current().id();
        let ((a, b), c) = helper.join(
            || helper.join(|| thread::current().id(), || thread::current().id()),
            || thread::current().id(),
        );
        assert_eq!((a, b), (outer, outer));
        assert_ne!(c, outer);
        // And the helper is free again afterwards.
        let (_, d) = helper.join(|| (), || thread::current().id());
        assert_ne!(d, outer);
    }

    #[test]
    fn a_parked_helper_wakes_for_the_next_job() {
        let helper = SpinHelper::with_thread().unwrap();
        helper.join(|| (), || ());
        thread::sleep(SPIN * 3);
        let (_, b) = helper.join(|| 1, || 2);
        assert_eq!(b, 2);
    }

    #[test]
    fn panics_reach_the_caller_after_both_halves_finished() {
        let helper = SpinHelper::with_thread().unwrap();
        let finished = AtomicBool::new(false);
        let caught = catch_unwind(AssertUnwindSafe(|| {
            helper.join(
                || -> () { panic!("in a") },
                || {
                    thread::sleep(Duration::from_millis(20));
                    finished.store(true, Ordering::SeqCst);
                },
            )
        }))
        .unwrap_err();
        assert_eq!(panic_message(&*caught), "in a");
        assert!(finished.load(Ordering::SeqCst), "a unwound before b ended");
        let caught =
            catch_unwind(AssertUnwindSafe(|| helper.join(|| (), || panic!("in b")))).unwrap_err();
        assert_eq!(panic_message(&*caught), "in b");
        // The helper survives its job's panic.
        assert_eq!(helper.join(|| 3, || 4), (3, 4));
    }
}

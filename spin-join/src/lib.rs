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
//! parks, so a finished or idle run does not keep a core busy. A job the
//! helper has not started by the time the caller's own half is done is taken
//! back and run by the caller: on a machine whose cores are busy with other
//! work the helper may wait milliseconds for a core, and the caller would
//! otherwise wait with it. A helper that is late (spinning, it started a
//! job, or had not started it when the caller took it back, more than
//! [`LATE`] after the job was posted: it had no core) is not used for
//! [`REST`]: joins run both halves on the caller meanwhile, as one thread
//! would, and the helper parks instead of competing with the caller and the
//! machine's other work for a core; then it is tried again. (How long the
//! helper's half takes is no sign: the halves of a join need not be even.)
//!
//! Large batches (3D, first integrations) still go to rayon, which scales
//! past two threads.
//!
//! This is the only `unsafe` code of dsc-seg (whose crate forbids it): the
//! job a helper runs borrows from the caller's stack frame, and
//! [`join`](SpinHelper::join) does not return, nor unwind, before that job
//! has finished or been taken back unstarted.
#![warn(missing_docs)]

use std::cell::Cell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// How long the helper keeps spinning after its last job before it parks.
pub const SPIN: Duration = Duration::from_millis(5);

/// How long after a job is posted a spinning helper may start it before it
/// counts as late (it had no core): far more than a spinning helper takes
/// to see a job on a free core (well under a microsecond), far less than a
/// scheduler's time slice.
pub const LATE: Duration = Duration::from_micros(200);

/// How long a late helper is left unused: joins run both halves on the
/// caller meanwhile (a 2D run of a 256² or 512² image takes about this long
/// or less).
pub const REST: Duration = Duration::from_millis(250);

/// A second thread for [`join`](Self::join), or none (then `join` runs both
/// halves on the caller's thread).
///
/// `Send` but not `Sync`: one owner posts one job at a time.
pub struct SpinHelper {
    worker: Option<Worker>,
    /// Whether a job is in flight: a `join` inside a `join`'s first closure
    /// then runs both of its closures on the caller (not `Sync`: one caller).
    busy: Cell<bool>,
    /// Until when the helper rests after it was late (see [`REST`]).
    resting_until: Cell<Option<Instant>>,
    /// When the helper last finished a job of this owner: within [`SPIN`]
    /// of it the helper is spinning, so a late start means it had no core
    /// (not that it was waking from a park, or starting).
    last_finished: Cell<Option<Instant>>,
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
    /// The job's sequence number (the one `join` waits for).
    seq: u64,
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
    /// When the helper started the work.
    started: Option<Instant>,
}

/// Runs the packet's closure, catching a panic so that it reaches the caller.
///
/// # Safety
/// `packet` must point to a live `Packet<B, R>` that nothing else accesses.
unsafe fn run_packet<B: FnOnce() -> R, R>(packet: *mut ()) {
    // SAFETY: the caller's contract.
    let packet = unsafe { &mut *(packet as *mut Packet<B, R>) };
    if let Some(work) = packet.work.take() {
        packet.started = Some(Instant::now());
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
            resting_until: Cell::new(None),
            last_finished: Cell::new(None),
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
            resting_until: Cell::new(None),
            last_finished: Cell::new(None),
        })
    }

    /// Whether there is a helper thread.
    pub fn is_threaded(&self) -> bool {
        self.worker.is_some()
    }

    /// Leaves the helper unused for [`REST`].
    fn rest(&self) {
        self.resting_until.set(Some(Instant::now() + REST));
    }

    /// Whether the helper is resting after it was late (see [`REST`]).
    pub fn is_resting(&self) -> bool {
        self.resting_until
            .get()
            .is_some_and(|until| Instant::now() < until)
    }

    /// Runs `a` on this thread and `b` on the helper, at the same time, and
    /// returns both results (without a helper: `a` then `b`). If the helper
    /// has not started `b` when `a` returns, `b` is taken back and runs here
    /// after `a` (the helper may be waiting for a core). A panic in either
    /// is resumed here once both have finished (a panic in `a` drops a `b`
    /// not yet started instead).
    ///
    /// The caller waits for `b` without doing other work: `b` must not
    /// wait for a thread pool the caller belongs to (e.g. rayon work posted
    /// from `b` while the caller is one of rayon's workers, all of which
    /// may be waiting so).
    ///
    /// A helper that was late (see [`LATE`]) rests for [`REST`]: meanwhile
    /// both halves run here, `a` then `b`.
    pub fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB + Send,
        RB: Send,
    {
        let Some(worker) = self
            .worker
            .as_ref()
            .filter(|_| !self.busy.get() && !self.is_resting())
        else {
            let ra = a();
            return (ra, b());
        };
        self.busy.set(true);
        let mut packet = Packet {
            work: Some(b),
            outcome: None,
            started: None,
        };
        let posted = Instant::now();
        let seq = worker.post(
            &mut packet as *mut Packet<B, RB> as *mut (),
            run_packet::<B, RB>,
        );
        // Takes the job back or waits for the helper even if `a` unwinds:
        // `packet` lives on this stack frame.
        let wait = WaitFor {
            shared: &worker.shared,
            seq,
            busy: &self.busy,
        };
        let ra = a();
        drop(wait);
        let spinning = self
            .last_finished
            .get()
            .is_some_and(|t| posted.saturating_duration_since(t) < SPIN);
        if let Some(b) = packet.work.take() {
            // Taken back before the helper started it.
            if spinning && is_late(posted, None, Instant::now()) {
                self.rest();
            }
            return (ra, b());
        }
        let now = Instant::now();
        self.last_finished.set(Some(now));
        if spinning && is_late(posted, packet.started, now) {
            self.rest();
        }
        match packet.outcome.take() {
            Some(Ok(rb)) => (ra, rb),
            Some(Err(panic)) => resume_unwind(panic),
            None => unreachable!("the helper ran the posted job"),
        }
    }
}

/// Whether a helper that was spinning when a job was posted at `posted`
/// started it late: at `started`, or not at all by `now` (taken back).
fn is_late(posted: Instant, started: Option<Instant>, now: Instant) -> bool {
    started.unwrap_or(now).saturating_duration_since(posted) > LATE
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
    /// Publishes the job of `packet` and wakes the helper if it parked;
    /// returns the job's sequence number.
    fn post(&self, packet: *mut (), run: unsafe fn(*mut ())) -> u64 {
        let shared = &self.shared;
        let seq = shared.posted.load(Ordering::Relaxed) + 1;
        *shared.job.lock().unwrap_or_else(PoisonError::into_inner) = Some(Job { seq, packet, run });
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

/// On drop, takes job `seq` back if the helper has not started it, or
/// else blocks until the helper has finished it; then frees the helper for
/// the next `join`.
struct WaitFor<'a> {
    shared: &'a Shared,
    seq: u64,
    busy: &'a Cell<bool>,
}

impl WaitFor<'_> {
    /// Removes job `seq` from the slot if it is still there (not started).
    fn take_back(&self) -> bool {
        let mut slot = self
            .shared
            .job
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let ours = slot.as_ref().is_some_and(|job| job.seq == self.seq);
        if ours {
            *slot = None;
        }
        ours
    }
}

impl Drop for WaitFor<'_> {
    fn drop(&mut self) {
        if self.take_back() {
            self.busy.set(false);
            return;
        }
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
            // (empty when the poster took its job back)
            let job = shared
                .job
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take();
            if let Some(job) = job {
                // SAFETY: `join` posted a live packet and, having found the
                // slot empty, waits for `finished` to reach the job's number
                // before it touches or frees it.
                unsafe { (job.run)(job.packet) };
                shared.finished.store(job.seq, Ordering::Release);
            }
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

    /// Waits until `flag` is set (by the other half of a join, which the
    /// helper runs: the join must not find it resting, see
    /// [`until_awake`]).
    fn wait_for(flag: &AtomicBool) {
        while !flag.load(Ordering::SeqCst) {
            thread::yield_now();
        }
    }

    /// Waits until `helper` is not resting (a late start on a loaded
    /// machine may have sent it to rest), so that its next join runs `b`
    /// on the helper.
    fn until_awake(helper: &SpinHelper) {
        while helper.is_resting() {
            thread::sleep(REST / 10);
        }
    }

    #[test]
    fn a_join_inside_a_join_runs_on_the_caller() {
        let helper = SpinHelper::with_thread().unwrap();
        let outer = thread::current().id();
        // (`a` waits until `b` has started, so `b` cannot be taken back)
        let started = AtomicBool::new(false);
        let ((a, b), c) = helper.join(
            || {
                let inner = helper.join(|| thread::current().id(), || thread::current().id());
                wait_for(&started);
                inner
            },
            || {
                started.store(true, Ordering::SeqCst);
                thread::current().id()
            },
        );
        assert_eq!((a, b), (outer, outer));
        assert_ne!(c, outer);
        // And the helper is free again afterwards.
        until_awake(&helper);
        let started = AtomicBool::new(false);
        let (_, d) = helper.join(
            || wait_for(&started),
            || {
                started.store(true, Ordering::SeqCst);
                thread::current().id()
            },
        );
        assert_ne!(d, outer);
    }

    #[test]
    fn every_job_runs_once_whether_taken_back_or_not() {
        let helper = SpinHelper::with_thread().unwrap();
        let outer = thread::current().id();
        let runs = AtomicU64::new(0);
        let mut taken_back = 0;
        for round in 0..2_000 {
            if round % 500 == 0 {
                // parked: the first job after waking is likely taken back
                thread::sleep(SPIN * 2);
            }
            let (a, (b, on)) = helper.join(
                || round,
                || {
                    runs.fetch_add(1, Ordering::SeqCst);
                    (round + 1, thread::current().id())
                },
            );
            assert_eq!((a, b), (round, round + 1));
            taken_back += usize::from(on == outer);
        }
        assert_eq!(runs.load(Ordering::SeqCst), 2_000);
        // Both ways happen on a quiet machine; neither is required.
        eprintln!("{taken_back} of 2000 jobs taken back");
    }

    #[test]
    fn lateness_is_the_start_more_than_late_after_the_post() {
        let posted = Instant::now();
        let soon = posted + LATE / 2;
        let later = posted + LATE * 2;
        assert!(!is_late(posted, Some(soon), later));
        assert!(is_late(posted, Some(later), later));
        // taken back unstarted: judged at the time of taking back
        assert!(!is_late(posted, None, soon));
        assert!(is_late(posted, None, later));
    }

    #[test]
    fn a_resting_helper_leaves_both_halves_to_the_caller_then_works_again() {
        let helper = SpinHelper::with_thread().unwrap();
        let outer = thread::current().id();
        helper.rest();
        assert!(helper.is_resting());
        let (a, b) = helper.join(|| thread::current().id(), || thread::current().id());
        assert_eq!((a, b), (outer, outer));
        thread::sleep(REST);
        assert!(!helper.is_resting());
        let started = AtomicBool::new(false);
        let (_, on) = helper.join(
            || wait_for(&started),
            || {
                started.store(true, Ordering::SeqCst);
                thread::current().id()
            },
        );
        assert_ne!(on, outer);
    }

    #[test]
    fn panics_reach_the_caller_after_both_halves_finished() {
        let helper = SpinHelper::with_thread().unwrap();
        let (started, finished) = (AtomicBool::new(false), AtomicBool::new(false));
        let caught = catch_unwind(AssertUnwindSafe(|| {
            helper.join(
                || -> () {
                    wait_for(&started);
                    panic!("in a")
                },
                || {
                    started.store(true, Ordering::SeqCst);
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

//! Cooperative cancellation of a run from another thread.
//!
//! The command line stops on Ctrl-C by exiting the process; a library caller
//! cannot: a Python user interrupting a long 3D run in a notebook expects a
//! `KeyboardInterrupt` and a live interpreter. So the caller runs the
//! segmentation on a thread of its own inside [`with_token`], keeps the
//! token, and sets it when the user interrupts. Every segmentation loop on
//! that thread (the main run, the coarse pass, the candidate runs of
//! `--phases auto`) checks [`requested`] before each iteration and stops, and
//! the pipeline then returns [`Error::Interrupted`](crate::Error::Interrupted)
//! instead of a result. The token is per thread, so concurrent runs (Dask
//! workers) are cancelled one by one, never by another's interruption.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

thread_local! {
    static TOKEN: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// Runs `f` on this thread with `token` as its cancellation token: once the
/// token is set, the runs `f` makes stop at their next iteration.
pub fn with_token<T>(token: Arc<AtomicBool>, f: impl FnOnce() -> T) -> T {
    let previous = TOKEN.with(|t| t.replace(Some(token)));
    let result = f();
    TOKEN.with(|t| *t.borrow_mut() = previous);
    result
}

/// Whether this thread's run has been asked to stop.
pub fn requested() -> bool {
    TOKEN.with(|t| {
        t.borrow()
            .as_ref()
            .is_some_and(|token| token.load(Ordering::Relaxed))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_token_is_seen_on_its_thread_only() {
        let token = Arc::new(AtomicBool::new(false));
        assert!(!requested());
        with_token(token.clone(), || {
            assert!(!requested());
            token.store(true, Ordering::Relaxed);
            assert!(requested());
            std::thread::spawn(|| assert!(!requested())).join().unwrap();
        });
        assert!(!requested());
    }
}

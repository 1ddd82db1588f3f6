//! The process's thread pool, made fork-safe.
//!
//! Why this exists: rayon's global pool lives in worker threads, and `fork()` copies only the
//! thread that calls it. A child process (a `multiprocessing` pool with the Linux default
//! start method, `ProcessPoolExecutor`, a PyTorch `DataLoader` worker) that inherits an
//! initialised global pool hands its parallel work to workers that do not exist and waits
//! forever. So the native module never touches the global pool: every call into the crates
//! runs inside a pool owned here and tagged with the id of the process that built it. A forked
//! child sees another process id and builds a pool of its own on its first call; the
//! parent's pool, whose threads the child does not have, is leaked in the child, never
//! joined or dropped (dropping it would wait on threads that are not there).
//!
//! The lock is only taken with the interpreter held, and Python forks with the interpreter
//! held, so no thread of the parent can be inside it at the moment of a fork.
//!
//! The pool size follows rayon's rules (`RAYON_NUM_THREADS`, else the number of cores);
//! results do not depend on it (every parallel loop of the crates is thread-count
//! independent).

use std::sync::mpsc::{RecvTimeoutError, sync_channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use pyo3::prelude::*;
use qsr_core::progress::Watch;

/// The pool and the process that built it.
struct Owned {
    pid: u32,
    pool: Arc<rayon::ThreadPool>,
}

static POOL: Mutex<Option<Owned>> = Mutex::new(None);

/// This process's pool, built on first use in each process. `None` only if the operating
/// system refused to start threads; the caller then runs on the calling thread.
fn current(_py: Python<'_>) -> Option<Arc<rayon::ThreadPool>> {
    let pid = std::process::id();
    // A poisoned lock only means another call panicked while holding it; the data is a
    // plain handle and stays valid.
    let mut guard = POOL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some(owned) = guard.as_ref()
        && owned.pid == pid
    {
        return Some(Arc::clone(&owned.pool));
    }
    // In a forked child: the inherited pool's workers do not exist here.
    if let Some(stale) = guard.take() {
        std::mem::forget(stale);
    }
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("qrm-worker-{i}"))
            .build()
            .ok()?,
    );
    *guard = Some(Owned {
        pid,
        pool: Arc::clone(&pool),
    });
    Some(pool)
}

/// Runs `f` with the interpreter released, inside this process's pool: the entry point of
/// every call that does real work.
pub(crate) fn detach<T, F>(py: Python<'_>, f: F) -> T
where
    T: Send,
    F: FnOnce() -> T + Send,
{
    let pool = current(py);
    py.detach(move || match pool {
        Some(pool) => pool.install(f),
        None => f(),
    })
}

/// How often a watched call looks for Ctrl-C and reports progress: often enough that an
/// interrupt feels immediate, rarely enough that a Python callback costs nothing.
const WATCH_PERIOD: Duration = Duration::from_millis(100);

/// Runs `f` like [`detach`] while the calling thread watches it — the entry point of every
/// call that can run for seconds or more.
///
/// Why: with the interpreter released, Python handles Ctrl-C only when the call returns, and
/// a silent minute looks like a hang. So the work runs on a thread of its own (inside this
/// process's pool) with a [`Watch`], and the calling thread wakes every [`WATCH_PERIOD`]:
/// it runs Python's signal handlers (`check_signals`: a `KeyboardInterrupt` stops the work)
/// and, when the count changed, calls `callback(done, total)` with the interpreter held (an
/// exception it raises stops the work too). A stop is a request: the work notices it at its
/// next unit and returns early; this call waits for that, so nothing keeps running behind
/// the caller's back, and then raises the interrupt or the callback's exception. A finished
/// run's result does not depend on whether it was watched.
pub(crate) fn watched<T, F>(
    py: Python<'_>,
    callback: Option<&Bound<'_, PyAny>>,
    f: F,
) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Watch) -> T + Send,
{
    let pool = current(py);
    let watch = Watch::new();
    let mut reported = (0, 0);
    let mut stopped: Option<PyErr> = None;
    let mut report = |stopped: &mut Option<PyErr>| {
        let now = (watch.done(), watch.total());
        if stopped.is_none()
            && now != reported
            && let Some(cb) = callback
        {
            reported = now;
            // A signal the callback raised or let arrive (a GUI's stop button calling
            // `interrupt_main`) is handled here, not one watch period later: the work may
            // be over by then and its end must not swallow the interrupt.
            if let Err(e) = cb.call1(now).and_then(|_| py.check_signals()) {
                watch.stop();
                *stopped = Some(e);
            }
        }
    };
    let out = std::thread::scope(|scope| {
        let (tx, rx) = sync_channel(1);
        let w = &watch;
        scope.spawn(move || {
            let out = match pool {
                Some(pool) => pool.install(|| f(w)),
                None => f(w),
            };
            // The receiver lives until this thread is joined: the send cannot fail.
            let _ = tx.send(out);
        });
        let mut rx = rx;
        loop {
            // The receiver is moved in and back: the interpreter-free closure must be Send.
            let (got, back) = py.detach(move || (rx.recv_timeout(WATCH_PERIOD), rx));
            rx = back;
            match got {
                Ok(out) => return Some(out),
                // The worker panicked: the scope re-raises it (pyo3 turns it into a
                // PanicException).
                Err(RecvTimeoutError::Disconnected) => return None,
                Err(RecvTimeoutError::Timeout) => {}
            }
            if stopped.is_none()
                && let Err(e) = py.check_signals()
            {
                watch.stop();
                stopped = Some(e);
            }
            report(&mut stopped);
        }
    });
    report(&mut stopped);
    match (stopped, out) {
        (Some(e), _) => Err(e),
        (None, Some(out)) => Ok(out),
        (None, None) => Err(pyo3::panic::PanicException::new_err(
            "a worker thread of qrm panicked",
        )),
    }
}

/// The number of worker threads of this process's pool (for tests and diagnostics).
#[pyfunction]
pub(crate) fn worker_threads(py: Python<'_>) -> usize {
    detach(py, rayon::current_num_threads)
}

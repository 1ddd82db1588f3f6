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
//!
//! A call does not wait for a sleeping worker to wake up: the calling thread does the work
//! itself, as worker 0 of a pool of its own (every thread with one worker thread, the first
//! thread that calls with more; [`detach`]). Waking a worker costs 70–130 µs on a 2-core
//! virtual machine; a one-row classification through the wheel took 86–105 µs that way and
//! takes 1–3 µs now.

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
///
/// Where it can, the calling thread does the work itself as worker 0 of a pool of its own
/// ([`on_this_thread`]) instead of handing it to the shared pool and sleeping until a worker
/// is done. A hand-off wakes a sleeping worker, which on a 2-core VM costs 70–130 µs on
/// average with 0.1–1 ms of other work between calls — more than a small call's work; the
/// caller starts at once, and the pool's other workers (if any) join in as they wake. The
/// parallel loops of the crates do not depend on the thread count, so neither does the result.
pub(crate) fn detach<T, F>(py: Python<'_>, f: F) -> T
where
    T: Send,
    F: FnOnce() -> T + Send,
{
    let pool = current(py);
    py.detach(move || match pool {
        Some(pool) => {
            on_this_thread(pool.current_num_threads(), f).unwrap_or_else(|f| pool.install(f))
        }
        None => f(),
    })
}

/// How many threads get a pool of their own ([`on_this_thread`]) when the pool has one
/// thread: rayon leaks such a pool's registry (a few kilobytes) when its thread ends, so a
/// program that starts thread after thread must not leak one per thread; past this many,
/// calls hand off to the shared pool.
const OWN_POOLS_OF_ONE: usize = 64;

/// How many threads get a pool of their own with more than one thread: one (in practice the
/// thread that calls first, a script's main thread). Each such pool has workers of its own,
/// so every thread having one would multiply the process's threads.
const OWN_POOLS_OF_MANY: usize = 1;

static OWN_POOLS_BUILT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// A thread's own pool, the process that built it, and its size.
struct Own {
    pool: rayon::ThreadPool,
    pid: u32,
    threads: usize,
}

thread_local! {
    /// How long this thread's last call through its own pool took.
    static LAST_CALL: std::cell::Cell<Duration> = const { std::cell::Cell::new(Duration::ZERO) };
    /// This thread's own pool (the thread is its worker 0), kept for the thread's life:
    /// building it registers the thread with rayon for good. `None`: none to be had.
    static OWN: std::cell::OnceCell<Option<Own>> = const { std::cell::OnceCell::new() };
}

/// Runs `f` on the calling thread as worker 0 of a pool of its own with `threads` workers in
/// all, so that the crates' parallel loops start on the caller and the other workers (if any)
/// steal from it. Gives `f` back where no such pool can be had: past [`OWN_POOLS_OF_ONE`] or
/// [`OWN_POOLS_OF_MANY`] threads, if the build failed, or in a process forked from the one
/// that built it when the pool had other workers (they were not copied by `fork`; a pool of
/// one is the thread itself, which the child has).
///
/// A thread that is already a rayon worker but not of its own pool — a pool's job that
/// called back into Python and from there into qrm — runs `f` where it is, in that pool.
fn on_this_thread<T: Send, F: FnOnce() -> T + Send>(threads: usize, f: F) -> Result<T, F> {
    OWN.with(|own| {
        let own = own.get_or_init(|| {
            if rayon::current_thread_index().is_some() {
                return None; // a worker of another pool: it cannot join a second
            }
            use std::sync::atomic::Ordering;
            let cap = if threads == 1 {
                OWN_POOLS_OF_ONE
            } else {
                OWN_POOLS_OF_MANY
            };
            OWN_POOLS_BUILT
                .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
                    (n < cap).then_some(n + 1)
                })
                .ok()?;
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .use_current_thread()
                .thread_name(|i| format!("qrm-worker-own-{i}"))
                .build()
                .ok()?;
            Some(Own {
                pool,
                pid: std::process::id(),
                threads,
            })
        });
        match own {
            // the thread is this pool's worker 0: `install` runs `f` right here
            Some(own) if own.threads == 1 => Ok(own.pool.install(f)),
            Some(own) if own.pid == std::process::id() => {
                // a call like the last one on this thread is likely (a loop): keep the
                // workers awake only where the last call was long enough to need them
                let awake =
                    (LAST_CALL.get() > KEEP_AWAKE_AFTER).then(|| KeepAwake::start(&own.pool));
                let started = std::time::Instant::now();
                let out = own.pool.install(f);
                LAST_CALL.set(started.elapsed());
                drop(awake);
                Ok(out)
            }
            // an own pool whose other workers fork did not copy: the (fresh) shared pool
            Some(_) => Err(f),
            None if rayon::current_thread_index().is_some() => Ok(f()),
            None => Err(f),
        }
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

/// Whether a call's work starts on the calling thread (the thread has a pool of its own; see
/// [`detach`]) rather than being handed to a worker (for tests and diagnostics).
#[pyfunction]
pub(crate) fn _on_caller_thread(py: Python<'_>) -> bool {
    let caller = std::thread::current().id();
    detach(py, move || std::thread::current().id() == caller)
}

/// Keeps an own pool's other workers awake and stealing for one call: each runs a job that
/// takes pending work ([`rayon::yield_now`]) until the call is over (the guard is dropped,
/// panics included). Why: a step is several parallel loops with short serial parts between
/// them, and a rayon worker that finds no work sleeps within microseconds; waking it again
/// costs 50–100 µs on a virtual machine, so a worker woken per loop arrived when the loop
/// was nearly done. Woken once per call instead.
struct KeepAwake(std::sync::Arc<std::sync::atomic::AtomicBool>);

/// A call after one that took longer than this keeps its pool's workers awake
/// ([`KeepAwake`]); after a shorter one it does not pay for waking them (15–20 µs a call).
/// 100 µs, not 200: a 10-landmark step takes 0.19–0.25 ms on two threads of a fast CPU, and
/// calls either side of the threshold alternated between kept awake and not.
const KEEP_AWAKE_AFTER: Duration = Duration::from_micros(100);

/// How long a worker kept awake by [`KeepAwake`] waits for work before it goes back to
/// rayon's own idling: longer than the serial parts between a step's parallel loops.
const IDLE_WINDOW: Duration = Duration::from_micros(100);

impl KeepAwake {
    fn start(pool: &rayon::ThreadPool) -> Self {
        use std::sync::atomic::Ordering;
        let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let flag = std::sync::Arc::clone(&done);
        pool.spawn_broadcast(move |ctx| {
            // worker 0 is the caller: it runs its copy (if ever) while waiting inside the call
            if ctx.index() == 0 {
                return;
            }
            // Idle for IDLE_WINDOW, it stops anyway: this job may have been picked up while
            // the worker waited inside a job of the same call (a join whose other half
            // another worker runs), and it must not hold that job up for longer.
            let mut idle_since: Option<std::time::Instant> = None;
            while !flag.load(Ordering::Acquire) {
                if rayon::yield_now() == Some(rayon::Yield::Executed) {
                    idle_since = None;
                    continue;
                }
                let since = *idle_since.get_or_insert_with(std::time::Instant::now);
                if since.elapsed() > IDLE_WINDOW {
                    return;
                }
                std::hint::spin_loop();
            }
        });
        Self(done)
    }
}

impl Drop for KeepAwake {
    fn drop(&mut self) {
        self.0.store(true, std::sync::atomic::Ordering::Release);
    }
}

/// The number of worker threads of this process's pool (for tests and diagnostics).
#[pyfunction]
pub(crate) fn worker_threads(py: Python<'_>) -> usize {
    detach(py, rayon::current_num_threads)
}

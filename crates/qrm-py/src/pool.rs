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

use std::sync::{Arc, Mutex};

use pyo3::prelude::*;

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

/// The number of worker threads of this process's pool (for tests and diagnostics).
#[pyfunction]
pub(crate) fn worker_threads(py: Python<'_>) -> usize {
    detach(py, rayon::current_num_threads)
}

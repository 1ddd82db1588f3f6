"""Python process-level behaviour: fork safety, catchable exceptions, the distribution name."""
import importlib.metadata
import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import qrm

# A child that inherits rayon's global pool (workers that fork did not copy) used to wait
# forever; the script runs in its own interpreter so a hang is caught by the timeout, not by
# the test runner hanging.
FORK_AFTER_CALL = textwrap.dedent(
    """
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor
    import numpy as np
    import qrm

    def work(seed):
        edc = qrm.Calculus.builtin("edc")
        rng = np.random.default_rng(seed)
        ids = edc.classify(rng.normal(size=(20000, 6)))
        m = qrm.Pqrm(edc, samples=200, seed=seed)
        xy = np.array([[0.0, 0.0], [0.0, 5.0], [-1.0, 2.0], [2.0, 1.0]])
        m.update(0.0, np.array([1, 2, 3, 4]), xy, np.array([[0.01, 0.0, 0.01]] * 4))
        return int(ids.sum()), len(m), qrm.worker_threads()

    if __name__ == "__main__":
        parent = work(0)  # starts the parent's worker threads
        assert parent[2] >= 1
        ctx = mp.get_context("fork")
        with ctx.Pool(2) as pool:
            forked = pool.map(work, [0, 1, 2])
        with ProcessPoolExecutor(2, mp_context=ctx) as ex:
            executor = list(ex.map(work, [0, 1]))
        assert forked[0][:2] == parent[:2], (forked[0], parent)
        assert executor[0][:2] == parent[:2]
        # the parent still works after its children
        assert work(0)[:2] == parent[:2]
        print("fork-ok", parent[0], forked[1][0])
    """
)


# Issue 40: once the parent had loaded a map (its rows are checked in parallel), a forked
# child that loaded or unpickled one hung. Every loader, in the parent and then in children.
FORK_AFTER_LOAD = textwrap.dedent(
    """
    import os, pickle, sys
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor
    import numpy as np
    import qrm

    DIR = sys.argv[1]
    JSON, BIN, CSV = (os.path.join(DIR, n) for n in ("m.json", "m.pqrm", "obs.csv"))

    def loaded(_):
        maps = [
            qrm.Pqrm.load(JSON),
            qrm.Pqrm.load(BIN),
            qrm.Pqrm.from_json(open(JSON).read()),
            qrm.Pqrm.from_bytes(open(BIN, "rb").read()),
            pickle.loads(pickle.dumps(qrm.Pqrm.load(BIN))),
        ]
        scans, _ = qrm.read_observations(CSV, "csv")
        return [len(m) for m in maps] + [len(scans)]

    if __name__ == "__main__":
        edc = qrm.Calculus.builtin("edc")
        m = qrm.Pqrm(edc, samples=200, seed=1)
        xy = np.array([[0.0, 0.0], [0.0, 5.0], [-1.0, 2.0], [2.0, 1.0]])
        m.update(0.0, np.array([1, 2, 3, 4]), xy, np.array([[0.01, 0.0, 0.01]] * 4))
        m.save(JSON)
        m.save(BIN)
        with open(CSV, "w") as f:
            f.write("t,robot,landmark,x,y,cxx,cxy,cyy\\n")
            for i, (x, y) in enumerate(xy):
                f.write(f"0,0,{i + 1},{x},{y},0.01,0,0.01\\n")
        parent = loaded(0)  # the parent loads first
        ctx = mp.get_context("fork")
        with ProcessPoolExecutor(2, mp_context=ctx) as ex:
            assert list(ex.map(len, [m] * 4)) == [len(m)] * 4  # unpickled in the children
            children = list(ex.map(loaded, range(3)))
        assert all(c == parent for c in children), (children, parent)
        print("fork-ok", parent)
    """
)


def _run_fork_script(tmp_path, name, text, what, *args, threads="2"):
    """Runs a fork script in its own interpreter (a hang is caught by the timeout, not by the
    test runner hanging); it must print `fork-ok`. With `threads="1"` every call runs on its
    caller's thread (`pool.rs`, `on_this_thread`), which a child forked from that thread
    inherits."""
    script = tmp_path / name
    script.write_text(text)
    env = dict(os.environ, RAYON_NUM_THREADS=threads)
    try:
        done = subprocess.run(
            [sys.executable, str(script), *args], capture_output=True, text=True, timeout=120, env=env
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"a fork-based pool started after {what} hung (> 120 s)")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("fork-ok"), done.stdout


@pytest.mark.skipif(sys.platform != "linux", reason="fork is the default start method on Linux only")
@pytest.mark.parametrize("threads", ["1", "2"])
def test_fork_pool_after_loading_maps_does_not_hang(tmp_path, threads):
    _run_fork_script(
        tmp_path, "fork_after_load.py", FORK_AFTER_LOAD, "loading a map", str(tmp_path), threads=threads
    )


@pytest.mark.skipif(sys.platform != "linux", reason="fork is the default start method on Linux only")
@pytest.mark.parametrize("threads", ["1", "2"])
def test_fork_pool_after_a_qrm_call_does_not_hang(tmp_path, threads):
    _run_fork_script(tmp_path, "fork_after_call.py", FORK_AFTER_CALL, "a qrm call", threads=threads)


# A call runs on its caller's thread as worker 0 of a pool of its own: with one worker thread
# every Python thread has one (up to 64 threads; later ones hand off to the shared pool), with
# more only the first. Many threads at once, more threads than that, and a progress callback
# that calls qrm while a watched call runs: the same results as one thread calling in turn,
# and no hang.
THREADS = textwrap.dedent(
    """
    import os
    import threading
    import numpy as np
    import qrm

    edc = qrm.Calculus.builtin("edc")
    XY = np.array([[0.0, 0.0], [0.0, 5.0], [-1.0, 2.0], [2.0, 1.0], [1.5, -2.0]])
    COV = np.array([[0.3, 0.0, 0.3]] * 5)

    def work(seed):
        rng = np.random.default_rng(seed)
        states = edc.classify(rng.normal(size=(5000, 6)))
        m = qrm.Pqrm(edc, samples=300, orderings="all", seed=seed)
        for t in range(3):
            m.update(float(t), np.arange(5), XY, COV)
        return int(states.sum()), m.to_json(), qrm.worker_threads()

    want = [work(s) for s in range(10)]
    assert all(w[2] == int(os.environ["RAYON_NUM_THREADS"]) for w in want)
    got = {}
    def run(i):
        got[i] = work(i % 10)
    for wave in range(10):  # 100 threads in all, 10 at a time
        threads = [threading.Thread(target=run, args=(10 * wave + i,)) for i in range(10)]
        [t.start() for t in threads]
        [t.join(60) for t in threads]
    assert sorted(got) == list(range(100)), sorted(got)
    assert all(got[i] == want[i % 10] for i in got)

    seen = []
    def callback(done, total):
        seen.append(int(edc.classify(np.array([[0.0, 0.0, 0.0, 1.0, 1.0, 0.5]]))[0]))
    rng = np.random.default_rng(1)
    beliefs = [{"samples": rng.normal(c, 0.15, size=(300, 2))} for c in ([-1.0, 0.5], [1.0, 0.5], [0.0, 2.5])]
    learned = qrm.serge(beliefs, 3, sigma=0.0, trials=20, grid=24, window=(-2.0, 2.0, -1.0, 3.0), seed=2)
    qrm.compose_cells(learned.to_calculus("toy"), progress=callback)
    assert seen and len(set(seen)) == 1, seen
    print("threads-ok", len(got))
    """
)


@pytest.mark.parametrize("threads", ["1", "2"])
def test_calls_from_many_threads(tmp_path, threads):
    script = tmp_path / "threads.py"
    script.write_text(THREADS)
    try:
        done = subprocess.run(
            [sys.executable, str(script)], capture_output=True, text=True, timeout=300,
            env=dict(os.environ, RAYON_NUM_THREADS=threads),
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"calls from many Python threads with RAYON_NUM_THREADS={threads} hung (> 300 s)")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("threads-ok 100"), done.stdout


def test_calls_start_on_the_callers_thread():
    """A call's work starts on the thread that called (no hand-off to a sleeping worker,
    70-130 us a call on a 2-core VM): on every thread with one worker thread, on the first
    thread that calls with more (the others hand off to the shared pool)."""
    code = textwrap.dedent(
        """
        import threading, qrm
        from qrm import _qrm
        seen = [_qrm._on_caller_thread()]
        t = threading.Thread(target=lambda: seen.append(_qrm._on_caller_thread()))
        t.start(); t.join()
        print(seen)
        """
    )
    for n, want in [("1", "[True, True]"), ("2", "[True, False]")]:
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
            env=dict(os.environ, RAYON_NUM_THREADS=n),
        )
        assert out.stdout.strip() == want, (n, out.stdout, out.stderr)


def test_worker_threads_follow_rayon_num_threads(tmp_path):
    code = "import qrm; print(qrm.worker_threads())"
    for n in ["1", "3"]:
        out = subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True, text=True, timeout=60,
            env=dict(os.environ, RAYON_NUM_THREADS=n),
        )
        assert out.stdout.strip() == n, out.stderr


@pytest.mark.parametrize(
    "cls, builtin",
    [
        ("InvalidInput", ValueError),
        ("DegenerateFrame", ValueError),
        ("SpecError", ValueError),
        ("FormatError", ValueError),
        ("UnsupportedError", NotImplementedError),
        ("IoError", OSError),
    ],
)
def test_each_error_is_also_the_builtin_users_catch(cls, builtin):
    exc = getattr(qrm, cls)
    assert issubclass(exc, qrm.QrmError)
    assert issubclass(exc, builtin)
    assert exc.__module__ == "qrm"
    # Errors cross process boundaries (multiprocessing, Ray) by pickle.
    e = exc("a message")
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is exc and str(back) == "a message"


def test_raised_errors_are_caught_by_builtin_except_clauses(tmp_path):
    edc = qrm.Calculus.builtin("edc")
    with pytest.raises(ValueError, match="finite|NaN|nan"):
        edc.classify(np.array([[0.0, 0.0, 0.0, 1.0, np.nan, 0.0]]))
    with pytest.raises(ValueError):
        edc.classify(np.array([[1.0, 1.0, 1.0, 1.0, 0.0, 0.0]]))  # coincident: DegenerateFrame
    with pytest.raises(ValueError):
        qrm.Calculus.builtin("no-such-calculus")
    with pytest.raises(NotImplementedError):
        qrm.Calculus.builtin("star-4").compose()
    with pytest.raises(OSError) as info:
        qrm.Calculus.from_spec(str(tmp_path / "missing.toml"))
    assert isinstance(info.value, qrm.IoError)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,robot,landmark,x,y,cxx,cxy,cyy\n0,0,1,zero,0,1,0,1\n")
    with pytest.raises(ValueError) as info:
        qrm.read_observations(str(bad), "csv")
    assert isinstance(info.value, qrm.FormatError)
    # A QrmError is still not caught by an unrelated builtin.
    with pytest.raises(qrm.SpecError):
        try:
            qrm.Calculus.builtin("no-such-calculus")
        except OSError:
            pytest.fail("a spec error is not an OSError")


def test_distribution_name_is_not_the_taken_one():
    dists = importlib.metadata.packages_distributions().get("qrm", [])
    assert dists == ["qrm-robotics"], dists
    assert importlib.metadata.version("qrm-robotics") == qrm.__version__

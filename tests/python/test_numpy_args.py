"""Array arguments are taken as NumPy functions take them (`np.asarray` semantics), and every
refusal names the argument and what it expected (issue 19: float32/int64/lists gave
`TypeError: type mismatch`, a wrong `out` dtype "'ndarray' object is not an instance of
'ndarray'")."""
import numpy as np
import pytest

import qrm

ROWS = [[0.0, 0.0, 0.0, 10.0, -1.0, 5.0], [0.0, 0.0, 0.0, 10.0, 1.0, 5.0], [0.0, 0.0, 10.0, 0.0, 5.0, 0.5]]


@pytest.fixture(scope="module")
def edc():
    return qrm.Calculus.builtin("edc")


@pytest.mark.parametrize(
    "points",
    [
        np.array(ROWS, dtype=np.float32),
        np.array(ROWS, dtype=np.float64).astype(np.int64),
        ROWS,
        tuple(tuple(r) for r in ROWS),
        np.asfortranarray(np.array(ROWS)),
        np.array(ROWS)[::1, ::1],
    ],
    ids=["float32", "int64", "list", "tuple", "fortran", "view"],
)
def test_classify_takes_anything_numpy_reads_as_numbers(edc, points):
    expected = edc.classify(np.asarray(points, dtype=np.float64))
    assert list(edc.classify(points)) == list(expected)
    assert edc.classify_labels(points) == [edc.labels[i] for i in expected]


def test_a_float64_array_is_not_copied_and_out_is_filled(edc):
    pts = np.array(ROWS)
    out = np.full(3, -1, dtype=np.int64)
    r = edc.classify(pts, out=out)
    assert r is out and (out >= 0).all()


@pytest.mark.parametrize(
    "bad, words",
    [
        (np.array([[True] * 6]), ["points", "real numbers", "bool"]),
        (np.array([[1j] * 6]), ["points", "real numbers", "complex128"]),
        (np.array([["a"] * 6]), ["points", "real numbers", "<U1"]),
        ([[1.0] * 6, [1.0] * 5], ["points", "2-D array"]),
        (np.zeros(6), ["points", "2-D", "(6,)"]),
        (np.zeros((2, 6, 1)), ["points", "2-D", "(2, 6, 1)"]),
    ],
)
def test_what_is_not_an_array_of_coordinates_is_named(edc, bad, words):
    with pytest.raises(qrm.InvalidType) as e:
        edc.classify(bad)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_a_wrong_column_count_names_the_argument_and_the_shape(edc):
    with pytest.raises(qrm.InvalidInput, match=r"points: calculus `edc` takes rows of 6 numbers.*\(3, 5\)|points: calculus `edc` takes rows of 6 numbers.*\[3, 5\]"):
        edc.classify(np.zeros((3, 5)))


@pytest.mark.parametrize(
    "out, words",
    [
        (np.zeros(3, dtype=np.float64), ["out", "int64", "(3,)", "float64"]),
        (np.zeros(4, dtype=np.int64), ["out", "(3,)", "(4,)"]),
        ([0, 0, 0], ["out", "int64", "list"]),
    ],
)
def test_a_wrong_out_says_what_it_must_be(edc, out, words):
    with pytest.raises(qrm.InvalidType) as e:
        edc.classify(np.array(ROWS), out=out)
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_a_read_only_out_is_refused_not_a_crash(edc):
    out = np.zeros(3, dtype=np.int64)
    out.flags.writeable = False
    with pytest.raises(qrm.InvalidType, match="read-only"):
        edc.classify(np.array(ROWS), out=out)


@pytest.mark.parametrize("ids", [np.array([1, 2, 3], dtype=np.int32), np.array([1, 2, 3], dtype=np.uint16), [1, 2, 3]])
def test_update_takes_any_integer_ids_and_array_likes(edc, ids):
    m = qrm.Pqrm(edc, samples=50)
    xy = [[0.0, 0.0], [0.0, 10.0], [-1.0, 5.0]]
    cov = np.array([[0.01, 0.0, 0.01]] * 3, dtype=np.float32)
    r = m.update(0.0, ids, xy, cov)
    assert r["observed"] == 6
    ref = qrm.Pqrm(edc, samples=50)
    ref.update(0.0, np.array([1, 2, 3]), np.array(xy), cov.astype(np.float64))
    assert np.array_equal(m.belief((1, 2, 3)), ref.belief((1, 2, 3)))


@pytest.mark.parametrize(
    "ids, words",
    [
        (np.array([1.0, 2.0, 3.5]), ["ids", "integers", "float64"]),
        (np.array([1, 2, 2**63], dtype=np.uint64), ["ids", "beyond int64"]),
        (np.array([[1, 2, 3]]), ["ids", "1-D", "(1, 3)"]),
    ],
)
def test_ids_that_are_not_integers_are_refused_by_name(edc, ids, words):
    m = qrm.Pqrm(edc, samples=50)
    with pytest.raises(qrm.InvalidType) as e:
        m.update(0.0, ids, np.zeros((3, 2)), np.ones((3, 3)))
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_classify_columns_gives_the_rows_answer_for_contiguous_strided_and_listed_columns(edc):
    """Issue 16: a columns (SoA) entry point, how a data frame or a sampler holds triplets."""
    t = np.random.default_rng(4).uniform(0.0, 100.0, size=(50_000, 6))
    want = edc.classify(t)
    soa = [np.ascontiguousarray(t[:, j]) for j in range(6)]
    assert np.array_equal(edc.classify_columns(*soa), want)
    assert np.array_equal(edc.classify_columns(*(t[:, j] for j in range(6))), want)  # strided
    out = np.empty(len(t), dtype=np.int64)
    assert edc.classify_columns(*soa, out=out) is out
    assert np.array_equal(out, want)
    small = [list(c[:3]) for c in soa]
    assert edc.classify_columns(*small).tolist() == want[:3].tolist()
    assert edc.classify_columns(*(c.astype(np.float32) for c in soa)).shape == (len(t),)


def test_classify_columns_names_the_column_and_the_first_bad_row(edc):
    cols = [np.zeros(10), np.zeros(10), np.zeros(10), np.ones(10), np.ones(10), np.ones(10)]
    with pytest.raises(qrm.InvalidInput, match="cy has 9"):
        edc.classify_columns(*cols[:5], np.ones(9))
    bad = [c.copy() for c in cols]
    bad[4][7] = np.nan
    bad[4][8] = np.nan
    with pytest.raises(qrm.InvalidInput, match="row 7"):
        edc.classify_columns(*bad)
    coincident = [c.copy() for c in cols]
    coincident[3][2] = 0.0  # B = A in row 2
    with pytest.raises(qrm.DegenerateFrame, match="row 2"):
        edc.classify_columns(*coincident)
    with pytest.raises(qrm.InvalidType, match="ax: expected a 1-D array"):
        edc.classify_columns(np.zeros((2, 2)), *cols[1:])
    binary = next(n for n in qrm.builtin_names() if qrm.Calculus.builtin(n).frame != "ternary")
    with pytest.raises(qrm.InvalidInput, match="not ternary"):
        qrm.Calculus.builtin(binary).classify_columns(*cols)


def test_large_classifications_do_not_depend_on_the_thread_count(tmp_path):
    """`classify` and `classify_columns` split large inputs over the worker threads; every id
    depends on its row alone, so one thread gives the same array."""
    import subprocess
    import sys

    code = (
        "import numpy as np, qrm, hashlib\n"
        "t = np.random.default_rng(9).uniform(0, 100, size=(300_000, 6))\n"
        "e = qrm.Calculus.builtin('edc')\n"
        "a = e.classify(t); b = e.classify_columns(*(t[:, j] for j in range(6)))\n"
        "assert (a == b).all()\n"
        "print(qrm.worker_threads(), hashlib.sha256(a.tobytes()).hexdigest())\n"
    )
    import os

    runs = {}
    for threads in ("1", "2"):
        r = subprocess.run([sys.executable, "-c", code], env=dict(os.environ, RAYON_NUM_THREADS=threads),
                           capture_output=True, text=True, check=True)
        n, digest = r.stdout.split()
        assert n == threads
        runs[threads] = digest
    assert runs["1"] == runs["2"]

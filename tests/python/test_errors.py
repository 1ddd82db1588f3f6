"""Every exception class is raised by some bad input; panics never crash the interpreter."""
import numpy as np
import pytest

import qrm


def test_hierarchy():
    for cls in [qrm.InvalidInput, qrm.DegenerateFrame, qrm.SpecError, qrm.UnsupportedError, qrm.FormatError, qrm.IoError]:
        assert issubclass(cls, qrm.QrmError)
    assert issubclass(qrm.DegenerateFrame, qrm.InvalidInput)


def test_each_class_is_raised(tmp_path):
    edc = qrm.Calculus.builtin("edc")
    with pytest.raises(qrm.DegenerateFrame):
        edc.classify(np.array([[1.0, 1.0, 1.0, 1.0, 0.0, 0.0]]))
    with pytest.raises(qrm.InvalidInput):
        edc.classify(np.array([[0.0, 0.0, 0.0, 1.0, np.nan, 0.0]]))
    with pytest.raises(qrm.SpecError):
        qrm.Calculus.builtin("no-such-calculus")
    with pytest.raises(qrm.SpecError):
        qrm.Calculus.from_spec_text('name = "x"\nframe = "ternary"\n')
    with pytest.raises(qrm.UnsupportedError):
        qrm.Calculus.builtin("star-4").compose()
    with pytest.raises(qrm.IoError):
        qrm.Calculus.from_spec(str(tmp_path / "missing.toml"))
    bad = tmp_path / "bad.csv"
    bad.write_text("t,robot,landmark,x,y,cxx,cxy,cyy\n0,0,1,zero,0,1,0,1\n")
    with pytest.raises(qrm.FormatError):
        qrm.read_observations(str(bad), "csv")
    m = qrm.Pqrm(edc, samples=10)
    with pytest.raises(qrm.InvalidInput):
        m.update(0.0, np.array([1, 2]), np.zeros((2, 2)), np.array([[1.0, 2.0, 1.0], [1.0, 0.0, 1.0]]))  # not PSD
    with pytest.raises(qrm.DegenerateFrame):
        m.update(0.0, np.array([1, 2, 3]), np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0]]), np.zeros((3, 3)))
    with pytest.raises(qrm.InvalidInput):
        qrm.Pqrm(edc, samples=0)
    with pytest.raises(qrm.InvalidInput):
        qrm.monte_carlo_config(trails=3)
    with pytest.raises(qrm.FormatError):
        (tmp_path / "m.json").write_text('{"format": "qrm-pqrm", "version": 99}')
        qrm.Pqrm.load(str(tmp_path / "m.json"))


def test_options_are_keyword_only():
    with pytest.raises(TypeError):
        qrm.Pqrm(qrm.Calculus.builtin("edc"), 100)  # samples must be given by name


def test_nan_in_a_study_config_is_refused_by_field_not_read_as_unset():
    """Issue 39: NaN went through JSON as null, i.e. "not set" (gating off, every frame)."""
    cfg = qrm.studies.config("monte-carlo")
    cfg["floor"] = float("nan")
    with pytest.raises(qrm.InvalidInput, match="`floor`"):
        qrm.studies.run("monte-carlo", cfg)
    cfg = qrm.studies.config("monte-carlo")
    cfg["sigmas"] = [1.0, float("inf")]
    with pytest.raises(qrm.InvalidInput, match=r"`sigmas\[1\]`"):
        qrm.distributed.shards("monte-carlo", cfg)
    cfg = qrm.studies.config("monte-carlo")
    cfg["floor"] = "x"
    with pytest.raises(qrm.InvalidInput, match="field `floor`"):
        qrm.studies.run("monte-carlo", cfg)


def test_arguments_of_the_wrong_type_are_invalid_input_and_type_errors():
    """Issue 40: a 1-D array, float ids, a string array and an int32 `out=` raised a bare
    TypeError, not a qrm error; `qrm.InvalidType` is both (an InvalidInput, so a ValueError)."""
    edc = qrm.Calculus.builtin("edc")
    cases = [
        lambda: edc.classify(np.zeros(6)),
        lambda: edc.classify(np.array([["a"] * 6])),
        lambda: edc.classify(np.zeros((2, 6)), out=np.zeros(2, dtype=np.int32)),
        lambda: qrm.Pqrm(edc, samples=10).update(
            0.0, np.array([0.5, 1.5, 2.5]), np.zeros((3, 2)), np.tile(np.eye(2), (3, 1, 1))
        ),
    ]
    for call in cases:
        with pytest.raises(qrm.InvalidInput) as e:
            call()
        assert isinstance(e.value, TypeError) and isinstance(e.value, ValueError)
        assert isinstance(e.value, qrm.InvalidType)

"""qrm.Pqrm from Python: equal to the Rust CLI's map for the same seed; files; metrics."""
import json
import subprocess
import warnings

import numpy as np
import pytest

import qrm


def write_dataset(d):
    lm = {1: (0.0, 0.0), 2: (0.3, 4.0), 3: (3.1, 2.6), 4: (-2.2, 1.3), 5: (1.0, -2.0)}
    lines = ["t,robot,landmark,x,y,cxx,cxy,cyy"]
    for t in range(6):
        for i, (x, y) in lm.items():
            if (i + t) % 5 == 0:
                continue
            lines.append(f"{t},0,{i},{x + 0.01 * t},{y - 0.02 * t},0.09,0.01,0.08")
    (d / "obs.csv").write_text("\n".join(lines) + "\n")
    (d / "truth.csv").write_text("landmark,x,y\n" + "".join(f"{i},{x},{y}\n" for i, (x, y) in lm.items()))
    return d / "obs.csv", lm


def test_a_pqrm_built_from_python_equals_one_built_by_rust(qrm_bin, tmp_path):
    obs, truth = write_dataset(tmp_path)
    out = tmp_path / "rust"
    # the filter, as Python's Pqrm is (`qrm map`'s default is the layout map: test below)
    subprocess.run([qrm_bin, "map", "--format", "csv", "--input", str(obs), "--calculus", "edc", "--samples", "300", "--seed", "9", "--evidence", "shared", "--out", str(out)], check=True, capture_output=True)
    scans, _ = qrm.read_observations(str(obs), "csv")
    m = qrm.Pqrm(qrm.Calculus.builtin("edc"), samples=300, seed=9)
    for s in scans:
        m.update(s["t"], s["ids"], s["xy"], s["cov"], robot=s["robot"])
    assert json.loads(m.to_json()) == json.loads((out / "map.json").read_text())
    met = m.metrics({k: v for k, v in truth.items()})
    assert met["error_rate"] < 0.3 and len(met["top_n_error"]) == 20
    # a CSV carries its covariances: asking to fit a range-bearing noise is refused in
    # Python's words (regression: the message named the command line's --noise/--format)
    with pytest.raises(qrm.InvalidInput, match=r'noise="auto" fits a range-bearing sensor') as e:
        qrm.read_observations(str(obs), "csv", noise="auto")
    assert "--" not in str(e.value) and "csv" in str(e.value)


def test_update_belief_entropy_save_load(tmp_path):
    m = qrm.Pqrm(qrm.Calculus.builtin("left-right"), samples=200)
    r = m.update(0.0, np.array([1, 2, 3]), np.array([[0.0, 0.0], [0.0, 5.0], [-2.0, 2.0]]), np.array([[0.01, 0, 0.01]] * 3))
    assert r == {"observed": 6, "new": 6, "conflicts": 0}
    assert m.belief((1, 2, 3))[0] > 0.99
    assert m.belief((1, 2, 9)) is None
    assert 0 <= m.entropy() < 0.1 and len(m) == 6
    p = tmp_path / "map.json"
    m.save(str(p))
    back = qrm.Pqrm.load(str(p))
    assert back.to_json() == m.to_json() and back.sets() == m.sets()


def test_mrclam_through_python(mrclam_dir):
    scans, truth = qrm.read_observations(str(mrclam_dir), "mrclam")
    assert len(truth) == 15
    m = qrm.Pqrm(qrm.Calculus.builtin("double-cross"), samples=50)
    for s in [s for s in scans if len(s["ids"]) >= 3][:150]:
        m.update(s["t"], s["ids"], s["xy"], s["cov"], robot=s["robot"])
    assert m.metrics(truth)["error_rate"] < 5 / 6


def test_mrclam_is_read_as_qrm_map_reads_it(mrclam_dir):
    """Issue 35: by default the noise is fitted from the recording and gross outliers are
    gated, as `qrm map` does; the old reading stays available by its flags."""
    fitted, _ = qrm.read_observations(str(mrclam_dir), "mrclam")
    plain, _ = qrm.read_observations(str(mrclam_dir), "mrclam", noise="fixed", gate=False)
    asked, _ = qrm.read_observations(str(mrclam_dir), "mrclam", noise="auto", gate=True)
    count = lambda scans: sum(len(s["ids"]) for s in scans)
    # gating drops a few detections (Dataset 7: 121 of 16067), never most of them
    assert count(plain) * 0.9 < count(fitted) < count(plain)
    assert count(asked) == count(fitted)
    # the fitted noise is not MRCLAM's fixed 0.15 m / 0.01 rad: covariances differ
    by_key = {(s["t"], s["robot"]): s for s in plain}
    same = [(s, by_key[(s["t"], s["robot"])]) for s in fitted if (s["t"], s["robot"]) in by_key]
    assert same and any(not np.allclose(a["cov"][0], b["cov"][0]) for a, b in same if a["ids"][0] == b["ids"][0])
    # given σs mean fixed noise, not gated unless asked
    given, _ = qrm.read_observations(str(mrclam_dir), "mrclam", sigma_range=0.15, sigma_bearing=0.01)
    assert count(given) == count(plain)
    with pytest.raises(qrm.InvalidInput, match="noise"):
        qrm.read_observations(str(mrclam_dir), "mrclam", noise="guess")
    # refused in the function's own words, not the command line's flags
    with pytest.raises(qrm.InvalidInput, match=r'noise="auto" fits sigma_range') as e:
        qrm.read_observations(str(mrclam_dir), "mrclam", noise="auto", sigma_range=0.2)
    assert "--" not in str(e.value)


def test_a_recording_mapped_by_its_layout_is_what_qrm_map_makes(mrclam_dir, qrm_bin, tmp_path):
    """Issue 35: `qrm.layout_map` on what `read_observations` returns is `qrm map`'s default
    map of the same recording, set for set; a layout map takes no frames and merges with
    nothing; bad options are refused by name."""
    scans, truth = qrm.read_observations(str(mrclam_dir), "mrclam")
    edc = qrm.Calculus.builtin("edc")
    m, fit = qrm.layout_map(edc, scans)
    assert m.evidence == "layout" and fit["converged"] and fit["pairs"] > 20
    assert 0.0 < fit["sigma_shared"] < fit["sigma_frame"] < 0.5
    assert len(fit["landmarks"]) == 15 and all(v["sightings"] > 0 for v in fit["landmarks"].values())
    assert m.metrics(truth)["error_rate"] < 0.05
    subprocess.run([qrm_bin, "map", "--format", "mrclam", "--input", str(mrclam_dir), "--calculus", "edc", "--out", str(tmp_path / "cli")], check=True, capture_output=True)
    cli = qrm.Pqrm.load(str(tmp_path / "cli" / "map.json"))
    assert cli.evidence == "layout" and sorted(cli.sets()) == sorted(m.sets())
    for s in m.sets()[::7]:
        assert np.allclose(cli.belief(s), m.belief(s), atol=1e-5)
    # inference over a layout map warns how its calibration was measured; over the filter's, not
    with pytest.warns(UserWarning, match="layout map"):
        assert abs(m.infer(m.sets()[0])["p"].sum() - 1.0) < 1e-9
    f = qrm.Pqrm(edc, samples=100)
    for s in scans[:200]:
        if len(s["ids"]) >= 3:
            f.update(s["t"], s["ids"], s["xy"], s["cov"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f.infer(f.sets()[0])
    one = [s for s in scans if len(s["ids"]) >= 3][0]
    with pytest.raises(qrm.QrmError, match="layout map"):
        m.update(one["t"], one["ids"], one["xy"], one["cov"])
    with pytest.raises(qrm.QrmError, match="layout map"):
        m.merge(qrm.Pqrm(edc))
    with pytest.raises(qrm.InvalidInput, match="orderings"):
        qrm.layout_map(edc, scans, orderings="some")
    canonical, _ = qrm.layout_map(edc, scans, orderings="canonical")
    assert len(canonical) * 6 == len(m)
    del scans[3]["cov"]
    with pytest.raises(qrm.InvalidInput, match=r'scans\[3\] has no "cov"'):
        qrm.layout_map(edc, scans)


def test_single_observation_matches_phi():
    lr = qrm.Calculus.builtin("left-right")
    p = qrm.single_observation(lr, np.array([[0.0, 0.0], [0.0, 10.0], [-1.0, 5.0]]), np.array([[0, 0, 0], [0, 0, 0], [1.0, 0, 1.0]]), samples=40000, seed=1)
    assert abs(p[0] - 0.8413) < 0.01


def test_sim_run_feeds_the_mapper():
    frames = qrm.sim.run("hallway", 4)
    again = qrm.sim.run("hallway", 4)
    assert all(np.array_equal(a["xy"], b["xy"]) for a, b in zip(frames, again))
    m = qrm.Pqrm(qrm.Calculus.builtin("left-right"), samples=100)
    for f in frames:
        if len(f["ids"]) >= 3:
            m.update(f["t"], f["ids"], f["xy"], f["cov"])
    assert len(m) > 100
    with_scan = qrm.sim.run("hallway", 4, lidar=True)
    assert with_scan[0]["ranges"].shape == (1081,)
    with pytest.raises(qrm.SpecError):
        qrm.sim.run("moon", 1)


def _frames(positions, offsets):
    """One scan per offset: every landmark at its position, landmark 4 moved by the offset."""
    scans = []
    for k, e in enumerate(offsets):
        ids = np.array(sorted(positions), dtype=np.int64)
        xy = np.array([positions[i] for i in ids], dtype=float)
        if 4 in positions:
            xy[list(ids).index(4)] += [e, e]
        scans.append({"t": float(k), "robot": 0, "ids": ids, "xy": xy, "cov": np.tile([0.01, 0.0, 0.01], (len(ids), 1))})
    return scans


def test_the_survey_check_names_the_pairs_every_frame_sees_otherwise():
    survey = {1: (0.0, 0.0), 2: (4.0, 0.0), 3: (0.0, 3.0), 4: (4.0, 3.0)}
    # landmark 4 stood 0.3 m off in x and in y in every frame (± 1 cm)
    got = qrm.survey_agreement(_frames(survey, [0.3, 0.31, 0.29, 0.3, 0.3, 0.305]), survey)
    assert got["pairs_seen"] == 6
    assert [(a, b) for a, b, _, _ in got["off"]] == [(1, 4), (2, 4), (3, 4)]
    for (a, b, median, frames), want in zip(got["off"], [np.hypot(4.3, 3.3) - 5, np.hypot(0.3, 3.3) - 3, np.hypot(4.3, 0.3) - 4]):
        assert abs(median - want) < 0.02 and frames == 6
    # frames that scatter by ±0.5 m put no pair off; a stricter frame count judges none
    loose = qrm.survey_agreement(_frames(survey, [0.5, -0.45, 0.4, -0.5, 0.2, 0.1]), survey)
    assert loose["off"] == []
    assert qrm.survey_agreement(_frames(survey, [0.3] * 6), survey, min_frames=7) == {"pairs_seen": 0, "off": []}


def test_the_survey_check_refuses_what_it_cannot_read():
    survey = {1: (0.0, 0.0), 2: (4.0, 0.0)}
    scans = _frames({1: (0.0, 0.0), 2: (4.0, 0.0), 4: (1.0, 1.0)}, [0.0] * 5)
    del scans[2]["xy"]
    with pytest.raises(qrm.InvalidInput, match=r'scans\[2\] has no "xy"'):
        qrm.survey_agreement(scans, survey)
    with pytest.raises(qrm.InvalidInput, match="off must be"):
        qrm.survey_agreement([], survey, off=float("nan"))
    with pytest.raises(qrm.InvalidInput, match="min_frames"):
        qrm.survey_agreement([], survey, min_frames=0)
    bad = _frames({1: (0.0, 0.0), 2: (4.0, 0.0)}, [0.0])
    bad[0]["xy"][0, 0] = np.nan
    with pytest.raises(qrm.QrmError, match=r"scans\[0\]"):
        qrm.survey_agreement(bad, survey)

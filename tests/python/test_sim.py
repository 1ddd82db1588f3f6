"""`qrm.sim.record` writes the recording `qrm sim` writes: one definition of the files
(`studies::simulation`, written through `qrm-files`) for both front ends."""
import filecmp
import subprocess

import pytest

import qrm

SCENARIO_SVG = "scenario.svg"


@pytest.mark.parametrize(
    "args, kwargs",
    [
        (["--scenario", "hallway", "--seed", "3"], dict(scenario="hallway", seed=3)),
        (
            ["--scenario", "field", "--seed", "1", "--detector", "lidar"],
            dict(scenario="field", seed=1, detector="lidar"),
        ),
        (
            ["--scenario", "pqrm-100", "--seed", "2", "--no-lidar", "--landmark-radius", "0.4"],
            dict(scenario="pqrm-100", seed=2, lidar=False, landmark_radius=0.4),
        ),
    ],
)
def test_python_records_the_files_qrm_sim_writes_byte_for_byte(qrm_bin, tmp_path, args, kwargs):
    cli = tmp_path / "cli"
    subprocess.run([qrm_bin, "sim", *args, "--out", str(cli)], check=True, capture_output=True)
    py = tmp_path / "py"
    written = qrm.sim.record(out=py, **kwargs)
    expected = sorted(p.name for p in cli.iterdir())
    assert written == expected
    assert {"observations.csv", "truth.csv", "world.toml", "run.mcap", SCENARIO_SVG} <= set(written)
    match, mismatch, errors = filecmp.cmpfiles(cli, py, expected, shallow=False)
    assert (mismatch, errors) == ([], [])


def test_a_bad_request_writes_nothing(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(qrm.InvalidInput, match="lidar"):
        qrm.sim.record("field", 0, out, detector="lidar", lidar=False)
    with pytest.raises(qrm.InvalidInput, match="detector"):
        qrm.sim.record("field", 0, out, detector="sonar")
    with pytest.raises(qrm.QrmError, match="scenario"):
        qrm.sim.record("moon", 0, out)
    bad = tmp_path / "world.toml"
    bad.write_text("landmarks = 3\n")
    with pytest.raises(qrm.QrmError, match="world file"):
        qrm.sim.record("hallway", 0, out, world=bad)
    assert not out.exists()

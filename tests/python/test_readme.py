"""The README's Python blocks run as written and pass `mypy --strict`."""
import pathlib
import re
import subprocess
import sys

README = pathlib.Path(__file__).resolve().parents[2] / "README.md"


def python_blocks():
    section = README.read_text().split("## Python", 1)[1]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_readme_python_quick_start_runs(capsys):
    readme = (pathlib.Path(__file__).resolve().parents[2] / "README.md").read_text()
    section = readme.split("## Python", 1)[1]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert blocks, "the README has a Python example"
    exec(compile(blocks[0], "README.md", "exec"), {})
    out = capsys.readouterr().out.split("\n")
    assert out[0] == "['13']"
    # C = (-1, 2) with A = (0, 0), B = (0, 5) is (-0.2, 0.4) normalised: left, below the
    # midpoint, inside both circles: the left lune state 13.
    assert out[1] == "13"


def test_readme_simulated_frames_feed_the_map():
    blocks = python_blocks()
    assert len(blocks) >= 2
    out = subprocess.run([sys.executable, "-c", blocks[1]], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "True"


def test_readme_python_blocks_pass_mypy_strict(tmp_path):
    """Issue 19: `qrm.sim.run` returned List[Dict[str, object]], so the README's own
    `m.update(f["t"], f["ids"], f["xy"], f["cov"])` failed mypy --strict."""
    for i, block in enumerate(python_blocks()):
        f = tmp_path / f"readme_block_{i}.py"
        f.write_text(block)
        r = subprocess.run(
            [sys.executable, "-m", "mypy", "--strict", "--no-incremental", str(f)],
            capture_output=True,
            text=True,
        )
        assert r.returncode == 0, f"README block {i}:\n{r.stdout}{r.stderr}"

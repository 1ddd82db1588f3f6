"""The README's Python quick start runs as written."""
import pathlib
import re


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

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


# Lines of the README's shell blocks that are not `qrm` commands: setup, benches, the fuzzer,
# the test suite itself (each is run by CI another way or is a tool install).
NOT_QRM = ("git clone", "cargo build", "cargo bench", "cd fuzz", "python3 ", ".venv/", "scripts/test")

# Long runs replaced by their quick settings (the commands, flags and files stay the same).
QUICKER = {
    "pqrm study --out out/study-full": "pqrm study --quick --out out/study-full",
    "serge study --out out/serge-full": "serge study --quick --out out/serge-full",
    "--set pairs=2000": "--set pairs=10 --set schedule_pairs=10",
    "qlink study --trial sensor-range --out": "qlink study --quick --trial sensor-range --out",
    "qlink study --out out/qlink-full": "qlink study --quick --out out/qlink-full",
    "qlink field --out out/field-trials": "qlink field --quick --out out/field-trials",
}


def shell_commands():
    """Every command of the README's ```sh blocks, in order: continuation lines (a trailing
    backslash, or an open single quote) joined."""
    commands = []
    for block in re.findall(r"```sh\n(.*?)```", README.read_text(), flags=re.S):
        pending = ""
        for line in block.splitlines():
            if not pending and (not line.strip() or line.lstrip().startswith("#")):
                continue
            pending = f"{pending}\n{line}" if pending else line
            if pending.endswith("\\") or pending.count("'") % 2 == 1:
                continue
            commands.append(pending)
            pending = ""
    return commands


def test_readme_shell_blocks_run_in_order_from_a_fresh_checkout(qrm_bin, tmp_path, mrclam_dir):
    """Issue 40: blocks used files no earlier block made (`beliefs.json`, the field
    recording, `net.json`), and flags the commands do not take (`study shard --full`). Every
    `qrm` command of the README runs here, in order, as written but for `cargo run --release
    --` (the binary) and the long runs in QUICKER, in a fresh directory with the checkout's
    files and `../shared` beside it; each must succeed."""
    checkout = tmp_path / "qrm"
    checkout.mkdir()
    root = README.parent
    for entry in root.iterdir():
        if entry.name not in {"out", "target", ".git"}:
            (checkout / entry.name).symlink_to(entry)
    (tmp_path / "shared").symlink_to(mrclam_dir.parents[1])
    ran = 0
    for command in shell_commands():
        if command.startswith(NOT_QRM):
            continue
        for long, quick in QUICKER.items():
            command = command.replace(long, quick)
        command = command.replace("cargo run --release --", qrm_bin)
        done = subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=checkout,
                              capture_output=True, text=True, timeout=900)
        assert done.returncode == 0, f"README: `{command}` failed:\n{done.stderr[-2000:]}"
        ran += qrm_bin in command
    assert ran >= 40, f"only {ran} README commands found"
    for made in ["out/map/map.json", "net.json", "out/learned/calculus.json", "out/merged.json"]:
        assert (checkout / made).exists(), made

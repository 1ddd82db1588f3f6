"""`qrm.studies`: every study through the one runner, the same as `qrm study run`."""
from __future__ import annotations

import csv
import json
import subprocess

import pytest

import qrm
from qrm import types as qt
from test_types import conforms


def small_config() -> dict:
    cfg = qrm.studies.config("table-4-1", seed=5)
    cfg.update(
        trial="sensor-range",
        pairs=30,
        schedule_pairs=30,
        samples=30,
        range_factors=[1.0, 0.7],
    )
    return cfg


@pytest.fixture(scope="module")
def small_run() -> qt.StudyRun:
    return qrm.studies.run("table-4-1", small_config())


def test_the_registry_lists_table_4_1_and_its_configs():
    names = [n for n, _ in qrm.studies.available()]
    assert "table-4-1" in names
    quick, full = qrm.studies.config("table-4-1"), qrm.studies.config("table-4-1", full=True)
    assert quick["pairs"] == 400 and full["pairs"] is None  # None: all 39,800 pairs
    assert qrm.studies.config("table-4-1", seed=9)["seed"] == 9


def test_a_run_is_typed_and_judged(small_run):
    conforms(small_run, qt.StudyRun)
    report = small_run["report"]
    rows = next(t for t in report["tables"] if t["name"] == "table")["rows"]
    assert len(rows) == 2  # one per range factor
    claim = next(c for c in report["claims"] if c["what"].startswith("Failure rate as R'"))
    ours = [r[7]["csv"] for r in rows]  # failure_rate, in full
    rising = float(ours[1]) > float(ours[0])
    assert claim["verdict"] == ("agree" if rising else "disagree"), (claim, ours)
    assert small_run["config"]["pairs"] == 30
    assert len(small_run["output"]["records"]) == 60


class _Bar:
    """What tqdm offers qrm: `total` and `update(n)`; records what qrm did with them."""

    def __init__(self) -> None:
        self.total = None
        self.n = 0
        self.totals_seen: list = []

    def update(self, n: int = 1) -> None:
        self.totals_seen.append(self.total)
        self.n += n


@pytest.mark.parametrize("name", ["table-4-1", "field", "demo"])
def test_a_bars_total_is_known_before_it_moves_and_is_met(name):
    # issue 40: the total grew ~20x during `qrm.studies.run` (97 %, then back), 0 for 38 s
    cfg = small_config() if name == "table-4-1" else qrm.studies.config(name)
    bar = _Bar()
    qrm.studies.run(name, cfg, progress=bar)
    assert bar.totals_seen and set(bar.totals_seen) == {bar.total}, bar.totals_seen[:5]
    assert bar.n == bar.total > 0


def test_python_and_the_cli_write_the_same_table(small_run, qrm_bin, tmp_path):
    # the flat fields as TOML; the tables (schedule, references) are the built-in ones
    toml_lines = []
    for k, v in small_config().items():
        if v is None or isinstance(v, dict) or (isinstance(v, list) and isinstance(v[0], dict)):
            continue
        toml_lines.append(f"{k} = {json.dumps(v)}")
    cfg = tmp_path / "cfg.toml"
    cfg.write_text("\n".join(toml_lines) + "\n")
    out = tmp_path / "out"
    subprocess.run(
        [qrm_bin, "study", "run", "table-4-1", "--config", str(cfg), "--out", str(out)],
        check=True,
        capture_output=True,
    )
    with open(out / "table.csv", newline="") as f:
        cli_rows = list(csv.reader(f))
    table = next(t for t in small_run["report"]["tables"] if t["name"] == "table")
    keys = [c["key"] for c in table["columns"] if c["shown"] != "human-only"]
    shown = [i for i, c in enumerate(table["columns"]) if c["shown"] != "human-only"]
    py_rows = [keys] + [[row[i]["csv"] for i in shown] for row in table["rows"]]
    assert cli_rows == py_rows


def test_a_misspelt_or_mistyped_field_is_refused_by_name():
    cfg = small_config()
    cfg["pears"] = 3
    with pytest.raises(qrm.InvalidInput, match="pears"):
        qrm.studies.run("table-4-1", cfg)
    cfg = small_config()
    cfg["pairs"] = "many"
    with pytest.raises(qrm.InvalidInput, match="many"):
        qrm.studies.run("table-4-1", cfg)
    with pytest.raises(qrm.InvalidInput, match="unknown study"):
        qrm.studies.run("table-9-9")


def test_a_table_becomes_a_data_frame(small_run):
    pd = pytest.importorskip("pandas")
    df = qrm.studies.table_frame(small_run["report"], "table")
    assert isinstance(df, pd.DataFrame)
    assert list(df["pairs"]) == [30, 30]
    with pytest.raises(KeyError, match="tables"):
        qrm.studies.table_frame(small_run["report"], "nope")


@pytest.mark.parametrize(
    "name,changes,table",
    [
        ("field", dict(trials=2, worlds=1), "variants"),
        ("serge-cv", dict(datasets=["hallway"], folds=2, grid=30, mus=[1, 5], sigmas=[2.0],
                          trials_per_belief=2, samples=300), "hallway/cv"),
    ],
)
def test_the_field_and_serge_studies_run_from_python_typed(name, changes, table):
    # issue 14 §2: every study through qrm.studies.run, its figures' data typed
    cfg = qrm.studies.config(name, seed=4)
    cfg.update(changes)
    run = qrm.studies.run(name, cfg)
    conforms(run, qt.StudyRun)
    report = run["report"]
    assert any(t["name"] == table for t in report["tables"])
    assert report["claims"] and all(
        c["verdict"] in ("agree", "disagree", "holds", "violated", "not-judged") for c in report["claims"]
    )
    kinds = {f["plot"]["kind"] for f in report["figures"]}
    assert kinds & {"site", "regions"}, kinds
    with pytest.raises(qrm.InvalidInput, match="worlds|datasets"):
        bad = dict(cfg, worlds=0) if name == "field" else dict(cfg, datasets=[])
        qrm.studies.run(name, bad)


def test_the_real_data_study_runs_from_python_as_on_the_command_line(mrclam_dir, qrm_bin, tmp_path):
    # issue 14 §2: the real-data study through qrm.studies.run, the same real.csv as the CLI
    cfg = qrm.studies.config("real-data", seed=3)
    cfg.update(input=str(mrclam_dir), max_frames=40, samples=30, variants=cfg["variants"][:1])
    run = qrm.studies.run("real-data", cfg)
    conforms(run, qt.StudyRun)
    report = run["report"]
    # five claims beside the thesis, then the three bars every recording is held to and
    # whether its ECE is beyond what chance gives a calibrated map (ours)
    verdicts = [c["verdict"] for c in report["claims"]]
    assert [v in ("agree", "disagree") for v in verdicts] == [True] * 5 + [False] * 4, verdicts
    assert set(verdicts[5:]) <= {"holds", "violated"}
    assert cfg["evidence"] == "layout" and cfg["also"] == []
    assert len(run["output"]["results"]) == 6 and len(run["output"]["sensor_models"]) == 6
    out = tmp_path / "real"
    subprocess.run(
        [qrm_bin, "pqrm", "real", "--input", str(mrclam_dir), "--max-frames", "40",
         "--samples", "30", "--seed", "3", "--out", str(out)],
        check=True,
        capture_output=True,
    )
    with open(out / "real.csv", newline="") as f:
        cli_rows = list(csv.reader(f))
    table = next(t for t in report["tables"] if t["name"] == "real")
    assert cli_rows == [[c["key"] for c in table["columns"]]] + [
        [cell["csv"] for cell in row] for row in table["rows"]
    ]
    with pytest.raises(qrm.InvalidInput, match="no such directory"):
        qrm.studies.run("real-data", dict(cfg, input=str(tmp_path / "nothing")))


def test_the_demo_runs_from_python_with_the_files_of_qrm_demo(qrm_bin, tmp_path):
    # issue 14 §2: the demo is a study; Python gets its log, summary and learned calculus as
    # the CLI writes them, byte for byte. Issue 40: with no seed given, `qrm demo`, `qrm study
    # run demo` and `qrm.studies.run("demo")` run one config (seed 1 was `qrm demo`'s alone).
    run = qrm.studies.run("demo")
    assert run["config"]["seed"] == qrm.studies.config("demo")["seed"]
    conforms(run, qt.StudyRun)
    files = {a["name"]: a for a in run["report"]["attachments"]}
    log = files["run.mcap"]["data"]
    assert isinstance(log, bytes) and log.startswith(b"\x89MCAP0\r\n")
    assert files["summary.json"]["data"] is None
    summary = json.loads(files["summary.json"]["text"])
    assert summary["success"] is True and summary["plan_len"] >= 3
    plot = next(f["plot"] for f in run["report"]["figures"] if f["name"] == "demo")
    assert plot["kind"] == "navigation" and plot["regions"] is not None
    assert len(plot["plan"]) == summary["plan_len"] + 1
    out = tmp_path / "demo"
    subprocess.run([qrm_bin, "demo", "--out", str(out)], check=True, capture_output=True)
    assert (out / "run.mcap").read_bytes() == log
    study_out = tmp_path / "study-demo"
    subprocess.run([qrm_bin, "study", "run", "demo", "--out", str(study_out)], check=True,
                   capture_output=True)
    assert (study_out / "run.mcap").read_bytes() == log
    assert (study_out / "summary.json").read_text() == files["summary.json"]["text"]
    assert (out / "summary.json").read_text() == files["summary.json"]["text"]
    assert (out / "learned_calculus.json").read_text() == files["learned_calculus.json"]["text"]
    with pytest.raises(qrm.InvalidInput, match="nav_range"):
        qrm.studies.run("demo", {"seed": 1, "nav_range": -1.0})
    # issue 14 §2: saved from Python, the run is the directory `qrm demo` wrote, file for
    # file and byte for byte (figures drawn by the same code), but report.md's line with the
    # run time, which only a run measured on the command line has
    saved = tmp_path / "saved"
    written = qrm.studies.save(run, saved)
    cli_files = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert written == cli_files and "demo.png" in written and "report.md" in written
    for name in written:
        ours, theirs = (saved / name).read_bytes(), (out / name).read_bytes()
        if name == "report.md":
            timing = [l for l in theirs.decode().splitlines() if l.startswith("Run in ")]
            assert len(timing) == 1
            theirs = theirs.replace(("\n" + timing[0] + "\n").encode(), b"")
        assert ours == theirs, name


def test_save_refuses_an_output_that_is_not_the_studys(small_run, tmp_path):
    # a wrong implementation would write whatever it is given: the report is made again from
    # the typed output, so an output of the wrong shape is refused and nothing is written
    broken = dict(small_run)
    broken["output"] = {"records": "not a list"}
    with pytest.raises(qrm.InvalidInput, match="not an output of `table-4-1`"):
        qrm.studies.save(broken, tmp_path / "broken")
    assert not (tmp_path / "broken").exists()
    assert list(tmp_path.iterdir()) == []
    # a file where the directory should be is an OSError naming it
    (tmp_path / "file").write_text("x")
    with pytest.raises(OSError, match="is a file"):
        qrm.studies.save(small_run, tmp_path / "file")


def test_the_reasoning_study_runs_from_python_as_on_the_command_line(mrclam_dir, qrm_bin, tmp_path):
    # issue 14 §2: `qrm reason study` is the registry's `reason`; Python gets the same scores
    cfg = qrm.studies.config("reason", seed=4)
    cfg.update(input=str(mrclam_dir), max_frames=80)
    cfg["study"]["calculi"] = ["double-cross"]
    run = qrm.studies.run("reason", cfg)
    conforms(run, qt.StudyRun)
    report = run["report"]
    assert {c["verdict"] for c in report["claims"]} <= {"holds", "violated"}
    kinds = {f["plot"]["kind"] for f in report["figures"]}
    assert kinds <= {"lines", "reference-pair"} and "lines" in kinds
    out = tmp_path / "reason"
    subprocess.run(
        [qrm_bin, "reason", "study", "--quick", "--calculi", "double-cross", "--max-frames", "80",
         "--seed", "4", "--input", str(mrclam_dir), "--out", str(out)],
        check=True,
        capture_output=True,
    )
    with open(out / "scores.csv", newline="") as f:
        cli_rows = list(csv.reader(f))
    table = next(t for t in report["tables"] if t["name"] == "scores")
    assert cli_rows == [[c["key"] for c in table["columns"]]] + [
        [cell["csv"] for cell in row] for row in table["rows"]
    ]
    reason_json = next(a for a in report["attachments"] if a["name"] == "reason.json")
    assert (out / "reason.json").read_text() == reason_json["text"]
    with pytest.raises(qrm.InvalidInput, match="hide_fraction"):
        bad = json.loads(json.dumps(cfg))
        bad["study"]["hide_fraction"] = 1.5
        qrm.studies.run("reason", bad)

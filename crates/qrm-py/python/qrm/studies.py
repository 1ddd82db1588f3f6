"""Every thesis study through one runner — the same configs, runs and reports as `qrm study`
on the command line (the studies themselves are in the Rust `studies` crate).

    >>> import qrm
    >>> [name for name, _ in qrm.studies.available()]
    ['monte-carlo', 'real-data', 'reason', 'serge-cv', 'table-4-1', 'field', 'demo']
    >>> cfg = qrm.studies.config("table-4-1")          # the quick config, a dict to edit
    >>> cfg["pairs"] = 40
    >>> run = qrm.studies.run("table-4-1", cfg)        # doctest: +SKIP
    >>> [c["verdict"] for c in run["report"]["claims"]]  # doctest: +SKIP

A run returns `{"study", "config", "output", "report"}`: the study's name, the config it ran (every field filled in),
the study's output (records and summaries) and its report — tables (each cell with its CSV
field and its text), claims set beside the thesis's with computed verdicts, and the data of
its figures, and the files it writes beside them (`attachments`: the demo's `summary.json`,
learned calculus and `run.mcap` log, whose bytes are in `data`). `save(run, dir)` writes it
as `qrm study run` does: tables as CSV, figures as SVG and PNG, report.md.
"""

from __future__ import annotations

import base64
import json
import math
import os
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

from . import _qrm, types
from . import _progress_callback, Progress  # noqa: F401  (re-used, not re-exported)

__all__ = ["available", "config", "run", "save", "table_frame"]


def available() -> List[Tuple[str, str]]:
    """`[(name, what it reproduces), ...]` of every study."""
    return [(n, a) for n, a in _qrm.studies_list()]


def config(name: str, *, full: bool = False, seed: Optional[int] = None) -> Dict[str, Any]:
    """The quick (default) or the thesis's full config of study `name`, as a dict to edit and
    pass to `run`. `seed` None: the study's default seed, as on the command line (0 but for
    the demo)."""
    result: Dict[str, Any] = json.loads(_qrm.studies_config(name, full, seed))
    return result


def run(
    name: str,
    config: Optional[Mapping[str, Any]] = None,
    *,
    quick: bool = False,
    seed: Optional[int] = None,
    progress: Optional[Progress] = None,
) -> types.StudyRun:
    """Runs study `name` with `config` (a dict as `config` returns; None: the built-in quick
    config with `quick=True`, else the thesis's) and returns its config, output and report.
    A config field of the wrong name or type raises `InvalidInput` naming it. `progress` counts
    the study's units of work (maps, navigations, trials, folds), the whole total announced
    before the first; Ctrl-C stops the run within a second."""
    text = None if config is None else _config_json(config)
    return _as_run(_qrm.studies_run(name, text, quick, seed, progress=_progress_callback(progress)))


def save(run: types.StudyRun, out: Union[str, "os.PathLike[str]"]) -> List[str]:
    """Writes `run` (as `run` or `qrm.distributed.run` returned it) into directory `out` as
    `qrm study run NAME --out DIR` does: each table as CSV, each figure as SVG and PNG, the
    attachments, the study's output file, report.md and config.toml — the same bytes, but
    report.md's line with the run time, which only a run measured there has. The report is
    made again from the run's config and output, so a run edited by hand is refused if its
    output no longer fits the study. Written whole or not at all; returns the files written,
    relative to `out`."""
    return _qrm.studies_save(
        run["study"], json.dumps(run["config"]), json.dumps(run["output"]), os.fspath(out)
    )


def _non_finite(value: Any, at: str) -> Optional[Tuple[str, float]]:
    """The first NaN or infinity in a config, by dotted path (`grid.step`, `sigmas[1]`)."""
    if isinstance(value, float) and not math.isfinite(value):
        return at, value
    if isinstance(value, Mapping):
        for k, v in value.items():
            found = _non_finite(v, f"{at}.{k}" if at else str(k))
            if found:
                return found
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            found = _non_finite(v, f"{at}[{i}]")
            if found:
                return found
    return None


def _config_json(config: Mapping[str, Any]) -> str:
    """A config as JSON, refusing NaN and infinity by field: JSON has neither, and a config
    value cannot mean "not set" by being NaN (the same rule as `qrm study run --set`)."""
    found = _non_finite(dict(config), "")
    if found:
        field, value = found
        raise _qrm.InvalidInput(
            f"`{field}` = {value}: a config value must be a finite number (NaN and infinity "
            "are not settings; leave a field out for its default)"
        )
    return json.dumps(dict(config), allow_nan=False)


def _as_run(text: str) -> types.StudyRun:
    """A run's JSON as a `StudyRun`."""
    result: types.StudyRun = json.loads(text)
    # JSON has no tuples: the (x, y) points and (legend, values) groups become tuples, as typed
    for figure in result["report"]["figures"]:
        plot: Any = figure["plot"]
        if plot["kind"] == "lines":
            for line in plot["series"]:
                line["points"] = [tuple(p) for p in line["points"]]
        elif plot["kind"] == "histogram":
            plot["groups"] = [tuple(g) for g in plot["groups"]]
        elif plot["kind"] == "edc-scatter":
            plot["points"] = [tuple(p) for p in plot["points"]]
        elif plot["kind"] == "regions":
            plot["marks"] = [(list(at), label) for at, label in plot["marks"]]
        elif plot["kind"] == "site":
            plot["drive"] = [tuple(p) for p in plot["drive"]]
            for r in plot["runs"]:
                r["points"] = [tuple(p) for p in r["points"]]
        elif plot["kind"] == "reference-pair":
            plot["observed"] = [tuple(p) for p in plot["observed"]]
            plot["inferred"] = [tuple(p) for p in plot["inferred"]]
        elif plot["kind"] == "navigation" and plot["regions"] is not None:
            panel = plot["regions"]
            panel["marks"] = [(list(at), label) for at, label in panel["marks"]]
    # a binary file's bytes cross JSON as base64 text
    for a in result["report"]["attachments"]:
        data: Any = a["data"]
        if data is not None:
            a["data"] = base64.b64decode(data)
    return result


def table_frame(report: types.Report, name: str) -> Any:
    """A report's table `name` as a pandas DataFrame of its CSV fields (numbers in full); pandas
    is optional: without it this raises ImportError saying how to get it."""
    try:
        import pandas as pd  # type: ignore[import-untyped,unused-ignore]
    except ImportError as e:
        raise ImportError("qrm.studies.table_frame needs pandas (pip install pandas)") from e
    import io

    for t in report["tables"]:
        if t["name"] == name:
            shown = [i for i, c in enumerate(t["columns"]) if c["shown"] != "human-only"]
            header = [t["columns"][i]["key"] for i in shown]
            rows = [[row[i]["csv"] for i in shown] for row in t["rows"]]
            text = "\n".join(",".join(json.dumps(v) for v in r) for r in [header, *rows])
            return pd.read_csv(io.StringIO(text))
    names = [t["name"] for t in report["tables"]]
    raise KeyError(f"no table {name!r} in the report (tables: {names})")

"""qrm — qualitative relational maps for robots.

Calculi (`Calculus`; binary OPRA-m and STAR-m with exact tables: `BinaryCalculus`), probabilistic qualitative relational mapping (`Pqrm`), observation
files (`read_observations`) and the thesis's Monte Carlo study, sharded for distributed runs
(`monte_carlo_config`, `monte_carlo_shard`, `monte_carlo_aggregate`, `monte_carlo`); salient
region maps and learned calculi (`serge`, `SalientRegionMap`, `compose_cells`,
`serge_cross_validate`); navigation with Q-Link (`navigate`, `qlink_study`,
`qlink_field`); qualitative reasoning (`reason.close`, `reason.scenario`, `Pqrm.infer`,
`Pqrm.check`); every thesis study through one runner, as `qrm study` runs them
(`studies.available`, `studies.config`, `studies.run`), sharded over Ray or processes
(`distributed.run`).

Every error is a `QrmError`; the subclasses say what kind and are also the builtin a caller
would catch (`InvalidInput` is a `ValueError`, `IoError` an `OSError`; see the stubs).
The module is fork-safe: each process builds its own worker threads (`worker_threads()`), and a
call starts on the calling thread rather than waiting for a sleeping worker to wake.

Long calls (`qlink_study`, `qlink_field`, `compose_cells`, `serge_cross_validate`,
`monte_carlo_shard`) stop on Ctrl-C within a fraction of a second (raising
`KeyboardInterrupt`) and take `progress=`: a tqdm bar (or anything with `update(n)`) or a
callable `progress(done, total)`.
"""
from __future__ import annotations

import json
from typing import Any, Callable, Dict, List, Mapping, Optional, Protocol, Sequence, Tuple, Union, cast

from ._qrm import (
    BinaryAlgebra,
    BinaryCalculus,
    Calculus,
    DegenerateFrame,
    FormatError,
    InvalidInput,
    InvalidType,
    IoError,
    Pqrm,
    QrmError,
    SalientRegionMap,
    SpecError,
    UnsupportedError,
    __version__,
    builtin_names,
    layout_map,
    read_observations,
    single_observation,
    survey_agreement,
    worker_threads,
)
from . import _qrm, reason, sim, types

__all__ = [
    "BinaryAlgebra",
    "BinaryCalculus",
    "Calculus",
    "DegenerateFrame",
    "FormatError",
    "InvalidInput",
    "InvalidType",
    "IoError",
    "Pqrm",
    "Progress",
    "ProgressBar",
    "QrmError",
    "SalientRegionMap",
    "SpecError",
    "UnsupportedError",
    "__version__",
    "builtin_names",
    "distributed",
    "compose_cells",
    "layout_map",
    "monte_carlo",
    "monte_carlo_aggregate",
    "monte_carlo_config",
    "monte_carlo_shard",
    "navigate",
    "qlink_study",
    "qlink_field",
    "reason",
    "read_observations",
    "serge",
    "serge_cross_validate",
    "sim",
    "single_observation",
    "studies",
    "survey_agreement",
    "to_pandas",
    "types",
    "worker_threads",
]


class ProgressBar(Protocol):
    """What qrm needs of a progress bar — tqdm's has it: `update(n)` advances it by n. When
    the bar also has a `total` attribute, qrm sets it to the work's total as the work announces
    it (and calls `refresh()` if there is one)."""

    def update(self, n: int = 1) -> object: ...


Progress = Union[ProgressBar, Callable[[int, int], object]]
"""A `progress=` argument: a `ProgressBar` such as `tqdm.tqdm()`, or a callable
`progress(done, total)` called (with the interpreter held, about ten times a second at most)
when the count changes. An exception it raises stops the work and is raised by the call."""


def _progress_callback(progress: Optional[Progress]) -> Optional[Callable[[int, int], object]]:
    """The native module's `(done, total)` callback for a `progress=` argument."""
    if progress is None:
        return None
    update = getattr(progress, "update", None)
    if callable(update):
        bar = progress
        shown = [0]

        def report(done: int, total: int) -> None:
            if total and hasattr(bar, "total") and getattr(bar, "total") != total:
                setattr(bar, "total", total)
                refresh = getattr(bar, "refresh", None)
                if callable(refresh):
                    refresh()
            if done > shown[0]:
                update(done - shown[0])
                shown[0] = done

        return report
    if callable(progress):
        return progress
    raise InvalidInput(
        f"progress: expected a bar with update(n) such as tqdm.tqdm() or a callable "
        f"(done, total), got {type(progress).__name__}"
    )


def compose_cells(calculus: Calculus, *, progress: Optional[Progress] = None) -> Dict[str, Dict[str, List[str]]]:
    """The compose table of a learned (raster) calculus by Algorithm 3 over its cells (thesis
    §3.3.3), sound for every configuration: `table[r][s]` lists the states t with
    {DE:F} = r, {EF:G} = s ⇒ {DE:G} = t possible. A fine raster takes seconds; `progress`
    counts cells."""
    return _qrm.compose_cells(calculus, progress=_progress_callback(progress))


def monte_carlo_config(*, quick: bool = False, **overrides: Any) -> types.MonteCarloConfig:
    """The Monte Carlo study's settings (thesis §2.3.1) as a dict, with overrides.

    Keys: sigmas, trials, samples, landmarks, world, radius, step_deg, range, calculi, floor,
    detail_sigmas, seed.
    """
    config: Dict[str, Any] = json.loads(_qrm.monte_carlo_config(quick=quick))
    unknown = set(overrides) - set(config)
    if unknown:
        raise InvalidInput(f"unknown study settings: {sorted(unknown)}")
    config.update(overrides)
    return cast(types.MonteCarloConfig, config)


def monte_carlo_shard(
    config: Mapping[str, Any], start: int, count: int, *, progress: Optional[Progress] = None
) -> List[types.MonteCarloRecord]:
    """Runs trials start..start+count of every noise level; returns their records.

    Each trial is seeded by (seed, level, trial) alone, so shards can run anywhere (processes,
    a Ray cluster) and `monte_carlo_aggregate` of all shards equals one `monte_carlo` run.
    `progress` counts trials (one per level and trial).
    """
    records: List[types.MonteCarloRecord] = json.loads(
        _qrm.monte_carlo_shard(studies._config_json(config), start, count, progress=_progress_callback(progress))
    )
    return records


def monte_carlo_aggregate(
    config: Mapping[str, Any], shards: Sequence[Sequence[Mapping[str, Any]]]
) -> types.MonteCarloResult:
    """Merges shard records (any order) into the study result."""
    texts = [json.dumps([dict(r) for r in s]) for s in shards]
    result: types.MonteCarloResult = json.loads(_qrm.monte_carlo_aggregate(studies._config_json(config), texts))
    result["confusion"] = [(float(sigma), matrix) for sigma, matrix in result["confusion"]]
    return result


def monte_carlo(
    config: Optional[Mapping[str, Any]] = None, *, progress: Optional[Progress] = None
) -> types.MonteCarloResult:
    """The whole study in this process (all cores)."""
    config = config if config is not None else monte_carlo_config(quick=True)
    shard = monte_carlo_shard(config, 0, int(config["trials"]), progress=progress)
    return monte_carlo_aggregate(config, [shard])


def _plain(value: Any) -> Any:
    """NumPy arrays and tuples to lists, for the JSON hand-over to the native module."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def serge(
    beliefs: Union[str, Sequence[Mapping[str, Any]]],
    mu: int,
    *,
    sigma: float = 2.0,
    trials: Optional[int] = None,
    grid: int = 200,
    window: Optional[Tuple[float, float, float, float]] = None,
    seed: int = 0,
) -> SalientRegionMap:
    """A salient region map of `beliefs` (SERGE, thesis Algorithm 2).

    Each belief is `{"mean": [x, y], "cov": [[a, b], [b, c]]}` or `{"samples": (n, 2)}`
    (lists or NumPy arrays), or pass the whole JSON document `{"beliefs": [...]}` as a string.
    `mu` is the desired number of regions, `sigma` ≥ 0 how much saliency may buy fewer regions
    (0: exactly `mu`), `trials` defaults to 100·K. Deterministic for a seed.
    """
    if isinstance(beliefs, str):
        text = beliefs
    else:
        items = []
        for b in beliefs:
            unknown = set(b) - {"mean", "cov", "samples"}
            if unknown:
                raise InvalidInput(f"unknown belief keys {sorted(unknown)} (mean/cov or samples)")
            items.append({k: _plain(v) for k, v in b.items()})
        try:
            text = json.dumps({"beliefs": items}, allow_nan=False)
        except ValueError as e:
            raise InvalidInput(f"beliefs hold a non-finite number: {e}") from None
    return _qrm.serge_run(text, mu, sigma, trials, grid, window, seed)


def serge_cross_validate(
    dataset: str, *, quick: bool = True, seed: int = 0, progress: Optional[Progress] = None
) -> List[types.CvRecord]:
    """The thesis's 5-fold cross-validation study (§3.4) on `well-separated`, `hallway` or
    `lab`: one record per SERGE run (sweep, mu, sigma, fold, n_regions, train_log_saliency,
    test_log_likelihood, errors, points). `progress` counts SERGE runs."""
    records: List[types.CvRecord] = json.loads(
        _qrm.serge_cross_validate(dataset, quick, seed, progress=_progress_callback(progress))
    )
    return records


def navigate(
    positions: Mapping[int, Tuple[float, float]],
    start: int,
    goal: int,
    *,
    pqrm: Optional[Pqrm] = None,
    calculus: Union[None, str, Calculus] = None,
    range: float = 20.0,
    map_range: Optional[float] = None,
    beta: int = 1,
    controller: str = "arc",
    horizon: int = 4,
    replan: bool = True,
    exact_robot: bool = False,
    seed: int = 0,
) -> types.NavOutcome:
    """Q-Link from landmark `start` to landmark `goal` (thesis chapter 4).

    The world is point landmarks at `positions` seen within `range`. The map is `pqrm` (a
    probabilistic map you built) or, without it, the exact map of `calculus` (a name or a
    `Calculus`) that a robot of range `map_range` (default `range`) would record. Controllers:
    arc, midpoint-sweep, closest-point, safe-search, direct. Returns success, failure, plan_len,
    replans, length, transit_length, bound (Proposition 2), bound_direct (Proposition 4),
    trajectory and transitions.

    The robot errs as the thesis's would: detections with N(0, 0.3 m) noise, missed as often
    as a real camera misses a landmark in view, wheels that slip (the trajectory is what it
    drove); its draws come from `seed`. `exact_robot=True` is the idealised robot: true
    detections, waypoints driven exactly.
    """
    calc = Calculus.builtin(calculus) if isinstance(calculus, str) else calculus
    pos = {int(k): (float(v[0]), float(v[1])) for k, v in positions.items()}
    out: types.NavOutcome = json.loads(
        _qrm.navigate(pos, start, goal, pqrm=pqrm, calculus=calc, range=range, map_range=map_range,
                      beta=beta, controller=controller, horizon=horizon, replan=replan,
                      exact_robot=exact_robot, seed=seed)
    )
    return out


def qlink_field(
    *, quick: bool = True, trials: Optional[int] = None, seed: int = 0, progress: Optional[Progress] = None
) -> types.FieldExperiment:
    """The §4.4.2 field experiment in one world: a lidar-only hybrid map of the simulated
    field site and random start/goal trials for the thesis's set-up and its improvements.
    Returns `{"mapping", "draws", "variants", "trials"}` (success rates and failure causes
    per variant in "variants"). `progress` counts trials (the mapping drive comes first)."""
    if trials is not None and trials < 1:
        raise InvalidInput(f"trials = {trials}: at least 1")
    result: types.FieldExperiment = json.loads(_qrm.qlink_field(quick, trials, seed, progress=_progress_callback(progress)))
    for v in result["variants"]:
        v["by_plan_len"] = [(int(n), int(k), float(m)) for n, k, m in v["by_plan_len"]]
    return result


def qlink_study(
    trial: str = "all",
    *,
    quick: bool = True,
    pairs: Optional[int] = None,
    seed: int = 0,
    progress: Optional[Progress] = None,
    exact_robot: bool = False,
) -> types.QlinkStudy:
    """The §4.4.1 study (Table 4.1): `{"table": [...], "records": [...]}`. `pairs` is per main
    row, and at most as many in the rows of further sensing schedules and of ablations (whose
    `robot` names the errors removed). `progress` counts each world's map, a distance field per goal landmark
    and every navigation, its total known before the first. The navigating robot errs
    (N(0, 0.3 m) detections, missed ones, wheel slip) unless `exact_robot`."""
    result: types.QlinkStudy = json.loads(
        _qrm.qlink_study(trial, quick, pairs, seed, progress=_progress_callback(progress),
                         exact_robot=exact_robot)
    )
    return result


def to_pandas(table: Union[Sequence[Mapping[str, Any]], Mapping[str, Sequence[Any]], Pqrm]) -> Any:
    """A pandas DataFrame of a study's records (a list of dicts, one row each), of a table of
    columns (a dict of equal-length sequences) or of a map (`Pqrm.to_pandas`: one row per
    set). pandas is optional: without it this raises ImportError saying how to get it."""
    try:
        import pandas as pd  # type: ignore[import-untyped,unused-ignore]
    except ImportError as e:
        raise ImportError("qrm.to_pandas needs pandas (pip install pandas)") from e
    if isinstance(table, Pqrm):
        return table.to_pandas()
    if isinstance(table, Mapping):
        return pd.DataFrame(dict(table))
    return pd.DataFrame(list(table))


# Last: `studies` uses `_progress_callback` and `Progress` from above.
from . import distributed, studies  # noqa: E402

"""qrm — qualitative relational maps for robots.

Calculi (`Calculus`), probabilistic qualitative relational mapping (`Pqrm`), observation
files (`read_observations`) and the thesis's Monte Carlo study, sharded for distributed runs
(`monte_carlo_config`, `monte_carlo_shard`, `monte_carlo_aggregate`, `monte_carlo`).

Every error is a `QrmError`; the subclasses say what kind (see the hierarchy in the stubs).
"""
from __future__ import annotations

import json
from typing import Any, Dict, List, Optional, Sequence

from ._qrm import (
    Calculus,
    DegenerateFrame,
    FormatError,
    InvalidInput,
    IoError,
    Pqrm,
    QrmError,
    SpecError,
    UnsupportedError,
    __version__,
    builtin_names,
    read_observations,
    single_observation,
)
from . import _qrm, sim

__all__ = [
    "Calculus",
    "DegenerateFrame",
    "FormatError",
    "InvalidInput",
    "IoError",
    "Pqrm",
    "QrmError",
    "SpecError",
    "UnsupportedError",
    "__version__",
    "builtin_names",
    "monte_carlo",
    "monte_carlo_aggregate",
    "monte_carlo_config",
    "monte_carlo_shard",
    "read_observations",
    "sim",
    "single_observation",
]


def monte_carlo_config(*, quick: bool = False, **overrides: Any) -> Dict[str, Any]:
    """The Monte Carlo study's settings (thesis §2.3.1) as a dict, with overrides.

    Keys: sigmas, trials, samples, landmarks, world, radius, step_deg, range, calculi, floor,
    detail_sigmas, seed.
    """
    config: Dict[str, Any] = json.loads(_qrm.monte_carlo_config(quick=quick))
    unknown = set(overrides) - set(config)
    if unknown:
        raise InvalidInput(f"unknown study settings: {sorted(unknown)}")
    config.update(overrides)
    return config


def monte_carlo_shard(config: Dict[str, Any], start: int, count: int) -> List[Dict[str, Any]]:
    """Runs trials start..start+count of every noise level; returns their records.

    Each trial is seeded by (seed, level, trial) alone, so shards can run anywhere (processes,
    a Ray cluster) and `monte_carlo_aggregate` of all shards equals one `monte_carlo` run.
    """
    records: List[Dict[str, Any]] = json.loads(_qrm.monte_carlo_shard(json.dumps(config), start, count))
    return records


def monte_carlo_aggregate(config: Dict[str, Any], shards: Sequence[List[Dict[str, Any]]]) -> Dict[str, Any]:
    """Merges shard records (any order) into the study result."""
    texts = [json.dumps(s) for s in shards]
    result: Dict[str, Any] = json.loads(_qrm.monte_carlo_aggregate(json.dumps(config), texts))
    return result


def monte_carlo(config: Optional[Dict[str, Any]] = None) -> Dict[str, Any]:
    """The whole study in this process (all cores)."""
    config = config if config is not None else monte_carlo_config(quick=True)
    return monte_carlo_aggregate(config, [monte_carlo_shard(config, 0, int(config["trials"]))])

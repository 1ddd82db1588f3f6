"""The simulated world (sim2d): scenarios from the thesis, run from a seed.

>>> import qrm
>>> frames = qrm.sim.run("hallway", 1)
>>> frames[0]["xy"].shape[1]
2

`record` writes a recording as `qrm sim` does, for `qrm map` or `Pqrm` to read back.
"""
from __future__ import annotations

import os
from typing import List, Optional, Union

from . import _qrm
from .types import Frame

SCENARIOS = ("pqrm-100", "qlink-200", "hallway", "field")


def run(scenario: str, seed: int, *, lidar: bool = False) -> List[Frame]:
    """Runs a scenario; each frame is {"t", "pose", "ids", "xy", "cov"} (+ "angles", "ranges"
    with `lidar=True`), positions in the robot frame, ready for `Pqrm.update`."""
    return _qrm.simulate(scenario, seed, lidar=lidar)


def record(
    scenario: str,
    seed: int,
    out: Union[str, "os.PathLike[str]"],
    *,
    detector: str = "ideal",
    lidar: bool = True,
    landmark_radius: Optional[float] = None,
    world: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> List[str]:
    """Runs a scenario and writes the directory `qrm sim` writes — observations.csv (the
    mapper's input), truth.csv, world.toml, run.mcap (Foxglove), scenario.svg/png — whole or
    not at all. `detector`: "ideal" (ids known) or "lidar" (extracted from the scan,
    recognised by triangles; needs `lidar=True`). Returns the file names written."""
    return _qrm.sim_record(
        scenario,
        seed,
        out,
        detector=detector,
        lidar=lidar,
        landmark_radius=landmark_radius,
        world=world,
    )

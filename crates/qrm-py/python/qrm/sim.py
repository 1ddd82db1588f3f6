"""The simulated world (sim2d): scenarios from the thesis, run from a seed.

>>> import qrm
>>> frames = qrm.sim.run("hallway", 1)
>>> frames[0]["xy"].shape[1]
2
"""
from __future__ import annotations

from typing import List

from . import _qrm
from .types import Frame

SCENARIOS = ("pqrm-100", "qlink-200", "hallway", "field")


def run(scenario: str, seed: int, *, lidar: bool = False) -> List[Frame]:
    """Runs a scenario; each frame is {"t", "pose", "ids", "xy", "cov"} (+ "angles", "ranges"
    with `lidar=True`), positions in the robot frame, ready for `Pqrm.update`."""
    return _qrm.simulate(scenario, seed, lidar=lidar)

"""The shapes of the dicts qrm returns, for type checkers (`mypy --strict` accepts
`m.update(f["t"], f["ids"], f["xy"], f["cov"])` on a simulated frame).

They are ordinary dicts at run time; these `TypedDict`s only say which keys they have and
what each holds.
"""
from __future__ import annotations

from typing import Dict, List, Tuple, TypedDict

import numpy as np
import numpy.typing as npt

__all__ = ["Frame", "MapMetrics", "Observations", "Truth", "UpdateReport"]


class Observations(TypedDict):
    """One time step of a recording (`read_observations`), in the robot frame."""

    t: float
    robot: int
    ids: npt.NDArray[np.int64]
    """landmark ids, shape (n,)"""
    xy: npt.NDArray[np.float64]
    """positions (m), shape (n, 2)"""
    cov: npt.NDArray[np.float64]
    """covariances [cxx, cxy, cyy] (m²), shape (n, 3)"""


class _FrameBase(TypedDict):
    t: float
    pose: Tuple[float, float, float]
    """the true pose (x, y, θ) in the world"""
    ids: npt.NDArray[np.int64]
    xy: npt.NDArray[np.float64]
    cov: npt.NDArray[np.float64]


class Frame(_FrameBase, total=False):
    """One simulated frame (`qrm.sim.run`); `angles` and `ranges` with `lidar=True`."""

    angles: npt.NDArray[np.float64]
    ranges: npt.NDArray[np.float64]
    """metres; inf = no return"""


class UpdateReport(TypedDict):
    """What one `Pqrm.update` did."""

    observed: int
    new: int
    conflicts: int


class MapMetrics(TypedDict):
    """A map scored against surveyed positions (`Pqrm.metrics`)."""

    n_sets: int
    n_scored: int
    mean_entropy: float
    normalized_entropy: float
    error_rate: float
    mean_neighbor_distance: float
    p_ml_mean: float
    top_n_error: List[float]
    confusion: List[List[int]]


Truth = Dict[int, Tuple[float, float]]
"""Surveyed positions: landmark id → (x, y)."""

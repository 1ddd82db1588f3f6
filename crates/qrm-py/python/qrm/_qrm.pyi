"""Type stubs of the native module `qrm._qrm` (import `qrm`, not this)."""
from typing import Union, Dict, List, Optional, Tuple, final

import numpy as np
import numpy.typing as npt

from .types import Frame, MapMetrics, Observations, UpdateReport

__version__: str
__all__ = [
    "QrmError",
    "InvalidInput",
    "DegenerateFrame",
    "SpecError",
    "UnsupportedError",
    "FormatError",
    "IoError",
    "Calculus",
    "BinaryCalculus",
    "Pqrm",
    "read_observations",
    "single_observation",
    "monte_carlo_shard",
    "monte_carlo_aggregate",
    "monte_carlo_config",
    "builtin_names",
    "simulate",
    "SalientRegionMap",
    "serge_run",
    "serge_cross_validate",
    "compose_cells",
    "navigate",
    "qlink_study",
    "qlink_field",
    "worker_threads",
    "reason_close",
    "reason_scenario",
    "reason_close_binary",
    "__version__",
]

class QrmError(Exception):
    """Base class of every qrm error."""

class InvalidInput(QrmError, ValueError):
    """Bad numbers, shapes, covariances or settings."""

class DegenerateFrame(InvalidInput):
    """Coincident reference points or landmarks."""

class SpecError(QrmError, ValueError):
    """A calculus spec or name that is not valid."""

class UnsupportedError(QrmError, NotImplementedError):
    """An operation the calculus does not define."""

class FormatError(QrmError, ValueError):
    """A malformed saved map or input file."""

class IoError(QrmError, OSError):
    """A file that cannot be read or written."""

def builtin_names() -> List[str]: ...
def reason_close(calculus: Calculus, network: str, *, general_position: bool = False) -> str: ...
def reason_scenario(
    calculus: Calculus, network: str, *, general_position: bool = False, max_nodes: int = 100000
) -> str: ...
def reason_close_binary(
    calculus: BinaryCalculus, constraints: List[Tuple[str, str, List[str]]]
) -> str: ...
def worker_threads() -> int:
    """Worker threads of this process's (fork-safe) thread pool."""

@final
class Calculus:
    @staticmethod
    def builtin(name: str) -> Calculus: ...
    @staticmethod
    def from_spec(path: str) -> Calculus: ...
    @staticmethod
    def from_spec_text(text: str, *, format: str = "toml") -> Calculus: ...
    @property
    def name(self) -> str: ...
    @property
    def frame(self) -> str: ...
    @property
    def labels(self) -> List[str]: ...
    @property
    def n_states(self) -> int: ...
    @property
    def max_entropy(self) -> float: ...
    def classify(self, points: npt.ArrayLike, *, out: Optional[npt.NDArray[np.int64]] = None) -> npt.NDArray[np.int64]: ...
    def classify_labels(self, points: npt.ArrayLike) -> List[str]: ...
    def neighbours(self) -> Dict[str, object]: ...
    def compose(self, *, generic: bool = False) -> Dict[str, Dict[str, List[str]]]: ...
    def permute(self, op: str, *, generic: bool = False) -> Dict[str, List[str]]: ...
    def merge_map(self, coarse: Calculus) -> npt.NDArray[np.int64]: ...
    def spec_toml(self) -> str: ...
    def render_svg(self, *, width: int = 640) -> str: ...

@final
class BinaryCalculus:
    """A binary point calculus (opra-M, star-m) with exact converse and composition."""
    @staticmethod
    def builtin(name: str) -> BinaryCalculus: ...
    @property
    def name(self) -> str: ...
    @property
    def labels(self) -> List[str]: ...
    @property
    def n_states(self) -> int: ...
    def classify(self, points: npt.ArrayLike) -> npt.NDArray[np.int64]: ...
    def compose(self) -> Dict[str, Dict[str, List[str]]]: ...
    def converse(self) -> Dict[str, List[str]]: ...
    def neighbours(self) -> Dict[str, object]: ...
    def render_svg(self, *, width: int = 640) -> str: ...

@final
class Pqrm:
    def __new__(
        cls,
        calculus: Calculus,
        *,
        samples: int = 1000,
        floor: float = 1.0,
        orderings: str = "all",
        seed: int = 0,
        sensor: str = "gaussian",
        temper: float = 1.0,
    ) -> Pqrm: ...
    def update(
        self,
        t: float,
        ids: npt.ArrayLike,
        xy: npt.ArrayLike,
        cov: npt.ArrayLike,
        *,
        robot: int = 0,
    ) -> UpdateReport: ...
    def belief(self, set: Tuple[int, int, int]) -> Optional[npt.NDArray[np.float64]]: ...
    def entropy(self) -> Optional[float]: ...
    def sets(self) -> List[Tuple[int, int, int]]: ...
    @property
    def calculus(self) -> Calculus: ...
    def metrics(self, truth: Dict[int, Tuple[float, float]]) -> MapMetrics: ...
    def merge(self, other: Pqrm) -> None: ...
    def save(self, path: str) -> None: ...
    @staticmethod
    def load(path: str) -> Pqrm: ...
    def to_json(self) -> str: ...
    def infer(
        self,
        set: Tuple[int, int, int],
        *,
        fusion: str = "fitted",
        epsilon: float = 0.01,
        rounds: int = 1,
    ) -> Dict[str, object]: ...
    def check(self) -> Dict[str, object]: ...
    def __len__(self) -> int: ...

def read_observations(
    path: str,
    format: str,
    *,
    sigma_range: float = 0.15,
    sigma_bearing: float = 0.01,
    topic: Optional[Union[str, List[str]]] = None,
    range_max: Optional[float] = None,
    allow_truncated: bool = False,
) -> Tuple[List[Observations], Optional[Dict[int, Tuple[float, float]]]]: ...
def single_observation(
    calculus: Calculus,
    points: npt.ArrayLike,
    cov: npt.ArrayLike,
    *,
    samples: int = 1000,
    floor: float = 0.0,
    seed: int = 0,
) -> npt.NDArray[np.float64]: ...
def monte_carlo_shard(config: str, start: int, count: int) -> str: ...
def monte_carlo_aggregate(config: str, shards: List[str]) -> str: ...
def monte_carlo_config(*, quick: bool = False) -> str: ...
def simulate(scenario: str, seed: int, *, lidar: bool = False) -> List[Frame]: ...

@final
class SalientRegionMap:
    @property
    def n_regions(self) -> int: ...
    @property
    def assignment(self) -> List[int]: ...
    @property
    def saliency(self) -> List[float]: ...
    @property
    def log_saliency(self) -> float: ...
    @property
    def log_phi(self) -> float: ...
    @property
    def initial_regions(self) -> int: ...
    @property
    def window(self) -> Tuple[float, float, float, float]: ...
    def cells(self) -> npt.NDArray[np.int64]: ...
    def region_of(self, points: npt.ArrayLike) -> npt.NDArray[np.int64]: ...
    def adjacency(self) -> List[Tuple[int, int, int]]: ...
    def polygons(self, r: int) -> List[List[Tuple[float, float]]]: ...
    def to_json(self) -> str: ...
    def to_calculus(self, name: str = "learned", description: str = "") -> Calculus: ...

def serge_run(
    beliefs_json: str,
    mu: int,
    sigma: float,
    trials: Optional[int],
    grid: int,
    window: Optional[Tuple[float, float, float, float]],
    seed: int,
) -> SalientRegionMap: ...
def serge_cross_validate(dataset: str, quick: bool, seed: int) -> str: ...
def compose_cells(calculus: Calculus) -> Dict[str, Dict[str, List[str]]]: ...
def navigate(
    positions: Dict[int, Tuple[float, float]],
    start: int,
    goal: int,
    *,
    pqrm: Optional[Pqrm] = None,
    calculus: Optional[Calculus] = None,
    range: float = 20.0,
    map_range: Optional[float] = None,
    beta: int = 1,
    controller: str = "arc",
    horizon: int = 4,
    replan: bool = True,
) -> str: ...
def qlink_study(trial: str, quick: bool, pairs: Optional[int], seed: int) -> str: ...
def qlink_field(quick: bool, trials: Optional[int], seed: int) -> str: ...

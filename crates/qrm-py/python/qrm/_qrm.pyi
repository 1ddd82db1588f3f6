"""Type stubs of the native module `qrm._qrm` (import `qrm`, not this)."""
import os
from typing import Any, Callable, Union, Dict, List, Optional, Tuple, final

import numpy as np
import numpy.typing as npt

from .types import ConsistencyCheck, Frame, Inference, LayoutFit, MapMetrics, Neighbours, Observations, SurveyAgreement, UpdateReport

_Callback = Optional[Callable[[int, int], object]]

__version__: str
__all__ = [
    "QrmError",
    "InvalidInput",
    "DegenerateFrame",
    "InvalidType",
    "SpecError",
    "UnsupportedError",
    "FormatError",
    "IoError",
    "Calculus",
    "BinaryCalculus",
    "Pqrm",
    "read_observations",
    "survey_agreement",
    "layout_map",
    "single_observation",
    "monte_carlo_shard",
    "monte_carlo_aggregate",
    "monte_carlo_config",
    "builtin_names",
    "simulate",
    "sim_record",
    "SalientRegionMap",
    "serge_run",
    "serge_cross_validate",
    "compose_cells",
    "navigate",
    "qlink_study",
    "qlink_field",
    "studies_list",
    "studies_config",
    "studies_run",
    "studies_shards",
    "studies_run_shard",
    "studies_aggregate",
    "studies_save",
    "worker_threads",
    "_on_caller_thread",
    "reason_close",
    "reason_scenario",
    "reason_close_binary",
    "BinaryAlgebra",
    "reason_solve_binary",
    "reason_read_csp",
    "__version__",
]

class QrmError(Exception):
    """Base class of every qrm error."""

class InvalidInput(QrmError, ValueError):
    """Bad numbers, shapes, covariances or settings."""

class DegenerateFrame(InvalidInput):
    """Coincident reference points or landmarks."""

class InvalidType(InvalidInput, TypeError):
    """An argument of a type or dtype qrm does not take (also a TypeError)."""

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
    calculus: Union[BinaryCalculus, BinaryAlgebra], constraints: List[Tuple[str, str, List[str]]]
) -> str: ...
def reason_solve_binary(
    calculus: Union[BinaryCalculus, BinaryAlgebra],
    constraints: List[Tuple[str, str, List[str]]],
    *,
    max_nodes: int = 1000000,
    split_path: Optional[str] = None,
    split_sets: Optional[List[List[str]]] = None,
    restarts: bool = True,
) -> str: ...
def reason_read_csp(calculus: Union[BinaryCalculus, BinaryAlgebra], text: str) -> str: ...
def worker_threads() -> int:
    """Worker threads of this process's (fork-safe) thread pool."""
def _on_caller_thread() -> bool:
    """Whether a call's work starts on the calling thread (as worker 0 of a pool of its own)
    rather than being handed to a worker (for tests and diagnostics)."""

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
    def classify_columns(
        self,
        ax: npt.ArrayLike,
        ay: npt.ArrayLike,
        bx: npt.ArrayLike,
        by: npt.ArrayLike,
        cx: npt.ArrayLike,
        cy: npt.ArrayLike,
        *,
        out: Optional[npt.NDArray[np.int64]] = None,
    ) -> npt.NDArray[np.int64]: ...
    def classify_labels(self, points: npt.ArrayLike) -> List[str]: ...
    def neighbours(self) -> Neighbours: ...
    def compose(self, *, generic: bool = False) -> Dict[str, Dict[str, List[str]]]: ...
    def permute(self, op: str, *, generic: bool = False) -> Dict[str, List[str]]: ...
    def merge_map(self, coarse: Calculus) -> npt.NDArray[np.int64]: ...
    def spec_toml(self) -> str: ...
    def render_svg(self, *, width: int = 640) -> str: ...
    def _repr_svg_(self) -> str: ...
    def __reduce__(self) -> Tuple[Callable[..., Calculus], Tuple[str]]: ...

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
    def neighbours(self) -> Neighbours: ...
    def render_svg(self, *, width: int = 640) -> str: ...
    def _repr_svg_(self) -> str: ...
    def __reduce__(self) -> Tuple[Callable[..., BinaryCalculus], Tuple[str]]: ...

@final
class BinaryAlgebra:
    """A binary calculus's reasoning tables, derived or read from GQR's or SparQ's files."""
    @staticmethod
    def from_gqr(path: Union[str, os.PathLike[str]]) -> BinaryAlgebra: ...
    @staticmethod
    def from_sparq(path: Union[str, os.PathLike[str]]) -> BinaryAlgebra: ...
    @staticmethod
    def from_gqr_tables(
        name: str, converse: str, composition: str, identity: str, weights: Optional[str] = None
    ) -> BinaryAlgebra: ...
    @staticmethod
    def of(calculus: BinaryCalculus) -> BinaryAlgebra: ...
    @property
    def name(self) -> str: ...
    @property
    def labels(self) -> List[str]: ...
    @property
    def n_states(self) -> int: ...
    @property
    def identity(self) -> Optional[str]: ...
    def laws(self) -> List[Tuple[str, Optional[bool], Optional[str]]]: ...
    def to_gqr_tables(self) -> Tuple[str, str, str, str]: ...
    def __reduce__(
        self,
    ) -> Tuple[Callable[..., BinaryAlgebra], Tuple[str, str, str, str, str]]: ...

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
        evidence: str = "shared",
    ) -> Pqrm: ...
    @property
    def evidence(self) -> str: ...
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
    @staticmethod
    def from_json(text: str) -> Pqrm: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: bytes) -> Pqrm: ...
    def __reduce__(self) -> Tuple[Callable[..., Pqrm], Tuple[bytes]]: ...
    def columns(self) -> Dict[str, npt.NDArray[Any]]: ...
    def to_pandas(self) -> Any: ...
    def _repr_svg_(self) -> str: ...
    def infer(
        self,
        set: Tuple[int, int, int],
        *,
        fusion: str = "fitted",
        epsilon: float = 0.01,
        rounds: int = 1,
        composition: str = "learned",
    ) -> Inference: ...
    def check(self) -> ConsistencyCheck: ...
    def __len__(self) -> int: ...

def read_observations(
    path: str,
    format: str,
    *,
    sigma_range: Optional[float] = None,
    sigma_bearing: Optional[float] = None,
    noise: Optional[str] = None,
    gate: Optional[bool] = None,
    topic: Optional[Union[str, List[str]]] = None,
    range_max: Optional[float] = None,
    allow_truncated: bool = False,
) -> Tuple[List[Observations], Optional[Dict[int, Tuple[float, float]]]]: ...
def survey_agreement(
    scans: List[Observations],
    survey: Dict[int, Tuple[float, float]],
    *,
    off: float = 0.1,
    min_frames: int = 5,
) -> SurveyAgreement: ...
def layout_map(
    calculus: Calculus,
    scans: List[Observations],
    *,
    orderings: str = "all",
    seed: int = 0,
) -> Tuple[Pqrm, LayoutFit]: ...
def single_observation(
    calculus: Calculus,
    points: npt.ArrayLike,
    cov: npt.ArrayLike,
    *,
    samples: int = 1000,
    floor: float = 0.0,
    seed: int = 0,
) -> npt.NDArray[np.float64]: ...
def monte_carlo_shard(config: str, start: int, count: int, progress: _Callback = None) -> str: ...
def monte_carlo_aggregate(config: str, shards: List[str]) -> str: ...
def monte_carlo_config(*, quick: bool = False) -> str: ...
def simulate(scenario: str, seed: int, *, lidar: bool = False) -> List[Frame]: ...
def sim_record(
    scenario: str,
    seed: int,
    out: Union[str, os.PathLike[str]],
    *,
    detector: str = "ideal",
    lidar: bool = True,
    landmark_radius: Optional[float] = None,
    world: Optional[Union[str, os.PathLike[str]]] = None,
) -> List[str]: ...

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
    @staticmethod
    def _from_state(state: str, initial_regions: int) -> SalientRegionMap: ...
    def __reduce__(self) -> Tuple[Callable[..., SalientRegionMap], Tuple[str, int]]: ...

def serge_run(
    beliefs_json: str,
    mu: int,
    sigma: float,
    trials: Optional[int],
    grid: int,
    window: Optional[Tuple[float, float, float, float]],
    seed: int,
) -> SalientRegionMap: ...
def serge_cross_validate(dataset: str, quick: bool, seed: int, progress: _Callback = None) -> str: ...
def compose_cells(calculus: Calculus, progress: _Callback = None) -> Dict[str, Dict[str, List[str]]]: ...
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
    exact_robot: bool = False,
    seed: int = 0,
) -> str: ...
def qlink_study(
    trial: str, quick: bool, pairs: Optional[int], seed: int, progress: _Callback = None, exact_robot: bool = False
) -> str: ...
def qlink_field(quick: bool, trials: Optional[int], seed: int, progress: _Callback = None) -> str: ...
def studies_list() -> List[Tuple[str, str]]: ...
def studies_config(name: str, full: bool, seed: Optional[int] = None) -> str: ...
def studies_run(
    name: str, config: Optional[str], quick: bool, seed: Optional[int] = None, progress: _Callback = None
) -> str: ...
def studies_shards(name: str, config: str) -> int: ...
def studies_run_shard(name: str, config: str, index: int, progress: _Callback = None) -> str: ...
def studies_aggregate(name: str, config: str, shards: List[Tuple[int, str]]) -> str: ...
def studies_save(name: str, config: str, output: str, out: Union[str, os.PathLike[str]]) -> List[str]: ...

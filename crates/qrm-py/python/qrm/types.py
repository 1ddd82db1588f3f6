"""The shapes of the dicts qrm returns, for type checkers (`mypy --strict` accepts
`m.update(f["t"], f["ids"], f["xy"], f["cov"])` on a simulated frame, and rejects a
misspelt key of a study result).

They are ordinary dicts at run time (JSON-like: they pickle, `qrm.to_pandas` takes their
record lists); these `TypedDict`s only say which keys they have and what each holds. The
test suite checks every result's keys against them.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Dict, List, Literal, Optional, Tuple, TypedDict, Union

if TYPE_CHECKING:  # Python 3.10+; annotations are not evaluated at run time here
    from typing import TypeAlias

import numpy as np
import numpy.typing as npt

__all__ = [
    "Assumptions",
    "BoundCheck",
    "ConsistencyCheck",
    "CvRecord",
    "FieldExperiment",
    "FieldMapping",
    "FieldResult",
    "FieldSummary",
    "FieldTrial",
    "FlaggedEntry",
    "Frame",
    "Inference",
    "LevelSummary",
    "MapMetrics",
    "MeanStd",
    "MonteCarloBaseline",
    "MonteCarloConfig",
    "MonteCarloRecord",
    "MonteCarloResult",
    "NavFailure",
    "NavStranded",
    "NavOutcome",
    "Neighbours",
    "Observations",
    "QlinkRecord",
    "QlinkStudy",
    "QlinkTableRow",
    "LayoutFit",
    "LayoutLandmark",
    "RobotAblation",
    "Schedule",
    "SurveyAgreement",
    "TaskDraws",
    "TransitionRecord",
    "TrialMetrics",
    "Truth",
    "UpdateReport",
    "WrongTriplet",
]


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


class LayoutLandmark(TypedDict):
    """One landmark of a recording's layout (`layout_map`)."""

    position: Tuple[float, float]
    """where the frames put it (m), in its component's frame"""
    sightings: int
    """frames (of three or more landmarks) that saw it"""
    component: int
    """landmarks linked by frames that saw them together share a component"""
    sigma_shared: float
    """the error its frames share beyond the layout (m, as a pair's distance)"""


class LayoutFit(TypedDict):
    """A recording's layout and the error its frames share beyond it (`layout_map`)."""

    sigma_shared: float
    """the recording's shared error (m, as a landmark pair's distance)"""
    sigma_frame: float
    """one frame's spread of a pair's distance (m)"""
    pairs: int
    """landmark pairs seen together in at least 5 frames"""
    rounds: int
    """rounds of alignment the fit took"""
    converged: bool
    """whether the fit stopped because nothing moved"""
    landmarks: Dict[int, LayoutLandmark]


class SurveyAgreement(TypedDict):
    """Landmark pairs the survey disagrees with the frames on (`survey_agreement`)."""

    pairs_seen: int
    """pairs of surveyed landmarks seen together in at least `min_frames` scans"""
    off: List[Tuple[int, int, float, int]]
    """(a, b, median of distance seen − surveyed (m), frames), a < b, in order"""


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


class Neighbours(TypedDict):
    """A calculus's neighbour graph (`Calculus.neighbours`, `BinaryCalculus.neighbours`)."""

    states: List[str]
    adjacent: List[Tuple[str, str]]
    """pairs of states that touch"""
    distance: List[List[int]]
    """hops between states, in the order of `states`"""


class Inference(TypedDict):
    """A relation inferred by composition (`Pqrm.infer`)."""

    p: npt.NDArray[np.float64]
    """the inferred distribution over the calculus's states"""
    paths: int
    """composition paths fused"""
    via: List[int]
    """the landmarks the paths went through"""
    round: int
    """the inference round that gave it (1: from observed sets only)"""
    alpha: float
    """the fusion's weight"""
    composition: str
    """how composition entries shared a path's probability ("learned" or "uniform")"""
    base_rate: bool
    """whether the pool divided the base rate out of each path and counted it once"""


class FlaggedEntry(TypedDict):
    """A map entry whose most likely state closure contradicts."""

    set: List[int]
    state: str
    p: float


class ConsistencyCheck(TypedDict):
    """The consistency check of the most likely states (`Pqrm.check`)."""

    sets: int
    consistent: bool
    contradiction: Optional[str]
    """why closure failed, None when it did not"""
    flagged: List[FlaggedEntry]
    closures: int


# --- PQRM: the Monte Carlo study (thesis §2.3.1) ---------------------------------------


class MonteCarloConfig(TypedDict):
    """The study's settings (`qrm.monte_carlo_config`)."""

    sigmas: List[float]
    """range noise levels σ_r (m)"""
    trials: int
    samples: int
    landmarks: int
    world: float
    radius: float
    step_deg: float
    range: float
    calculi: List[str]
    """the first is the finest; the others are its merges"""
    floor: float
    detail_sigmas: List[float]
    seed: int


class TrialMetrics(MapMetrics):
    """One calculus's map after one trial."""

    neighbor_histogram: List[int]


class WrongTriplet(TypedDict):
    """A set whose most likely state is not the true one."""

    sigma_r: float
    x: float
    y: float
    d_ab: float
    truth: str
    ml: str


class MonteCarloRecord(TypedDict):
    """One trial of one noise level (`qrm.monte_carlo_shard`); `metrics` per calculus, None
    for a trial that saw no landmark set."""

    level: int
    trial: int
    metrics: Optional[List[TrialMetrics]]
    wrong: List[WrongTriplet]


class MeanStd(TypedDict):
    mean: float
    std: float


class LevelSummary(TypedDict):
    """One calculus at one noise level, over the trials."""

    calculus: str
    sigma_r: float
    sigma_n: float
    trials: int
    n_sets: MeanStd
    mean_entropy: MeanStd
    normalized_entropy: MeanStd
    error_rate: MeanStd
    p_ml: MeanStd
    neighbor_distance: MeanStd


class MonteCarloBaseline(TypedDict):
    """What a uniform belief would score."""

    error_rate: float
    mean_neighbor_distance: float
    p_ml: float
    top_n_error: List[float]
    entropy: float


class MonteCarloResult(TypedDict):
    """The study (`qrm.monte_carlo`, `qrm.monte_carlo_aggregate`)."""

    config: MonteCarloConfig
    levels: List[LevelSummary]
    baselines: Dict[str, MonteCarloBaseline]
    confusion: List[Tuple[float, List[List[int]]]]
    """(detail σ_r, confusion matrix [true][most likely]) of the finest calculus"""
    wrong: List[WrongTriplet]


# --- SERGE: cross-validation (thesis §3.4) ---------------------------------------------


class CvRecord(TypedDict):
    """One SERGE run of the cross-validation study (`qrm.serge_cross_validate`)."""

    sweep: Literal["mu", "sigma"]
    mu: int
    sigma: float
    fold: int
    n_regions: int
    train_log_saliency: float
    test_log_likelihood: float
    errors: int
    points: int


# --- Q-Link (thesis chapter 4) ---------------------------------------------------------

# A Union of one-value Literals (not one Literal of three) so that the run-time object is a
# `typing.Union`, as stubtest expects of an alias it sees as a union.
NavFailure: TypeAlias = Union[Literal["no-start"], Literal["no-path"], Literal["insufficient-features"]]
NavStranded: TypeAlias = Union[
    Literal["no-element-in-view"], Literal["no-path-left"], Literal["replan-budget"]
]
"""What a run that failed for insufficient features was left without after its last
contingency: no map element in view (even after the localisation circle), no path to the goal
once the failed links are excluded, or the re-plan budget spent."""
"""Why a navigation failed."""


TransitionRecord = TypedDict(
    "TransitionRecord",
    {
        "from": int,
        "to": int,
        "link": int,
        "commands": List[int],
        "success": bool,
        "length": float,
        "end": List[float],
    },
)
"""One transition of a navigation: plan element `from` to `to` through `link` (the
functional form because `from` is a Python keyword)."""


class NavOutcome(TypedDict):
    """One navigation (`qrm.navigate`)."""

    success: bool
    failure: Optional[NavFailure]
    plan_len: int
    replans: int
    stranded: Optional[NavStranded]
    length: float
    transit_length: float
    bound: float
    """Proposition 2's bound (2π + 1)·R·|P| (m)"""
    bound_direct: float
    """Proposition 4's bound R·|P| (m)"""
    trajectory: List[List[float]]
    transitions: List[TransitionRecord]
    plan: List[int]
    """the first plan's map elements"""
    searches: List[List[int]]
    """[first, last) trajectory indices of each search"""


class Schedule(TypedDict):
    """When the robot senses (`"continuous"` or `{"at-stops": {"degrees": d}}`) and how many
    fallback circles it may drive."""

    sensing: Union[str, Dict[str, Dict[str, float]]]
    fallbacks: int


RobotAblation: TypeAlias = Union[
    Literal["full"],
    Literal["exact"],
    Literal["without-misses"],
    Literal["without-detection-noise"],
    Literal["without-false-reports"],
    Literal["without-motion-noise"],
    Literal["motion-only"],
]
"""Which of the navigating robot's errors a row of the §4.4.1 study keeps."""


class QlinkRecord(TypedDict):
    """One navigation of the §4.4.1 study."""

    trial: Literal["sensor-range", "occlusion"]
    value: float
    """R'/R (sensor-range) or the landmark size in m (occlusion)"""
    schedule: Schedule
    robot: RobotAblation
    """the full robot, or one with some errors removed (the ablation rows)"""
    start: int
    goal: int
    plan_len: int
    success: bool
    failure: Optional[NavFailure]
    length: float
    transit_length: float
    bound: float
    bound_direct: float


class QlinkTableRow(TypedDict):
    """One row of Table 4.1."""

    trial: Literal["sensor-range", "occlusion"]
    value: float
    schedule: Schedule
    robot: RobotAblation
    pairs: int
    no_path: int
    failures: int
    failure_rate: float
    over_bound: int
    """successes whose transitions exceed Proposition 2's bound"""
    over_bound_trajectory: int
    """successes whose whole trajectory exceeds it (the thesis's Fig 4.7 reading)"""
    mean_length: float


class QlinkStudy(TypedDict):
    """The §4.4.1 study (`qrm.qlink_study`)."""

    table: List[QlinkTableRow]
    records: List[QlinkRecord]


class FieldMapping(TypedDict):
    """What the lidar-only mapping drive of the field experiment saw and built."""

    frames: int
    detections: int
    aliased_detections: int
    mapped_ids: int
    real_landmarks: int
    false_landmarks: int
    world_landmarks: int
    point_elements: int
    wall_elements: int
    wall_frames: int
    wall_frame_error: float
    """mean distance (m) of the walls' frame points as the scans placed them from the truth"""
    ground_share: float
    """share of the drive's lidar rays that met the pitched ground"""
    effective_range: float


class TaskDraws(TypedDict):
    """How the random start/goal tasks were drawn: kept, and why others were not."""

    kept: int
    no_start: int
    no_path: int
    trivial: int
    blocked: int
    wanted: int
    """pairs asked for: more than `kept` when the map was too sparse to find them all"""


FieldResult: TypeAlias = Union[
    Literal["success"],
    Literal["perceptual-aliasing"],
    Literal["insufficient-features"],
    Literal["insufficient-features-and-aliasing"],
    Literal["no-path"],
]
"""A field trial's outcome, by cause."""


class Assumptions(TypedDict):
    """Which assumptions of Propositions 2 and 4 a run meets."""

    disc: bool
    """A1 (i): every element's landmarks in a disc of radius R"""
    circle: bool
    """A1 (ii) + A2: a drivable circle of radius R about every link, sensing it"""
    pairwise: bool
    """A3 (i): landmarks pairwise within R"""
    sight_lines: bool
    """A3 (ii): sight of both along the line between any two"""
    straight: bool
    """A4: straight drives between landmarks"""


class BoundCheck(TypedDict):
    """Both distance bounds of one run at one R."""

    range: float
    transitions: int
    length: float
    prop2: float
    prop4: float
    assumptions: Assumptions


class FieldTrial(TypedDict):
    """One field trial (`qrm.qlink_field`)."""

    variant: str
    trial: int
    start: List[float]
    goal: int
    result: FieldResult
    plan_len: int
    replans: int
    stranded: Optional[NavStranded]
    length: float
    final_distance: float
    transit_length: float
    ground_share: float
    """share of the trial's lidar rays that met the pitched ground"""
    final_ground_share: float
    """the same over its last 20 scans"""
    bounds: List[BoundCheck]
    """at the lidar's range and at the effective range"""


class FieldSummary(TypedDict):
    """One variant's success rate and failure causes."""

    variant: str
    trials: int
    no_path: int
    successes: int
    success_rate: float
    perceptual_aliasing: int
    insufficient_features: int
    insufficient_features_and_aliasing: int
    replanned_successes: int
    mean_length: float
    by_plan_len: List[Tuple[int, int, float]]
    """Table 4.2: (|P|, successful paths, mean trajectory length in m)"""


class FieldExperiment(TypedDict):
    """The field experiment in one world (`qrm.qlink_field`)."""

    mapping: FieldMapping
    draws: TaskDraws
    variants: List[FieldSummary]
    trials: List[FieldTrial]


# --- studies (`qrm.studies`): the report every study returns --------------------------------

StudyVerdict: TypeAlias = Union[
    Literal["agree"],
    Literal["disagree"],
    Literal["holds"],
    Literal["violated"],
    Literal["not-judged"],
]


class ReportClaim(TypedDict):
    """One thing the thesis says, what we measured, and the computed verdict."""

    what: str
    thesis: str
    ours: str
    verdict: StudyVerdict
    why: str


class ReportCell(TypedDict):
    """A table cell: its CSV field (full precision, empty when missing) and its text."""

    csv: str
    text: str


class ReportColumn(TypedDict):
    """A table column: CSV key, heading, and where it is shown."""

    key: str
    heading: str
    shown: Union[Literal["everywhere"], Literal["csv-only"], Literal["human-only"]]


class ReportTable(TypedDict):
    """A table defined once (`name` is its CSV's stem)."""

    name: str
    title: str
    caption: str
    columns: List[ReportColumn]
    rows: List[List[ReportCell]]
    in_report: bool


class ReportLine(TypedDict):
    """A series of a line chart."""

    name: str
    points: List[Tuple[float, float]]
    err: Optional[List[float]]
    reference: bool


class HistogramPlot(TypedDict):
    """Histograms over shared bin edges."""

    kind: Literal["histogram"]
    edges: List[float]
    groups: List[Tuple[str, List[float]]]


class LinesPlot(TypedDict):
    """Lines."""

    kind: Literal["lines"]
    series: List[ReportLine]


class EdcScatterPlot(TypedDict):
    """Points `(x, y, value)` in a ternary calculus's normalised frame (thesis Fig 2.8)."""

    kind: Literal["edc-scatter"]
    points: List[Tuple[float, float, float]]
    colour_label: str


class HeatmapPlot(TypedDict):
    """A labelled matrix of counts (a confusion matrix)."""

    kind: Literal["heatmap"]
    labels: List[str]
    matrix: List[List[int]]


class RegionsPlot(TypedDict):
    """A window partitioned into regions cell by cell, row by row (a salient region map, a
    raster calculus; thesis Figs 3.8-3.10), with data points, shaded cells and marks."""

    kind: Literal["regions"]
    window: List[float]
    nx: int
    ny: int
    cell_region: List[int]
    points: List[List[float]]
    shade: Optional[List[bool]]
    marks: List[Tuple[List[float], str]]
    numbers: bool


class SiteRun(TypedDict):
    """A run drawn on a site: its path and whether it reached its goal."""

    points: List[Tuple[float, float]]
    reached: bool


class SitePlot(TypedDict):
    """A simulated site from above (a sim2d world spec: bounds, landmark, wall, clutter), the
    mapping drive and runs over it (thesis Fig 4.9)."""

    kind: Literal["site"]
    world: Dict[str, Any]
    drive: List[Tuple[float, float]]
    runs: List[SiteRun]


class ReferencePairPlot(TypedDict):
    """Every landmark in the normalised frame of one reference pair, `(x, y, p)` with p the
    probability of the true state: sets observed with the pair, and sets inferred (the
    reasoning study)."""

    kind: Literal["reference-pair"]
    observed: List[Tuple[float, float, float]]
    inferred: List[Tuple[float, float, float]]


class RegionsPanel(TypedDict):
    """A calculus's regions on a grid over its normalised frame (A = (0, 0), B = (1, 0)), row
    by row, drawn beside another picture."""

    title: str
    window: List[float]
    nx: int
    ny: int
    cell_region: List[int]
    marks: List[Tuple[List[float], str]]


class NavigationPlot(TypedDict):
    """One navigation over a simulated site (the demo's picture): the mapping drive, the
    trajectory with the index ranges `[from, to]` spent searching, the first plan's elements as
    triangles of landmark positions, the links found, start and goal, and the learned
    calculus's regions beside it."""

    kind: Literal["navigation"]
    world: Dict[str, Any]
    drive: List[List[float]]
    trajectory: List[List[float]]
    searches: List[List[int]]
    plan: List[List[List[float]]]
    links: List[List[float]]
    start: List[float]
    goal: List[float]
    regions: Optional[RegionsPanel]


class ReportFigure(TypedDict):
    """A figure's data (the CLI draws it as SVG and PNG)."""

    name: str
    title: str
    x_label: str
    y_label: str
    plot: Union[
        HistogramPlot,
        LinesPlot,
        EdcScatterPlot,
        HeatmapPlot,
        RegionsPlot,
        SitePlot,
        ReferencePairPlot,
        NavigationPlot,
    ]


class ReportAttachment(TypedDict):
    """A file a study produces beside its tables and figures (`name` is its path under the
    output directory): a text file's `text`, or a binary file's `data` (the demo's `run.mcap`;
    `None` for a text file)."""

    name: str
    text: str
    data: Optional[bytes]


class Report(TypedDict):
    """What a study says about a run (`qrm.studies.run(...)["report"]`)."""

    title: str
    setup: str
    tables: List[ReportTable]
    claims: List[ReportClaim]
    figures: List[ReportFigure]
    notes: str
    attachments: List[ReportAttachment]


class StudyRun(TypedDict):
    """A run of `qrm.studies.run`: the config it ran, its output (the study's records and
    summaries) and its report."""

    study: str
    config: Dict[str, Any]
    output: Dict[str, Any]
    report: Report

"""Plan, evaluate and check minimum-jerk trajectories of the triquint 3-PUU
translational parallel robot.

Cartesian inputs are in millimetres unless ``units="m"``; everything a
``Plan`` returns is SI (m, m/s, m/s², m/s³, N·m, s), like the plan file.
"""

import os
from typing import Any, Callable, Dict, List, Literal, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
PLAN_FORMAT: str
"""The plan file's format tag, ``"triquint-plan/1"``."""

_ArrayLike = npt.ArrayLike
_Array = npt.NDArray[np.float64]
_Units = Literal["mm", "m"]
_Objective = Literal["min-max-jerk", "min-time"]
_Knots = Literal["fixed", "free"]
_PathLike = Union[str, "os.PathLike[str]"]

class TriquintError(Exception):
    """Base class of every error triquint raises."""

class InvalidJobError(TriquintError, ValueError):
    """A malformed job; NaN input raises it."""

    field: str
    """The field as in a job file: ``limits.jerk``, ``path.points``, ``robot.lead``, ``objective``."""
    reason: str

class JobFileError(TriquintError, ValueError):
    """A job file that cannot be read or parsed."""

    origin: str
    line: Optional[int]
    """1-based line of the error, when known."""
    reason: str

class OutsideWorkspaceError(TriquintError, ValueError):
    """A point the robot cannot reach (or joints with no valid pose)."""

    index: int
    """0-based index of the point (of the knot when ``kind == 'knot'``)."""
    point: Tuple[float, float, float]
    """The point in the caller's units (millimetres for job files)."""
    kind: Literal["via-point", "knot", "position", "joints"]
    position_m: Tuple[float, float, float]
    reason: str

class InfeasibleError(TriquintError):
    """A valid job that no plan satisfies."""

    limit: Literal[
        "velocity", "acceleration", "jerk", "torque", "total_time", "max_deviation_mm", "travel"
    ]
    """The binding limit."""
    unit: str
    limit_value: float
    reached: float
    """Best value of the binding quantity found (in ``unit``: SI, mm for the last two)."""
    shortest_total_time: Optional[float]
    """Shortest total time (s) that meets every limit, or None."""
    segment: int
    """With ``limit == 'travel'`` only: the 0-based segment that leaves the travel."""
    axis: int
    """With ``limit == 'travel'`` only: the 0-based slider."""

class UnstreamableError(TriquintError):
    """A plan within every limit that would not stream to the default drives
    (docs/protocol.md, Streamability): use fewer points or a longer total time."""

    first: int
    """0-based first segment of the run too short to stream."""
    last: int
    """0-based last segment of that run (a queue's worth less one)."""
    run_s: float
    """How long the run lasts (s)."""
    need_s: float
    """The look-ahead plus refill delay the drives must hold ahead (s)."""
    capacity: int
    """The drives' queue capacity (segments)."""

class CancelledError(TriquintError):
    """The progress callable returned False (``reason == 'observer'``)."""

    reason: Literal["observer", "time-budget", "other"]

class SolverError(TriquintError):
    """The numerical solver failed on a valid job (worth a report)."""

class PlanFileError(TriquintError, ValueError):
    """Text that is not a usable plan file."""

    kind: Literal["json", "format", "invalid"]

class InternalError(TriquintError):
    """A defect inside triquint (a caught Rust panic)."""

class Robot:
    """Geometry and inertia of the machine, SI units; defaults: the paper's Table 1."""

    platform_radius: float
    """s (m)."""
    base_radius: float
    """S (m)."""
    strut_length: float
    """l (m)."""
    slider_offset: float
    """d (m)."""
    platform_mass: float
    """m_p (kg)."""
    payload_mass: float
    """Extra mass on the platform (kg)."""
    strut_mass: float
    """m_i (kg)."""
    slider_mass: float
    """m_qi (kg)."""
    motor_inertia: float
    """I_M (kg m²)."""
    coupling_inertia: float
    """I_C (kg m²)."""
    leadscrew_inertia: float
    """I_L (kg m²)."""
    lead: float
    """p: slider travel per motor turn (m)."""
    gravity: float
    """g (m/s², along -z)."""
    def __init__(
        self,
        *,
        platform_radius: float = 0.070,
        base_radius: float = 0.370,
        strut_length: float = 0.450,
        slider_offset: float = 0.070,
        platform_mass: float = 3.5,
        payload_mass: float = 0.0,
        strut_mass: float = 0.72,
        slider_mass: float = 1.377,
        motor_inertia: float = 1.4e-4,
        coupling_inertia: float = 1.3e-5,
        leadscrew_inertia: float = 1.1e-4,
        lead: float = 0.010,
        gravity: float = 9.807,
    ) -> None: ...
    def to_dict(self) -> Dict[str, float]: ...
    @classmethod
    def from_dict(cls, fields: Dict[str, float]) -> "Robot": ...

class Machine:
    """A machine file (docs/machine.md): robot, homing, axes, travel, ceilings."""

    def __init__(self) -> None: ...
    @classmethod
    def from_toml(cls, path: _PathLike) -> "Machine":
        """Reads a machine file, as ``--machine`` does."""
    @classmethod
    def from_text(cls, text: str) -> "Machine":
        """A machine file's contents."""
    @property
    def robot(self) -> Robot: ...
    @property
    def travel(self) -> Dict[str, List[float]]:
        """{'min': [...], 'max': [...]}, metres."""
    @property
    def ceilings(self) -> Dict[str, float]:
        """velocity, acceleration, jerk, torque: what no plan may exceed."""
    @property
    def counts_per_metre(self) -> List[float]:
        """Encoder counts per metre of slider travel, per axis (signed)."""

class Job:
    """A planning job, validated when it is made."""

    def __init__(
        self,
        points: _ArrayLike,
        *,
        units: _Units = "mm",
        objective: _Objective = "min-max-jerk",
        knots: _Knots = "fixed",
        knot_segments: Optional[int] = None,
        max_deviation_mm: Optional[float] = None,
        total_time: float = 5.0,
        velocity: float = 0.5,
        acceleration: float = 1.2,
        jerk: float = 5.0,
        torque: float = 10.0,
        robot: Optional[Robot] = None,
        machine: Optional[Machine] = None,
        shaper: Union[str, Dict[str, Any], None] = None,
    ) -> None: ...
    @classmethod
    def from_toml(cls, path: _PathLike, *, machine: Optional[Machine] = None) -> "Job":
        """Reads a job file of ``triquint plan``."""
    @property
    def objective(self) -> _Objective: ...
    @property
    def knot_placement(self) -> _Knots: ...
    @property
    def points(self) -> _Array:
        """Via-points (n, 3), metres."""
    @property
    def knots(self) -> _Array:
        """Cartesian knots (k + 1, 3), metres: the via-points, with straight-line points for fewer than five."""
    @property
    def limits(self) -> Dict[str, float]: ...
    @property
    def robot(self) -> Robot: ...

class Progress:
    """A snapshot of a running search."""

    elapsed: float
    """Seconds since planning started."""
    stage: Literal["searching", "limits-bind", "min-time", "finishing"]
    lp_solves: int
    best_max_jerk: Optional[float]
    """Best max |jerk| (m/s³) of any start so far."""

class State:
    """Joint motion at one time ((3,) each) or m times ((m, 3) each)."""

    q: _Array
    """Position (m)."""
    v: _Array
    """Velocity (m/s)."""
    a: _Array
    """Acceleration (m/s²)."""
    jerk: _Array
    """Jerk (m/s³)."""

class Samples:
    """An evenly spaced sampling of a plan."""

    t: _Array
    """Times (n,), s: 0, dt, 2 dt, ... and the end time."""
    q: _Array
    v: _Array
    a: _Array
    jerk: _Array
    torque: _Array
    """Motor torques (n, 3), N·m."""
    platform: _Array
    """Platform position (n, 3), m, by forward kinematics."""
    def __len__(self) -> int: ...

class Segments:
    """Segment start times, durations and quintic coefficients."""

    t0: _Array
    """(k,), s."""
    durations: _Array
    """(k,), s."""
    coeffs: _Array
    """(k, 3, 6): joint j of segment i is sum_p coeffs[i, j, p] u**p, u in [0, durations[i]]."""
    def __len__(self) -> int: ...

class Plan:
    """A planned trajectory: the CLI's plan file (``triquint-plan/1``), SI units."""

    @property
    def duration(self) -> float:
        """Total duration (s)."""
    @property
    def format(self) -> str: ...
    @property
    def objective(self) -> _Objective: ...
    @property
    def robot(self) -> Robot: ...
    @property
    def limits(self) -> Dict[str, float]: ...
    @property
    def shaper(self) -> Optional[Dict[str, Any]]:
        """The input shaper (type, frequency_hz, damping, duration_s), or None."""
    @property
    def via_points(self) -> _Array:
        """(n, 3), metres."""
    @property
    def knots(self) -> _Array:
        """Joint positions q (k + 1, 3), metres, at the segment boundaries."""
    @property
    def free_knots(self) -> List[int]:
        """Indices into ``knots`` of the knots the planner chose (``knots="free"``); empty otherwise."""
    @property
    def path_deviation(self) -> Dict[str, float]:
        """'max' (m, sampled), 'at' (s), 'bound' (m, Lipschitz bound between samples), 'step' (s):
        the platform's largest distance from the straight segments between via-points."""
    @property
    def segments(self) -> Segments: ...
    @property
    def max_abs(self) -> Dict[str, _Array]:
        """'velocity', 'acceleration', 'jerk', 'torque' → per-joint maxima (3,), SI."""
    @property
    def solver(self) -> Dict[str, Union[int, float]]: ...
    def at(self, t: Union[float, _ArrayLike]) -> State:
        """Joint motion at plan time t (s): a number gives (3,) arrays, shape (m,) gives (m, 3)."""
    def sample(self, dt: float) -> Samples:
        """Samples every dt seconds and at the end time."""
    def check(self) -> List[Dict[str, Any]]:
        """The checks of ``triquint check``: dicts of what, value, bound, ok."""
    def to_json(self) -> str:
        """The plan file's text."""
    @classmethod
    def from_json(cls, text: str) -> "Plan": ...
    @classmethod
    def load(cls, path: _PathLike) -> "Plan":
        """Reads a plan file (at most 16 MiB); OSError if unreadable, PlanFileError if not a plan."""
    def save(self, path: _PathLike) -> None:
        """Writes the plan file through an exclusive temporary renamed into place;
        OSError for a target that is not a regular file (device, FIFO, folder, symbolic link)."""

def plan(
    points: Union[_ArrayLike, Job],
    *,
    units: _Units = "mm",
    objective: _Objective = "min-max-jerk",
    knots: _Knots = "fixed",
    knot_segments: Optional[int] = None,
    max_deviation_mm: Optional[float] = None,
    total_time: float = 5.0,
    velocity: float = 0.5,
    acceleration: float = 1.2,
    jerk: float = 5.0,
    torque: float = 10.0,
    robot: Optional[Robot] = None,
    machine: Optional[Machine] = None,
    shaper: Union[str, Dict[str, Any], None] = None,
    starts: int = 8,
    seed: int = 1,
    progress: Optional[Callable[[Progress], Optional[bool]]] = None,
) -> Plan:
    """Plans a globally min-max-jerk (or minimum-time) trajectory through via-points.

    With a Job, only ``starts``, ``seed`` and ``progress`` may be given.
    ``starts`` is 1 to 1000 (ValueError otherwise), as the CLI's ``--starts``.
    """

def ik(
    x: Union[float, _ArrayLike],
    y: Optional[float] = None,
    z: Optional[float] = None,
    *,
    units: _Units = "mm",
    robot: Optional[Robot] = None,
) -> _Array:
    """Slider positions for platform positions: (3,) or (n, 3); millimetres unless units='m'."""

def fk(
    q1: Union[float, _ArrayLike],
    q2: Optional[float] = None,
    q3: Optional[float] = None,
    *,
    units: _Units = "mm",
    robot: Optional[Robot] = None,
) -> _Array:
    """Platform positions for slider positions: (3,) or (n, 3); millimetres unless units='m'."""

def torque(
    q: _ArrayLike,
    qd: _ArrayLike,
    qdd: _ArrayLike,
    *,
    robot: Optional[Robot] = None,
) -> _Array:
    """Motor torques (N·m) for joint positions, velocities and accelerations (SI)."""

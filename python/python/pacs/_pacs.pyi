"""Type stubs of the extension module (see the docstrings at runtime for the details).

Units: m, s, rad, rad/s, rad/s², kg, J. Arrays are numpy float64 (anything numpy.asarray
accepts is converted); every error is a pacs.Error subclass.
"""

import os
from typing import Any, Literal, Mapping, Sequence, TypedDict

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
PathLike = str | os.PathLike[str]
RobotArg = str | os.PathLike[str] | Mapping[str, Any]
ModelArg = str | Mapping[str, Any]

class Progress(TypedDict):
    chunk: int  # serial of the chunk the commands follow (0: the start's standstill)
    passed: int  # its executed actions passed so far
    executed: int  # h of that chunk
    accepted: int  # chunks accepted so far

class Command:
    """The command of one safety step (for time `t`)."""
    @property
    def t(self) -> float: ...  # s
    @property
    def q(self) -> npt.NDArray[np.float64]: ...  # rad, (dof,)
    @property
    def dq(self) -> npt.NDArray[np.float64]: ...  # rad/s, (dof,)
    @property
    def ddq(self) -> npt.NDArray[np.float64]: ...  # rad/s², (dof,)
    @property
    def verified(self) -> bool: ...
    @property
    def on_failsafe(self) -> bool: ...
    @property
    def binding(self) -> dict[str, Any]: ...  # {"kind": "none" | "no-measurement" | "ssm" | ...}
    @property
    def min_separation(self) -> float: ...  # m (inf where not computed: no human, some unverified steps)
    @property
    def contact_energy(self) -> float: ...  # J
    @property
    def contact_threshold(self) -> float: ...  # J
    @property
    def path_speed(self) -> float: ...  # 1 = intended timing, 0 = stopped
    @property
    def stop_time(self) -> float: ...  # s
    @property
    def chunk(self) -> int: ...
    @property
    def passed(self) -> int: ...
    def to_dict(self) -> dict[str, Any]: ...

class Shield:
    def __init__(
        self,
        robot: RobotArg | None = "fr3",
        humans: ModelArg | Sequence[ModelArg] | None = "default",
        constraints: ModelArg | None = "sorting",
        objects: Sequence[Mapping[str, Any]] | None = None,
        environment: Sequence[Mapping[str, Any]] | None = None,
        config: Mapping[str, Any] | None = None,
        side: PathLike | None = None,
        log: PathLike | None = None,
    ) -> None: ...
    def start(self, t: float, q: ArrayLike) -> None: ...
    def set_chunk(
        self, deltas: ArrayLike, t: float, h: int | None = None, absolute: bool | None = False
    ) -> int: ...
    def measure(
        self,
        t_meas: float,
        positions: ArrayLike,
        velocities: ArrayLike | None = None,
        human: str | int | None = None,
    ) -> None: ...
    def measure_object(
        self, id: str | int, t_meas: float, position: ArrayLike, velocity: ArrayLike | None = None
    ) -> None: ...
    def step(self, t: float) -> Command: ...
    def progress(self) -> Progress: ...
    @property
    def remaining(self) -> float | None: ...  # s
    @property
    def dof(self) -> int: ...
    @property
    def safety_step(self) -> float: ...  # s
    @property
    def time(self) -> float: ...  # s
    @property
    def humans(self) -> int: ...
    @property
    def keypoints(self) -> list[int]: ...
    @property
    def object_ids(self) -> list[str]: ...
    @property
    def header(self) -> dict[str, Any]: ...
    def close(self) -> None: ...
    def __enter__(self) -> "Shield": ...
    def __exit__(self, *args: Any) -> bool: ...

class ShieldLoop:
    def __init__(
        self,
        shield: Shield,
        realtime: bool | None = True,
        history: int | None = 10000,
        priority: int | None = None,  # SCHED_FIFO 1..99 for the loop thread (Linux)
    ) -> None: ...
    def start(self) -> None: ...
    def run_until(self, t: float) -> None: ...
    def stop(self) -> None: ...
    def set_chunk(
        self, deltas: ArrayLike, t: float | None = None, h: int | None = None, absolute: bool = False
    ) -> int: ...
    def measure(
        self,
        t_meas: float,
        positions: ArrayLike,
        velocities: ArrayLike | None = None,
        human: str | int | None = None,
    ) -> None: ...
    def measure_object(
        self, id: str | int, t_meas: float, position: ArrayLike, velocity: ArrayLike | None = None
    ) -> None: ...
    def latest(self) -> Command | None: ...
    @property
    def time(self) -> float: ...
    def progress(self) -> Progress: ...
    def commands(self) -> dict[str, npt.NDArray[Any]]: ...  # t, q, dq, ddq, verified
    def stats(
        self,
    ) -> dict[str, int | float | str]: ...  # steps, overruns, rt_priority (int); max_step_us, mean_step_us, max_late_us (µs); rt_priority_error (str, if refused)
    def __enter__(self) -> "ShieldLoop": ...
    def __exit__(self, *args: Any) -> bool: ...

class Run:
    @property
    def log(self) -> str: ...
    @property
    def verdict(self) -> Literal["pass", "fail", "inconclusive"]: ...
    @property
    def passed(self) -> bool: ...
    @property
    def violations(self) -> list[dict[str, Any]]: ...
    @property
    def inconclusive(self) -> list[dict[str, Any]]: ...
    @property
    def metrics(self) -> dict[str, Any]: ...
    @property
    def models(self) -> dict[str, Any]: ...
    @property
    def meta(self) -> dict[str, Any]: ...
    @property
    def people(self) -> list[str]: ...
    @property
    def evidence(self) -> dict[str, Any]: ...
    @property
    def episodes(self) -> list[dict[str, Any]]: ...
    def to_dict(self) -> dict[str, Any]: ...

def audit(
    paths: PathLike | Sequence[PathLike],
    config: Mapping[str, Any] | PathLike | None = None,
    header: Mapping[str, Any] | PathLike | None = None,
) -> list[Run]: ...
def report(runs: Sequence[Run], out_dir: PathLike) -> Literal["pass", "fail", "inconclusive"]: ...
def robot_spec(robot: RobotArg, side: PathLike | None = None) -> dict[str, Any]: ...

# pacs.fleet's Rust side (use pacs.fleet.audit / pacs.simulate).
def _run_from_state(state: bytes) -> Run: ...
def _fleet_logs(paths: PathLike | Sequence[PathLike]) -> list[str]: ...
def _takes_header(path: PathLike) -> bool: ...
def _fleet_report(runs: Sequence[Run]) -> dict[str, Any]: ...
def _simulate_check(
    tasks: Sequence[str], methods: Sequence[str], with_human: bool, chunk_motion: str, policy: str
) -> None: ...
def _simulate_rollouts(
    tasks: Sequence[str],
    methods: Sequence[str],
    seed: int,
    rollouts: int,
    with_human: bool,
    chunk_motion: str,
    policy: str,
    log_dir: PathLike | None = None,
    threads: int | None = None,
) -> bytes: ...
def _simulate_external(
    policy: Any,
    tasks: Sequence[str],
    methods: Sequence[str],
    seeds: Sequence[int],
    with_human: bool,
    chunk_motion: str,
    log_dir: str | None = None,
) -> bytes: ...
def _tolerance(
    policy: Any,
    task: str,
    method: str,
    seeds: Sequence[int],
    at: Sequence[float],
    holds: Sequence[float],
    progress: Any = None,
) -> dict[str, Any]: ...
def _simulate_merge(parts: Sequence[bytes]) -> dict[str, Any]: ...

class LogWriter:
    def __init__(
        self,
        path: PathLike,
        robot: RobotArg | None = "fr3",
        human: ModelArg | None = "default",
        constraints: ModelArg | None = "sorting",
        objects: Sequence[Mapping[str, Any]] | None = None,
        environment: Sequence[Mapping[str, Any]] | None = None,
        side: PathLike | None = None,
        meta: Mapping[str, Any] | None = None,
    ) -> None: ...
    def robot(
        self, t: float, q: ArrayLike, dq: ArrayLike | None = None, ddq: ArrayLike | None = None
    ) -> None: ...
    def human(
        self, t: float, t_meas: float, positions: ArrayLike, person: int | str | None = None
    ) -> None: ...
    def object(
        self, t: float, t_meas: float, id: str, position: ArrayLike, velocity: ArrayLike | None = None
    ) -> None: ...
    def event(self, t: float, name: str) -> None: ...
    def close(self) -> None: ...
    @property
    def path(self) -> str: ...
    def __enter__(self) -> "LogWriter": ...
    def __exit__(self, *args: Any) -> bool: ...

def teleop_demonstrations(
    task: str = "sorting", count: int = 50, seed: int = 0, fps: float = 30.0
) -> list[dict[str, Any]]: ...

def paced_replay(
    q: npt.ArrayLike,
    fps: float = 30.0,
    pauses: Sequence[tuple[float, float]] = ...,
    slows: Sequence[tuple[float, float, float]] = ...,
) -> dict[str, npt.NDArray[np.float64]]: ...

def replay_event(
    end_s: float,
    k: int,
    seed: int,
    hold: tuple[float, float] | None = None,
    pace: tuple[float, float] | None = None,
) -> dict[str, list[tuple[float, ...]]]: ...

class Demo:
    def __init__(
        self, task: str | None = "sorting", seed: int | None = 0, with_human: bool | None = True
    ) -> None: ...
    @property
    def task(self) -> str: ...
    @property
    def start(self) -> npt.NDArray[np.float64]: ...
    @property
    def max_time(self) -> float: ...
    @property
    def goals(self) -> list[dict[str, Any]]: ...
    def shield_args(self) -> dict[str, Any]: ...
    def chunk(self, q: ArrayLike) -> tuple[npt.NDArray[np.float64], int]: ...
    def keypoints(self, t: float) -> npt.NDArray[np.float64]: ...
    @property
    def object_ids(self) -> list[str]: ...
    def object_state(self, i: int, t: float) -> tuple[list[float], list[float]]: ...
    def tool_point(self, q: ArrayLike) -> list[float]: ...
    def deviation(self, q: ArrayLike) -> float: ...

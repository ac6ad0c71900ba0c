"""pacs — path-consistent safety filtering for chunking robot policies.

Put the PACS shield between a policy (diffusion policy, VLA, LeRobot) and a robot arm, and
audit logged runs against ISO/TS 15066 SSM and PFL:

>>> import numpy as np, pacs
>>> shield = pacs.Shield(robot="fr3", humans="default", constraints="sorting")
>>> demo = pacs.Demo("sorting")
>>> shield.start(0.0, demo.start)
>>> shield.measure(0.0, demo.keypoints(0.0))
>>> deltas, h = demo.chunk(demo.start)
>>> shield.set_chunk(deltas, t=0.0, h=h)
1
>>> cmd = shield.step(0.0)
>>> cmd.verified, cmd.q.shape
(True, (7,))

Units everywhere: m, s, rad, rad/s, rad/s², kg, J.

- :class:`Shield`: the shield (``start``, ``set_chunk``, ``measure``, ``measure_object``,
  ``step`` → :class:`Command`);
- :class:`ShieldLoop`: its 1 kHz step loop on a Rust thread;
- :func:`audit`, :class:`Run`, :class:`LogWriter`, :func:`report`: the offline audit;
- :class:`Demo`: the simulation's FR3 tasks and their demonstration policy;
  :func:`teleop_demonstrations`: demonstrations of those tasks with the variety of human
  teleoperation (pauses, changes of pace, hesitations near people, detours), for training;
- :mod:`pacs.fleet`: a fleet's archive audited in parallel, locally or on Dask
  (:func:`pacs.fleet.audit`), and :func:`simulate`, the simulation's evaluation (also on Dask);
- :func:`tolerance`: does a policy still succeed when PACS slows or stops it along its path
  (also ``python -m pacs tolerance``)?
- :mod:`pacs.lerobot`: adapters for LeRobot-style policies, robots and processor pipelines;
- :mod:`pacs.errors`: the exceptions (all subclasses of :class:`Error`).
"""

from . import errors
from .errors import (
    ArgumentTypeError,
    ChunkRejected,
    Error,
    InputError,
    NotStartedError,
    OutputError,
)
from ._pacs import (
    Command,
    Demo,
    LogWriter,
    Run,
    Shield,
    ShieldLoop,
    __version__,
    audit,
    report,
    robot_spec,
    teleop_demonstrations,
    paced_replay,
)
from . import fleet
from .fleet import simulate
from ._tolerance import tolerance

__all__ = [
    "Shield",
    "Command",
    "ShieldLoop",
    "audit",
    "Run",
    "LogWriter",
    "report",
    "robot_spec",
    "Demo",
    "teleop_demonstrations",
    "paced_replay",
    "fleet",
    "simulate",
    "tolerance",
    "errors",
    "__version__",
    *errors.__all__,
]

"""Adapters between pacs and LeRobot-style policy loops.

LeRobot's interfaces (lerobot ≥ 0.4; checked against 0.6): a policy (``PreTrainedPolicy``) has
``predict_action_chunk(batch) -> (B, chunk_size, action_dim)`` and ``select_action(batch) ->
(B, action_dim)`` and ``reset()``; a robot (``Robot``) has ``get_observation() -> dict`` and
``send_action(action: dict) -> dict`` with joint keys such as ``"shoulder_pan.pos"`` (SO-100/101:
degrees); a robot-side processor step (``RobotActionProcessorStep``) maps a ``RobotAction`` dict to
a ``RobotAction`` dict and is registered with ``ProcessorStepRegistry.register(name)``. These
adapters use only those names, so they work with LeRobot's classes and with anything shaped
like them (lerobot itself is optional: it pulls torch).

- :class:`ShieldedPolicyLoop`: policy → chunks → shield (1 kHz) → ``robot.send_action``, in real
  time or in simulated time; tells which actions of each chunk were executed (and the left-over
  actions real-time chunking needs).
- Observation history: policies that stack several past observations (LeRobot's
  ``DiffusionPolicy`` with ``n_obs_steps`` > 1, VQ-BeT, TD-MPC, multi-task DiT) keep them in
  ``policy._queues``, which only their ``select_action`` fills. The loop fills them itself on
  every tick, the way ``select_action`` does (LeRobot's ``populate_queues``: the first
  observation repeated to the queue's length, then one per tick), so ``predict_action_chunk``
  sees the last ``n_obs_steps`` observations; policies without observation queues (ACT) are
  called with the current observation alone. Run the loop at the policy's training frame rate
  (``fps``): one observation per tick is one frame of history.
- :func:`write_dataset`: demonstrations (:func:`pacs.teleop_demonstrations`) written as a
  LeRobot dataset (``LeRobotDataset.create`` / ``add_frame`` / ``save_episode``), the training
  data of a LeRobot policy; :func:`environment_state` is its ``observation.environment_state``.
- :func:`paced_replays`: a dataset transform: each demonstration also replayed along its own
  path with the braking, holding, slowing and resuming profiles PACS uses, so a policy learns
  that being slowed or stopped on its path is in distribution.
- :class:`SimulationPolicy`: a LeRobot policy as the simulation's policy
  (``pacs.simulate(policy=SimulationPolicy(...))``): OFF / PACS / single-action / CBF
  rollouts of a learned policy on the built-in scenes, scored against the true people.
- :class:`ShieldActionStep`: a ``RobotActionProcessorStep``-style step for a LeRobot robot
  pipeline: every action the pipeline passes goes through a running :class:`pacs.ShieldLoop`,
  and the robot receives the shield's command instead.

Units: the shield works in rad, rad/s, s; ``unit="deg"`` converts robot/policy values in
degrees (LeRobot's SO-100/101 default) in and out. Keys not listed in ``joint_keys`` (e.g. a
gripper) pass through unchanged.
"""

from __future__ import annotations

import math
import time
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from ._pacs import Shield, ShieldLoop
from .errors import ArgumentTypeError, ChunkRejected, InputError, NotStartedError

__all__ = [
    "ObservationHistory",
    "ShieldedPolicyLoop",
    "ShieldActionStep",
    "environment_state",
    "normalization_stats",
    "STATE_SPAN",
    "ENVIRONMENT_STATE_SPAN",
    "write_dataset",
    "paced_replays",
    "SimulationPolicy",
    "to_numpy",
    "chunk_array",
]

_UNITS = {"rad": 1.0, "deg": math.pi / 180.0}


def _scale(unit: str) -> float:
    if unit not in _UNITS:
        raise InputError(f"unit: unknown unit {unit!r} (rad, deg)")
    return _UNITS[unit]


def to_numpy(x: Any) -> np.ndarray:
    """A float64 numpy array of a torch tensor (any device), numpy array or nested list."""
    if hasattr(x, "detach"):  # torch.Tensor
        x = x.detach().to("cpu").numpy()
    try:
        return np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ArgumentTypeError(f"expected an array of numbers, got {type(x).__name__}: {e}") from e


def chunk_array(x: Any) -> np.ndarray:
    """A policy's action chunk for one observation as an (H, A) array: (1, H, A) batch-major,
    as most LeRobot policies return it, or (H, 1, A) time-major, as TD-MPC's planner does
    (LeRobot's own ``select_action`` takes its actions along the first axis); (H, A) as is.
    The adapters always pass a batch of one observation, so the batch axis is the one of
    length 1 (a (1, 1, A) chunk is one action either way)."""
    a = to_numpy(x)
    if a.ndim == 3:
        if a.shape[0] == 1:
            a = a[0]
        elif a.shape[1] == 1:
            a = a[:, 0]
        else:
            raise InputError(
                f"policy: action chunk of shape {a.shape} for one observation: expected "
                "(1, H, A) or, time-major, (H, 1, A)"
            )
    if a.ndim != 2:
        raise InputError(
            f"policy: action chunk of shape {a.shape}, expected (H, A), (1, H, A) or (H, 1, A)"
        )
    return a


def _populate_queues(queues: Any, batch: Mapping[str, Any]) -> None:
    """LeRobot's ``populate_queues`` rule (lerobot.policies.utils, 0.4-0.6), in place: every key
    of ``batch`` that has a queue enters it; an empty (just reset) queue is filled to its length
    with copies of the first observation."""
    for key, value in batch.items():
        if key not in queues:
            continue
        q = queues[key]
        if q.maxlen is None:
            raise InputError(f"policy._queues[{key!r}]: an observation queue without a length")
        q.append(value)
        while len(q) < q.maxlen:  # just reset: the first observation fills the history
            q.append(value)


class ObservationHistory:
    """Feeds a LeRobot policy's observation queues (``policy._queues``: a dict of deques of
    length ``n_obs_steps``, one per observation key, plus the action queue) with one
    observation per call, exactly as the policy's own ``select_action`` does before it predicts:
    camera images stacked under ``observation.images`` (or the first one as
    ``observation.image``) when the policy queues them that way, the action key never queued.
    A policy without such queues (ACT, or any non-LeRobot policy) is left alone.

    ``feed(batch)`` returns the batch to pass to ``predict_action_chunk`` (the one with the
    stacked images, which LeRobot's ``predict_action_chunk`` reads its queue keys from).
    """

    OBS_IMAGES = "observation.images"
    OBS_IMAGE = "observation.image"
    ACTION = "action"

    def __init__(self, policy: Any) -> None:
        self.policy = policy

    def queues(self) -> Any:
        q = getattr(self.policy, "_queues", None)
        return q if isinstance(q, Mapping) or hasattr(q, "keys") else None

    def feed(self, batch: Any) -> Any:
        queues = self.queues()
        if queues is None or not isinstance(batch, Mapping):
            return batch
        batch = {k: v for k, v in batch.items() if k != self.ACTION}
        images = list(getattr(getattr(self.policy, "config", None), "image_features", None) or [])
        if images and self.OBS_IMAGES in queues and self.OBS_IMAGES not in batch:
            import torch  # only LeRobot policies with cameras get here

            missing = [k for k in images if k not in batch]
            if missing:
                raise InputError(f"policy input: no camera key {missing[0]!r} (preprocess)")
            batch[self.OBS_IMAGES] = torch.stack([batch[k] for k in images], dim=-4)
        elif images and self.OBS_IMAGE in queues and self.OBS_IMAGE not in batch:
            if images[0] not in batch:
                raise InputError(f"policy input: no camera key {images[0]!r} (preprocess)")
            batch[self.OBS_IMAGE] = batch[images[0]]
        observed = {k: v for k, v in batch.items() if k in queues and k != self.ACTION}
        _populate_queues(queues, observed)
        return batch

    def depth(self) -> dict[str, int]:
        """How many observations each observation queue holds (``{}`` without queues)."""
        queues = self.queues()
        if queues is None:
            return {}
        return {k: len(v) for k, v in queues.items() if k != self.ACTION}


class ShieldedPolicyLoop:
    """Run a chunking policy on a robot through a pacs shield.

    Each control tick (``fps``): read the robot's observation, and when the shield has passed
    all but ``replan_margin`` of the current chunk's executed actions, ask the policy for a new
    chunk (``predict_action_chunk``; ``select_action`` for policies without chunks, one action
    at a time), hand it to the shield, let the shield step at its safety rate up to now, and
    send the shield's command to the robot.

    Args:
        policy: has ``predict_action_chunk(batch)`` (→ (1, H, A), time-major (H, 1, A) or
            (H, A): :func:`chunk_array`) or ``select_action(batch)`` (→ (1, A) or (A,));
            optional ``reset()``.
        robot: has ``get_observation() -> dict`` and ``send_action(dict) -> dict``.
        shield: a started :class:`pacs.Shield` (its time is the loop's time).
        joint_keys: the robot's joint keys in the shield's joint order (e.g.
            ``["shoulder_pan.pos", ...]``); observation and action dicts use them.
        action_indices: which columns of the policy's action vector are these joints
            (default ``0..len(joint_keys)``).
        unit: ``"rad"`` or ``"deg"``: the unit of joint values in observations, actions and
            the policy's outputs.
        action_kind: ``"absolute"`` (LeRobot policies emit joint targets) or ``"delta"``
            (joint-position deltas, as the PACS paper's policies).
        n_action_steps: h, the executed actions per chunk (default: all H).
        preprocess: ``obs -> batch`` for the policy (e.g. LeRobot's preprocessor pipeline);
            default: the observation dict itself.
        postprocess: applied to the policy's output before the shield (e.g. LeRobot's
            postprocessor, which un-normalizes actions: LeRobot ≥ 0.4 policies return
            normalized actions); default: none.
        humans: ``t -> None | (t_meas, positions (K, 3) m)``, polled every tick, or None.
        realtime: True: wall-clock ticks and a :class:`pacs.ShieldLoop` stepping at the
            safety rate on a Rust thread; False: simulated time, the shield steps between ticks.
        replan_margin: request the next chunk when this many executed actions are left.
        extra_keys: robot action keys that are not shield joints (e.g. ``{"gripper.pos": 6}``)
            mapped to their column in the policy's action vector: sent with the current
            chunk's action at the shield's progress along it (unfiltered: the shield does not
            model them). Other ``.pos`` keys of the observation are sent back unchanged.
        history: ``"auto"`` (default): every tick, the preprocessed observation enters the
            policy's observation queues (``policy._queues``, LeRobot's convention) when it has
            them, as its ``select_action`` would; ``"none"``: never (the policy keeps its own
            history, or ``preprocess`` stacks frames itself).

    A chunk the shield rejects (``pacs.ChunkRejected``) is recorded in ``rejected`` (time,
    reason) and the policy is asked again at the next tick; the robot keeps its verified motion.
    """

    def __init__(
        self,
        policy: Any,
        robot: Any,
        shield: Shield,
        joint_keys: Sequence[str],
        *,
        action_indices: Sequence[int] | None = None,
        unit: str = "rad",
        action_kind: str = "absolute",
        n_action_steps: int | None = None,
        preprocess: Callable[[Mapping[str, Any]], Any] | None = None,
        postprocess: Callable[[Any], Any] | None = None,
        humans: Callable[[float], Any] | None = None,
        fps: float = 30.0,
        realtime: bool = False,
        replan_margin: int = 0,
        extra_keys: Mapping[str, int] | None = None,
        history: str = "auto",
    ) -> None:
        if not hasattr(policy, "predict_action_chunk") and not hasattr(policy, "select_action"):
            raise ArgumentTypeError(
                "policy: needs predict_action_chunk(batch) or select_action(batch)"
            )
        for m in ("get_observation", "send_action"):
            if not hasattr(robot, m):
                raise ArgumentTypeError(f"robot: needs {m}()")
        if not isinstance(shield, Shield):
            raise ArgumentTypeError(f"shield: expected a pacs.Shield, got {type(shield).__name__}")
        self.joint_keys = list(joint_keys)
        if len(self.joint_keys) != shield.dof:
            raise InputError(
                f"joint_keys: {len(self.joint_keys)} keys for a robot with {shield.dof} joints"
            )
        self.action_indices = (
            list(range(shield.dof)) if action_indices is None else list(action_indices)
        )
        if len(self.action_indices) != shield.dof:
            raise InputError(
                f"action_indices: {len(self.action_indices)} indices for {shield.dof} joints"
            )
        if action_kind not in ("absolute", "delta"):
            raise InputError(f"action_kind: {action_kind!r} (absolute, delta)")
        if history not in ("auto", "none"):
            raise InputError(f"history: {history!r} (auto, none)")
        if not (fps > 0 and math.isfinite(fps)):
            raise InputError(f"fps: {fps} is not a positive rate (Hz)")
        self.policy, self.robot, self.shield = policy, robot, shield
        self.scale = _scale(unit)
        self.absolute = action_kind == "absolute"
        self.n_action_steps = n_action_steps
        self.preprocess = preprocess
        self.postprocess = postprocess
        self.humans = humans
        self.period = 1.0 / fps
        self.realtime = realtime
        self.replan_margin = replan_margin
        self.extra_keys = dict(extra_keys or {})
        if hasattr(policy, "reset"):
            policy.reset()  # a new episode: empty observation and action queues
        # Chunks from predict_action_chunk while the policy has it (and does not raise
        # NotImplementedError), else one action per chunk from select_action.
        self.chunking = hasattr(policy, "predict_action_chunk")
        # A select_action-only policy keeps its own history (its select_action fills it).
        self.history = (
            ObservationHistory(policy) if history == "auto" and self.chunking else None
        )
        self.loop = ShieldLoop(shield, realtime=realtime)
        self.loop.start()
        self.rejected: list[tuple[float, str]] = []
        self.chunks: dict[int, np.ndarray] = {}
        self.chunk_h: dict[int, int] = {}
        self.last_chunk = 0
        self._wall0 = time.monotonic()
        self._t0 = shield.time

    # -- time ---------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """The shield's time (s)."""
        return self.loop.time

    def _advance(self, t: float) -> None:
        if self.realtime:
            wait = self._wall0 + (t - self._t0) - time.monotonic()
            if wait > 0:
                time.sleep(wait)
        else:
            self.loop.run_until(t)

    # -- chunks -------------------------------------------------------------------------
    def _policy_batch(self, obs: Mapping[str, Any]) -> Any:
        """The policy's input for this tick, its observation history updated with it."""
        batch = self.preprocess(obs) if self.preprocess is not None else obs
        if self.history is not None:
            batch = self.history.feed(batch)
        return batch

    def _keeps_history(self) -> bool:
        """Whether the policy has observation queues to feed every tick (else its input is
        prepared only when a chunk is asked for: also for policies whose queues hold actions
        only, as LeRobot's VLA classes)."""
        if self.history is None:
            return False
        queues = self.history.queues()
        return queues is not None and any(k != ObservationHistory.ACTION for k in queues)

    def _policy_chunk(self, batch: Any) -> np.ndarray:
        post = self.postprocess if self.postprocess is not None else (lambda x: x)
        raw = None
        if self.chunking:
            try:
                raw = self.policy.predict_action_chunk(batch)
            except NotImplementedError:
                # A policy that inherits predict_action_chunk but acts one action at a time
                # (LeRobot's base class raises, e.g. GaussianActor): from now on select_action,
                # which keeps its own history, on a fresh episode.
                self.chunking = False
                self.history = None
                if hasattr(self.policy, "reset"):
                    self.policy.reset()
        if self.chunking:
            a = chunk_array(post(raw))
        else:
            a = to_numpy(post(self.policy.select_action(batch)))
            if a.ndim == 2:
                a = a[0]
            if a.ndim != 1:
                raise InputError(f"policy: select_action returned shape {a.shape}, expected (A,) "
                                 "or (1, A)")
            a = a[None, :]
        if max(self.action_indices) >= a.shape[1]:
            raise InputError(
                f"policy: action dimension {a.shape[1]} has no column {max(self.action_indices)}"
            )
        return a

    def _needs_chunk(self) -> bool:
        p = self.loop.progress()
        if self.last_chunk == 0:
            return True
        if p["chunk"] != self.last_chunk:
            # The newest chunk did not take over at the step after its handover (not verified,
            # e.g. a person close by): the shield dropped it; ask the policy again.
            return True
        return p["executed"] - p["passed"] <= self.replan_margin

    def executed(self) -> dict:
        """Which chunk runs and how many of its executed actions were passed:
        ``{"chunk", "passed", "executed", "accepted"}`` (see ``Shield.progress``)."""
        return self.loop.progress()

    def left_over(self) -> np.ndarray:
        """The current chunk's actions not yet executed (policy units, shape (H - passed, A)):
        LeRobot's real-time chunking passes these as ``prev_chunk_left_over``."""
        p = self.loop.progress()
        c = self.chunks.get(p["chunk"])
        if c is None:
            return np.zeros((0, 0))
        return c[p["passed"]:]

    def observe_joints(self, obs: Mapping[str, Any]) -> np.ndarray:
        """Joint positions (rad) from an observation dict."""
        try:
            return np.array([float(obs[k]) for k in self.joint_keys]) * self.scale
        except KeyError as e:
            raise InputError(f"robot observation: no joint key {e.args[0]!r}") from None

    # -- one tick -----------------------------------------------------------------------
    def tick(self) -> dict:
        """One control tick: observe, maybe hand over a chunk, step the shield to the next tick,
        send the command. Returns the action dict sent to the robot."""
        t = self.loop.time
        obs = self.robot.get_observation()
        if self.humans is not None:
            m = self.humans(t)
            if m is not None:
                t_meas, positions = m
                self.loop.measure(t_meas, positions)
        batch = self._policy_batch(obs) if self._keeps_history() else None
        if self._needs_chunk():
            a = self._policy_chunk(batch if batch is not None else self._policy_batch(obs))
            joints = a[:, self.action_indices] * self.scale
            h = self.n_action_steps if self.n_action_steps is not None else len(joints)
            h = min(h, len(joints))
            try:
                serial = self.loop.set_chunk(joints, h=h, absolute=self.absolute, t=t)
            except ChunkRejected as e:
                # Not plannable from this state (e.g. a target outside the joint limits, or
                # braking harder than the intended limits allow): the robot keeps its verified
                # motion and the policy is asked again next tick.
                self.rejected.append((t, str(e)))
                serial = None
            if serial is not None:
                self.chunks[serial] = a
                self.chunk_h[serial] = h
                self.last_chunk = serial
                running = self.loop.progress()["chunk"]
                for old in [k for k in self.chunks if k < min(running, serial)]:
                    del self.chunks[old], self.chunk_h[old]
        self._advance(t + self.period)
        cmd = self.loop.latest()
        if cmd is None:
            return {}  # the shield has not stepped yet: nothing to send (never the raw action)
        action = {k: v for k, v in obs.items() if k.endswith(".pos") and k not in self.joint_keys}
        q = cmd.q / self.scale
        for k, v in zip(self.joint_keys, q):
            action[k] = float(v)
        chunk = self.chunks.get(cmd.chunk)
        if chunk is not None:
            # The action being executed: q̂_passed → q̂_{passed+1} (the last executed one at the end).
            row = chunk[min(cmd.passed, self.chunk_h[cmd.chunk] - 1)]
            for k, col in self.extra_keys.items():
                action[k] = float(row[col])
        return self.robot.send_action(action)

    def run(self, duration: float) -> None:
        """Tick for ``duration`` seconds (shield time)."""
        end = self.loop.time + duration
        while self.loop.time + 0.5 * self.period < end:
            self.tick()

    def close(self) -> None:
        """Stop the shield loop (the shield can step directly again)."""
        self.loop.stop()

    def __enter__(self) -> "ShieldedPolicyLoop":
        return self

    def __exit__(self, *exc) -> bool:
        self.close()
        return False


#: Names of ``observation.environment_state``'s entries in datasets from :func:`write_dataset`.
ENVIRONMENT_STATE_NAMES = ["stage", "person_x", "person_y", "person_z", "person_distance"]


# The span floors of :func:`normalization_stats` for the observations :func:`write_dataset`
# records: 0.5 rad per joint; the sub-goals reached (0–2), the person's centroid and the tool's
# distance to the person (0.5 m each).
STATE_SPAN = 0.5
ENVIRONMENT_STATE_SPAN = (2.0, 0.5, 0.5, 0.5, 0.5)


def environment_state(stage: float, person: Any, person_distance: float) -> np.ndarray:
    """``observation.environment_state`` as :func:`write_dataset` records it (float32, shape
    (5,)): the sub-goals reached so far, the person's keypoint centroid (m, world frame) and the
    tool's distance to the person's nearest keypoint (m). Compute it the same way at inference."""
    p = to_numpy(person).reshape(-1)
    if p.shape != (3,):
        raise InputError(f"person: expected a point (3,), got shape {p.shape}")
    return np.array([float(stage), *p, float(person_distance)], dtype=np.float32)


def normalization_stats(x: Any, min_span: Any) -> dict:
    """Statistics of the rows of ``x`` (N, D) for LeRobot's normalizers (``min``, ``max``,
    ``mean``, ``std``, ``count``), with every feature's ``[min, max]`` widened about its
    midpoint to a span of at least ``min_span`` (a scalar or one per feature, in the feature's
    unit; the float32 ends rounded outward, so the range holds every row) and ``std`` floored at
    ``min_span / 4``.

    LeRobot's MIN_MAX normalizer divides by ``max - min`` (by 1e-8 where they are equal), so a
    feature the demonstrations hold (nearly) constant — a joint that never moves, a seated
    person's height — maps a deviation of a millimetre at inference to ±10⁵: the policy is far
    out of its training distribution at its first step. With a span floor such a feature keeps
    a bounded scale. :data:`STATE_SPAN` and :data:`ENVIRONMENT_STATE_SPAN` are the floors for
    :func:`write_dataset`'s observations.
    """
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 2 or a.shape[0] == 0 or not np.isfinite(a).all():
        raise InputError(f"x: expected a finite (N, D) array with N >= 1, got shape {a.shape}")
    span = np.asarray(min_span, dtype=np.float64)
    if span.shape not in ((), (a.shape[1],)) or not (np.isfinite(span).all() and (span > 0).all()):
        raise InputError(f"min_span: expected a positive finite span or {a.shape[1]} of them, "
                         f"got {min_span!r}")
    span = np.broadcast_to(span, (a.shape[1],))
    lo, hi = a.min(0), a.max(0)
    mid, half = (lo + hi) / 2, np.maximum(hi - lo, span) / 2
    f32 = np.float32
    # float32 ends rounded outward: the range contains every row.
    lo32, hi32 = (mid - half).astype(f32), (mid + half).astype(f32)
    lo32 = np.where(lo32 > mid - half, np.nextafter(lo32, f32(-np.inf)), lo32)
    hi32 = np.where(hi32 < mid + half, np.nextafter(hi32, f32(np.inf)), hi32)
    return {"min": lo32, "max": hi32,
            "mean": a.mean(0).astype(f32), "std": np.maximum(a.std(0), span / 4).astype(f32),
            "count": np.array([a.shape[0]])}


def write_dataset(
    demos: Sequence[Mapping[str, Any]],
    root: str,
    *,
    repo_id: str | None = None,
    task: str | None = None,
    joint_names: Sequence[str] | None = None,
) -> Any:
    """Write demonstrations (the dicts of :func:`pacs.teleop_demonstrations`: ``q``,
    ``action``, ``stage``, ``person``, ``person_distance``, ``fps``, ``task``) as a LeRobot
    dataset under ``root`` (a new directory), one episode per demonstration, without videos:

    - ``observation.state`` (7,): joint positions (rad);
    - ``observation.environment_state`` (5,): :func:`environment_state`;
    - ``action`` (7,): the joint-position delta to the next frame (rad; run such a policy with
      ``ShieldedPolicyLoop(..., action_kind="delta")``).

    Needs lerobot (≥ 0.4). Returns the ``LeRobotDataset``. ``repo_id`` defaults to
    ``"pacs/<task>-teleop"``, ``task`` (the language instruction of every frame) to the task's
    name; the frame rate is the demonstrations' ``fps`` (an integer, as LeRobot requires)."""
    try:
        from lerobot.datasets.lerobot_dataset import LeRobotDataset
    except Exception as e:  # noqa: BLE001 - lerobot absent or of another layout
        raise ArgumentTypeError(
            f"write_dataset needs lerobot (pip install 'lerobot>=0.4'): {e}"
        ) from e
    if not demos:
        raise InputError("demos: no demonstrations to write")
    fps = demos[0].get("fps")
    if fps is None or float(fps) != round(float(fps)) or not 1 <= float(fps) <= 1000:
        raise InputError(f"demos[0]['fps']: {fps!r} is not an integer frame rate (Hz)")
    fps = int(round(float(fps)))
    name = str(demos[0].get("task", "demo"))
    dof = to_numpy(demos[0]["q"]).shape[1]
    joints = list(joint_names) if joint_names is not None else [f"joint{i + 1}" for i in range(dof)]
    if len(joints) != dof:
        raise InputError(f"joint_names: {len(joints)} names for {dof} joints")
    features = {
        "observation.state": {"dtype": "float32", "shape": (dof,), "names": joints},
        "observation.environment_state": {
            "dtype": "float32",
            "shape": (len(ENVIRONMENT_STATE_NAMES),),
            "names": ENVIRONMENT_STATE_NAMES,
        },
        "action": {"dtype": "float32", "shape": (dof,), "names": [f"d_{j}" for j in joints]},
    }
    ds = LeRobotDataset.create(
        repo_id or f"pacs/{name}-teleop", fps, features, root=root, use_videos=False
    )
    instruction = task or name
    for i, d in enumerate(demos):
        if float(d.get("fps", fps)) != fps:
            raise InputError(f"demos[{i}]['fps']: {d.get('fps')} differs from {fps}")
        q, a = to_numpy(d["q"]), to_numpy(d["action"])
        stage, person, dist = (
            to_numpy(d["stage"]), to_numpy(d["person"]), to_numpy(d["person_distance"])
        )
        n = len(q)
        if q.shape != (n, dof) or a.shape != (n, dof) or len(stage) != n or len(dist) != n \
                or person.shape != (n, 3):
            raise InputError(f"demos[{i}]: arrays of different lengths or widths")
        for k in range(n):
            ds.add_frame({
                "observation.state": q[k].astype(np.float32),
                "observation.environment_state": environment_state(stage[k], person[k], dist[k]),
                "action": a[k].astype(np.float32),
                "task": instruction,
            })
        ds.save_episode()
    ds.finalize()
    return ds


def paced_replays(
    demos: Sequence[Mapping[str, Any]],
    *,
    per_demo: int = 1,
    seed: int = 0,
    hold: tuple[float, float] | None = None,
    pace: tuple[float, float] | None = None,
) -> list[dict]:
    """Path-consistent slowed and paused replays of demonstrations (the dicts of
    :func:`pacs.teleop_demonstrations`, or any with ``q`` (T, 7) rad and ``fps``), for training.

    Each demonstration gets ``per_demo`` replays along its own path
    (:func:`pacs.paced_replay`: the shield's jerk-limited path-speed profiles, within the FR3's
    operated limits): alternately one pause (brake to rest at 15–85 % of the recording, hold
    for a time in ``hold`` s, default (0.3, 1.5), resume) and one slow passage (a fifth to a
    third of the recording at a pace in ``pace``, default (0.2, 0.6), of the recorded one) —
    the recipe of ``pacs_sim::teleop::replay_event``, which also trains the built-in
    ``kernel-shield-paced`` policy; replay ``r`` of demonstration ``i`` draws its event from
    ``seed``, ``i`` and ``r``. Per-frame fields of the recording (``stage``, ``person``,
    ``person_distance``) follow the replay's place on the path (the nearest recorded frame);
    ``action`` is recomputed as the delta to the next replayed frame. Returns new dicts (the
    originals are not included), each with ``replay_of`` (the source's index), ``events``.
    """
    from . import _pacs

    out = []
    for i, d in enumerate(demos):
        q = to_numpy(d["q"])
        fps = float(d.get("fps", 30.0))
        end = (len(q) - 1) / fps
        for r in range(per_demo):
            events = _pacs.replay_event(end, r, (seed * 1_000_003 + i * 1_009 + r) % 2**63,
                                        hold=hold, pace=pace)
            rep = _pacs.paced_replay(q, fps=fps, **events)
            src = np.clip(np.rint(rep["source"]).astype(int), 0, len(q) - 1)
            new = dict(d)
            new["q"] = rep["q"]
            new["action"] = np.vstack([np.diff(rep["q"], axis=0), np.zeros((1, q.shape[1]))])
            for key in ("stage", "person", "person_distance"):
                if key in d:
                    new[key] = to_numpy(d[key])[src] if key != "stage" else np.asarray(d[key])[src]
            new["pace"] = rep["pace"]
            new["timestamp"] = np.arange(len(rep["q"])) / fps
            new["replay_of"] = i
            new["events"] = events
            out.append(new)
    return out


def _frame_environment(stage: float, person: Any, tool: Any) -> np.ndarray:
    """:func:`environment_state` from the person's keypoints (K, 3) and the tool point."""
    k = to_numpy(person).reshape(-1, 3)
    if len(k) == 0:
        raise InputError("obs: the scene has no person (environment_state needs one)")
    d = float(np.min(np.linalg.norm(k - to_numpy(tool).reshape(1, 3), axis=1)))
    return environment_state(stage, k.mean(axis=0), d)


class SimulationPolicy:
    """A LeRobot policy trained on :func:`write_dataset` data, as the simulation's policy
    (``pacs.simulate(task, method, policy=SimulationPolicy(...))``, the protocol of
    :func:`pacs.simulate`'s ``policy`` objects).

    Each ``act(obs)`` builds the two frames the policy saw in training — ``observation.state``
    (q) and ``observation.environment_state`` (:func:`environment_state` of the stage, the
    person and the tool) one policy step before and now —, resets the policy, feeds both
    frames through :class:`ObservationHistory` (LeRobot's own queue rule, so a policy with
    ``n_obs_steps`` = 2 sees exactly those two frames), predicts a chunk with
    ``predict_action_chunk`` and returns it un-normalized (the postprocessor) as joint-position
    deltas (H, 7) rad. ``n_action_steps`` is the policy config's (the executed actions per
    chunk). The sampling noise (a diffusion policy's) is seeded from the rollout's seed and the
    call's index in the rollout (``torch.manual_seed``), so a rollout is reproducible.

    Args:
        policy: a LeRobot ``PreTrainedPolicy`` (e.g. ``DiffusionPolicy``) with
            ``n_obs_steps`` ≤ 2.
        preprocess, postprocess: LeRobot's processor pipelines (``make_pre_post_processors``),
            or None (inputs and outputs un-normalized).
        threads: torch CPU threads during a call (default 1; restored after it). A float
            reduction's order depends on the thread count, so the same rollout on another count
            (Dask workers run one) can differ in the last bits and then diverge; one thread by
            default makes a rollout the same everywhere.
    """

    def __init__(
        self, policy: Any, preprocess: Any = None, postprocess: Any = None, threads: int = 1
    ) -> None:
        if not hasattr(policy, "predict_action_chunk"):
            raise ArgumentTypeError("policy: needs predict_action_chunk(batch)")
        if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
            raise InputError(f"threads: must be a positive int, got {threads!r}")
        self.threads = threads
        cfg = getattr(policy, "config", None)
        self.n_obs_steps = int(getattr(cfg, "n_obs_steps", 1))
        if self.n_obs_steps > 2:
            raise InputError(
                f"policy.config.n_obs_steps: {self.n_obs_steps}; the simulation observes two frames"
            )
        self.n_action_steps = int(getattr(cfg, "n_action_steps", 8))
        self.policy, self.preprocess, self.postprocess = policy, preprocess, postprocess
        self.history = ObservationHistory(policy)
        self._key: Any = None
        self._calls = 0

    @classmethod
    def from_pretrained(cls, path: str, threads: int = 1) -> "SimulationPolicy":
        """Load a policy and its processors saved by LeRobot (``save_pretrained``), on CPU."""
        from lerobot.policies.factory import get_policy_class, make_pre_post_processors
        from lerobot.configs.policies import PreTrainedConfig

        cfg = PreTrainedConfig.from_pretrained(path)
        cfg.device = "cpu"
        policy = get_policy_class(cfg.type).from_pretrained(path, config=cfg).eval()
        pre, post = make_pre_post_processors(
            cfg, pretrained_path=path,
            preprocessor_overrides={"device_processor": {"device": "cpu"}},
        )
        return cls(policy, pre, post, threads=threads)

    def frames(self, obs: Mapping[str, Any]) -> list[dict[str, np.ndarray]]:
        """The two observation frames (before, now) of a simulation observation."""
        out = []
        for q, person, tool in (
            (obs["q_before"], obs["person_before"], obs["tool_before"]),
            (obs["q"], obs["person"], obs["tool"]),
        ):
            out.append({
                "observation.state": to_numpy(q).astype(np.float32),
                "observation.environment_state": _frame_environment(obs["stage"], person, tool),
            })
        return out

    def reset(self) -> None:
        if hasattr(self.policy, "reset"):
            self.policy.reset()

    def _seed(self, obs: Mapping[str, Any]) -> int:
        """A seed for this call's sampling noise: the rollout's seed and the number of calls
        since the rollout began (t = 0), so a rollout is the same whenever it is run (locally,
        on Dask, or again as the tolerance tool's twin)."""
        key = (obs.get("task"), obs.get("seed"))
        if key != self._key or float(obs.get("t", 0.0)) == 0.0:
            self._key, self._calls = key, 0
        self._calls += 1
        return (int(obs.get("seed") or 0) * 1_000_003 + self._calls) % (2**63)

    def act(self, obs: Mapping[str, Any]) -> np.ndarray:
        import torch

        self.reset()
        torch.manual_seed(self._seed(obs))
        batch = None
        before = torch.get_num_threads()
        torch.set_num_threads(self.threads)
        try:
            with torch.no_grad():
                for frame in self.frames(obs):
                    b = {k: torch.from_numpy(v) for k, v in frame.items()}
                    if self.preprocess is not None:
                        b = self.preprocess(b)
                    else:
                        b = {k: v[None] for k, v in b.items()}
                    batch = self.history.feed(b)
                a = self.policy.predict_action_chunk(batch)
                if self.postprocess is not None:
                    a = self.postprocess(a)
        finally:
            torch.set_num_threads(before)
        return chunk_array(a)


try:  # LeRobot's base class and registry, when installed.
    from lerobot.processor import ProcessorStepRegistry as _Registry
    from lerobot.processor import RobotActionProcessorStep as _ActionStepBase
except Exception:  # noqa: BLE001 - lerobot absent or of another layout
    _Registry = None

    class _ActionStepBase:  # the documented interface of RobotActionProcessorStep
        """Stand-in for ``lerobot.processor.RobotActionProcessorStep`` (lerobot not installed)."""

        _current_transition = None

        def __call__(self, transition: dict) -> dict:
            new = dict(transition)
            action = new.get("action")
            if not isinstance(action, dict):
                raise InputError("transition['action']: expected a robot action dict")
            new["action"] = self.action(action.copy())
            return new

        def get_config(self) -> dict:
            return {}

        def state_dict(self) -> dict:
            return {}

        def load_state_dict(self, state: dict) -> None:
            return None

        def reset(self) -> None:
            return None


class ShieldActionStep(_ActionStepBase):
    """A robot-pipeline step (``RobotActionProcessorStep``-style): each robot action (a dict of
    joint targets, one per control tick) is handed to a running :class:`pacs.ShieldLoop` as a
    one-action chunk of absolute joint positions, and the action returned to the robot is the
    shield's latest command — the verified motion toward the target, or braking along the path.
    A target the shield drops (not verified at its first step) is handed over again; one it
    rejects (``pacs.ChunkRejected``) is recorded in ``rejected`` and the robot keeps its
    verified motion. Keys other than ``joint_keys`` pass through unchanged.

    Args:
        loop: a started :class:`pacs.ShieldLoop` (real time) stepping the shield.
        joint_keys: the robot's joint keys in the shield's joint order.
        unit: ``"rad"`` or ``"deg"`` (joint values in the action dicts).
    """

    def __init__(self, loop: ShieldLoop, joint_keys: Sequence[str], unit: str = "rad") -> None:
        if not isinstance(loop, ShieldLoop):
            raise ArgumentTypeError(f"loop: expected a pacs.ShieldLoop, got {type(loop).__name__}")
        self.loop = loop
        self.joint_keys = list(joint_keys)
        self.unit = unit
        self.scale = _scale(unit)
        self._last_target: np.ndarray | None = None
        self._last_serial = 0
        self._handover_time = -math.inf
        self.rejected: list[str] = []

    def action(self, action: dict) -> dict:
        try:
            target = np.array([float(action[k]) for k in self.joint_keys]) * self.scale
        except KeyError as e:
            raise InputError(f"action: no joint key {e.args[0]!r}") from None
        # Dropped: a step after the handover ran, and the commands still follow an older chunk.
        dropped = (
            self._last_serial
            and self.loop.time > self._handover_time
            and self.loop.progress()["chunk"] != self._last_serial
        )
        if dropped or self._last_target is None or not np.array_equal(target, self._last_target):
            try:
                self._handover_time = self.loop.time
                self._last_serial = self.loop.set_chunk(target[None, :], absolute=True)
                self._last_target = target
            except ChunkRejected as e:  # the robot keeps its verified motion
                self.rejected.append(str(e))
        cmd = self.loop.latest()
        if cmd is None:
            raise NotStartedError(
                "ShieldActionStep: the ShieldLoop has not stepped yet (start it before the pipeline runs)"
            )
        out = dict(action)
        for k, v in zip(self.joint_keys, cmd.q / self.scale):
            out[k] = float(v)
        return out

    def transform_features(self, features):
        """The step keeps the action features (same keys, same shapes)."""
        return features

    def get_config(self) -> dict:
        return {"joint_keys": self.joint_keys, "unit": self.unit}

    def reset(self) -> None:
        self._last_target = None
        self._last_serial = 0


if _Registry is not None:  # pragma: no cover - only with lerobot installed
    try:
        _Registry.register("pacs_shield_action")(ShieldActionStep)
    except ValueError:
        pass

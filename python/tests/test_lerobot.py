"""The LeRobot adapters against LeRobot's documented interfaces (fake policy and robot with
the same method names and shapes), and against LeRobot's real classes when
PACS_TEST_LEROBOT=1 and lerobot is installed."""

import os

import numpy as np
import pytest

import pacs
from collections import deque

from pacs.lerobot import ObservationHistory, ShieldActionStep, ShieldedPolicyLoop
from conftest import far_human

KEYS = [f"joint{i + 1}.pos" for i in range(7)]


def _state_features(action_dim=7):
    """LeRobot feature dicts of the tests' state-only policies: ``observation.state`` (7) and
    ``observation.environment_state`` (3) in, ``action`` (``action_dim``) out."""
    from lerobot.configs.types import FeatureType, PolicyFeature

    return (
        {
            "observation.state": PolicyFeature(type=FeatureType.STATE, shape=(7,)),
            "observation.environment_state": PolicyFeature(type=FeatureType.ENV, shape=(3,)),
        },
        {"action": PolicyFeature(type=FeatureType.ACTION, shape=(action_dim,))},
    )


def _run_torch_deltas(demo, policy, preprocess, n_action_steps, seconds=1.0):
    """One second of a torch policy's chunks (as deltas, 0.002 × its clamped output) through
    a shield at 30 Hz, the person far away; returns the finished loop and the robot."""
    import torch

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    with torch.no_grad(), ShieldedPolicyLoop(
        policy, robot, shield, KEYS, action_kind="delta", n_action_steps=n_action_steps,
        fps=30.0, preprocess=preprocess, postprocess=lambda a: 0.002 * torch.clamp(a, -1, 1),
        humans=lambda t: (t, person),
    ) as loop:
        loop.run(seconds)
    return loop, robot


class DemoPolicy:
    """A PreTrainedPolicy-shaped wrapper of the simulation's demonstration policy:
    predict_action_chunk(batch) -> (B, H, A) absolute joint targets (degrees)."""

    def __init__(self, demo):
        self.demo = demo
        self.calls = 0

    def predict_action_chunk(self, batch):
        self.calls += 1
        q = np.radians([batch[k] for k in KEYS])
        deltas, _ = self.demo.chunk(q)
        targets = q + np.cumsum(deltas, axis=0)
        gripper = 40.0 + np.arange(len(targets))[:, None]  # percent, not converted; per action
        return np.hstack([np.degrees(targets), gripper])[None]

    def reset(self):
        pass


class FakeRobot:
    """A Robot-shaped simulated arm: get_observation() -> {key: degrees}, send_action(dict)."""

    def __init__(self, q0_deg):
        self.q = dict(zip(KEYS, q0_deg))
        self.q["gripper.pos"] = 0.0
        self.sent = []

    def get_observation(self):
        return dict(self.q)

    def send_action(self, action):
        self.sent.append(dict(action))
        self.q.update(action)
        return action


def test_shielded_policy_loop_runs_chunks_through_the_shield(demo):
    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(np.degrees(demo.start))
    policy = DemoPolicy(demo)
    person = far_human(demo)
    loop = ShieldedPolicyLoop(
        policy, robot, shield, KEYS, unit="deg", n_action_steps=8, fps=30.0,
        humans=lambda t: (t, person), realtime=False, extra_keys={"gripper.pos": 7},
    )
    with loop:
        loop.run(3.0)
        progress = loop.executed()
        left = loop.left_over()
    assert policy.calls >= 3
    assert progress["accepted"] == policy.calls
    assert 0 <= progress["passed"] <= 8
    assert left.shape[1] == 8 and len(left) == 16 - progress["passed"]
    # The robot moved along the demonstration and received every joint key (+ the gripper).
    assert len(robot.sent) == pytest.approx(90, abs=2)
    assert set(robot.sent[-1]) == set(KEYS) | {"gripper.pos"}
    # The policy's gripper command of the action being executed (not the observation's, never
    # one beyond the h executed actions).
    assert all(40.0 <= a["gripper.pos"] <= 47.0 for a in robot.sent)
    q = np.radians([robot.q[k] for k in KEYS])
    assert np.linalg.norm(q - demo.start) > 0.05
    assert demo.deviation(q) < 0.05


class QueuedPolicy:
    """Shaped like LeRobot's DiffusionPolicy (0.6): reset() empties one observation queue per
    key (length n_obs_steps) and the action queue; predict_action_chunk stacks the queues (as
    LeRobot's does once they are filled) and fails on a history of the wrong length, as
    LeRobot's ``generate_actions`` asserts. Records every history it was asked with."""

    def __init__(self, demo, n_obs_steps=2):
        self.demo, self.n_obs_steps = demo, n_obs_steps
        self.seen = []
        self._queues = None

    def reset(self):
        self._queues = {
            "observation.state": deque(maxlen=self.n_obs_steps),
            "action": deque(maxlen=8),
        }

    def predict_action_chunk(self, batch):
        assert any(len(q) > 0 for q in self._queues.values()), "queues never filled"
        stacked = {k: np.stack(list(self._queues[k]), axis=1) for k in batch if k in self._queues}
        state = stacked["observation.state"]  # (B, n_obs_steps, 7)
        assert state.shape == (1, self.n_obs_steps, 7), state.shape
        self.seen.append(state[0].copy())
        q = state[0, -1]
        deltas, _ = self.demo.chunk(q)
        return (q + np.cumsum(deltas, axis=0))[None]


def test_the_loop_fills_a_policys_observation_history(demo):
    """A history-stacking policy (n_obs_steps = 2) gets, at every chunk, the observations of
    the last two ticks (the first one repeated at the start, as LeRobot's select_action does);
    without the history (history="none") it fails as LeRobot's diffusion policy did."""
    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    policy = QueuedPolicy(demo)
    observed = []

    def preprocess(obs):
        state = np.array([[obs[k] for k in KEYS]])
        observed.append(state[0])
        return {"observation.state": state, "action": np.zeros((1, 7))}

    with ShieldedPolicyLoop(policy, robot, shield, KEYS, n_action_steps=8, fps=30.0,
                            preprocess=preprocess, humans=lambda t: (t, person)) as loop:
        loop.run(2.0)
    assert len(policy.seen) >= 4 and not loop.rejected
    # The first chunk: the first observation twice.
    np.testing.assert_array_equal(policy.seen[0], [observed[0], observed[0]])
    # Every later chunk: the previous tick's and this tick's observations, in order. Match
    # each history to the tick whose observation ends it.
    for hist in policy.seen[1:]:
        i = next(i for i in range(1, len(observed)) if np.array_equal(observed[i], hist[1])
                 and np.array_equal(observed[i - 1], hist[0]))
        assert i >= 1
    # The robot moved between chunks, so the two frames of a later history differ.
    assert any(not np.array_equal(h[0], h[1]) for h in policy.seen[1:])
    assert len(policy._queues["action"]) == 0  # the action key is never queued

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    with pytest.raises(AssertionError, match="never filled"):
        with ShieldedPolicyLoop(QueuedPolicy(demo), FakeRobot(demo.start), shield, KEYS,
                                preprocess=preprocess, history="none",
                                humans=lambda t: (t, person)) as loop:
            loop.run(0.1)


def test_observation_history_follows_lerobots_rule():
    class P:
        def __init__(self):
            self._queues = {"observation.state": deque(maxlen=3), "action": deque(maxlen=4)}

    p = P()
    h = ObservationHistory(p)
    out = h.feed({"observation.state": 1, "other": 9, "action": 5})
    assert out == {"observation.state": 1, "other": 9}
    assert list(p._queues["observation.state"]) == [1, 1, 1]
    h.feed({"observation.state": 2})
    h.feed({"observation.state": 3})
    h.feed({"observation.state": 4})
    assert list(p._queues["observation.state"]) == [2, 3, 4]
    assert h.depth() == {"observation.state": 3}
    assert ObservationHistory(object()).feed({"a": 1}) == {"a": 1}  # no queues: untouched


def test_a_select_action_policy_becomes_one_action_chunks(demo):
    class SinglePolicy:
        def select_action(self, batch):
            q = np.array([batch[k] for k in KEYS])
            return (q + 0.01)[None]

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    with ShieldedPolicyLoop(SinglePolicy(), robot, shield, KEYS,
                            humans=lambda t: (t, person)) as loop:
        loop.run(0.5)
    assert loop.executed()["executed"] == 1
    assert robot.q["joint1.pos"] > demo.start[0]


def test_normalization_stats_floor_the_span_of_constant_features():
    """A feature the demonstrations hold constant (joint 7 at 0.7854 rad) gets the floor span
    about its value, so an inference-time deviation of 0.015 rad normalizes to a bounded value
    (LeRobot's MIN_MAX: 2·(x − min)/(max − min) − 1), not to ±10⁶; a feature that varies more
    than the floor keeps its own range; the std is floored at a quarter of the span."""
    from pacs.lerobot import normalization_stats

    rng = np.random.default_rng(3)
    x = np.column_stack([rng.uniform(-1.0, 2.0, 500), np.full(500, 0.7854),
                         0.09 + rng.uniform(0.0, 1e-3, 500)])
    st = normalization_stats(x, [0.5, 0.5, 0.5])
    assert st["min"][0] == pytest.approx(x[:, 0].min(), abs=1e-6)
    assert st["max"][0] == pytest.approx(x[:, 0].max(), abs=1e-6)
    assert st["min"][1] == pytest.approx(0.7854 - 0.25, abs=1e-6)
    assert st["max"][1] == pytest.approx(0.7854 + 0.25, abs=1e-6)
    assert (st["max"] - st["min"] >= 0.5 - 1e-6).all()
    assert (st["min"] <= x.min(0)).all() and (st["max"] >= x.max(0)).all()
    normalized = 2 * (0.7854 + 0.015 - st["min"][1]) / (st["max"][1] - st["min"][1]) - 1
    assert abs(normalized) < 0.1
    assert st["std"][1] == pytest.approx(0.125) and st["std"][0] == pytest.approx(x[:, 0].std(), rel=1e-5)
    assert st["mean"][2] == pytest.approx(x[:, 2].mean(), abs=1e-6) and st["count"][0] == 500
    assert all(v.dtype == np.float32 for k, v in st.items() if k != "count")
    # The floors for write_dataset's observations fit them, one per feature.
    from pacs.lerobot import ENVIRONMENT_STATE_SPAN, STATE_SPAN, environment_state
    assert len(ENVIRONMENT_STATE_SPAN) == environment_state(1, [0.5, 0.0, 0.4], 0.3).shape[0]
    assert np.isscalar(STATE_SPAN) and STATE_SPAN > 0
    # A scalar span applies to every feature.
    assert (normalization_stats(x, 1.0)["max"] - normalization_stats(x, 1.0)["min"] >= 1.0 - 1e-6).all()
    for bad, match in (([[np.nan, 1.0]], "x: expected a finite"), (np.zeros((0, 2)), "x: expected"),
                       (np.zeros(3), "x: expected")):
        with pytest.raises(pacs.InputError, match=match):
            normalization_stats(bad, 0.5)
    for span in (0.0, -1.0, np.inf, [0.5, 0.5], [[0.5, 0.5, 0.5]]):
        with pytest.raises(pacs.InputError, match="min_span: expected a positive finite span or 3"):
            normalization_stats(x, span)


def test_chunk_array_reads_batch_major_and_time_major_chunks():
    """(1, H, A) as most LeRobot policies return a chunk, (H, 1, A) as TD-MPC's planner does:
    both are the same (H, A) chunk; anything else for one observation is refused."""
    from pacs.lerobot import chunk_array

    c = np.arange(5 * 7, dtype=float).reshape(5, 7)
    assert np.array_equal(chunk_array(c[None]), c)
    assert np.array_equal(chunk_array(c[:, None, :]), c)
    assert np.array_equal(chunk_array(c), c)
    assert np.array_equal(chunk_array(c[:1][None]), c[:1])
    for bad in (np.zeros((2, 5, 7)), np.zeros(7), np.zeros((1, 1, 5, 7))):
        with pytest.raises(pacs.InputError, match="action chunk of shape"):
            chunk_array(bad)


def test_a_time_major_chunk_is_executed_whole(demo):
    """A policy returning (H, 1, A) chunks (TD-MPC's layout): every action of the chunk is
    kept, not only the first (each chunk stored with H rows, and the robot follows them)."""

    class TimeMajorPolicy:
        def __init__(self):
            self.calls = 0

        def predict_action_chunk(self, batch):
            self.calls += 1
            return np.full((5, 1, 7), 0.004)  # (H, B, A): five deltas of 4 mrad

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    policy = TimeMajorPolicy()
    with ShieldedPolicyLoop(policy, robot, shield, KEYS, action_kind="delta", n_action_steps=5,
                            fps=30.0, humans=lambda t: (t, person)) as loop:
        loop.run(1.0)
    assert loop.chunks and all(c.shape == (5, 7) for c in loop.chunks.values())
    # Five actions per chunk: about one chunk per 5/30 s (not one per tick).
    assert policy.calls <= 8
    assert robot.q["joint1.pos"] > demo.start[0] + 0.01


def test_action_only_queues_are_not_fed_every_tick(demo):
    """A policy whose queues hold actions only (LeRobot's VLA classes) gains nothing from the
    history: its input is prepared only when a chunk is asked for, not every tick."""

    class ActionQueuePolicy:
        def __init__(self):
            self._queues = {"action": deque(maxlen=8)}
            self.calls = 0

        def reset(self):
            self._queues["action"].clear()

        def predict_action_chunk(self, batch):
            self.calls += 1
            return np.full((1, 8, 7), 0.002)

    prepared = []

    def preprocess(obs):
        prepared.append(obs["joint1.pos"])
        return obs

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    policy = ActionQueuePolicy()
    with ShieldedPolicyLoop(policy, robot, shield, KEYS, action_kind="delta", n_action_steps=8,
                            preprocess=preprocess, humans=lambda t: (t, person)) as loop:
        loop.run(1.0)
    assert policy.calls >= 2 and len(prepared) == policy.calls
    assert len(robot.sent) >= 25  # every tick still sent a command


def test_a_policy_without_chunks_falls_back_to_select_action(demo):
    """A LeRobot-shaped policy that inherits predict_action_chunk but raises
    NotImplementedError (as GaussianActor does) is driven by select_action, on a fresh episode
    (reset), one action per chunk; its own select_action keeps its history (not fed twice)."""

    class SingleOnly:
        def __init__(self):
            self.resets = 0
            self._queues = {"observation.state": deque(maxlen=1)}

        def reset(self):
            self.resets += 1
            self._queues["observation.state"].clear()

        def predict_action_chunk(self, batch):
            raise NotImplementedError("this policy does not support action chunking")

        def select_action(self, batch):
            self._queues["observation.state"].append(batch["joint1.pos"])
            q = np.array([batch[k] for k in KEYS])
            return (q + 0.01)[None]

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    policy = SingleOnly()
    with ShieldedPolicyLoop(policy, robot, shield, KEYS,
                            humans=lambda t: (t, person)) as loop:
        loop.run(0.5)
        assert loop.history is None and not loop.chunking
    assert policy.resets == 2  # the new episode, then the switch to select_action
    assert all(c.shape == (1, 7) for c in loop.chunks.values())
    assert robot.q["joint1.pos"] > demo.start[0]


def test_rejected_chunks_are_recorded_and_the_loop_goes_on(demo):
    class WildPolicy:
        def __init__(self):
            self.calls = 0

        def predict_action_chunk(self, batch):
            self.calls += 1
            q = np.array([batch[k] for k in KEYS])
            far = 10.0 if self.calls <= 3 else 0.01  # the first chunks leave the joint limits
            return (q + far * np.arange(1, 5)[:, None])[None]

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    policy = WildPolicy()
    with ShieldedPolicyLoop(policy, robot, shield, KEYS, humans=lambda t: (t, person)) as loop:
        loop.run(0.5)
    assert len(loop.rejected) == 3 and "outside" in loop.rejected[0][1]
    assert loop.executed()["accepted"] >= 1
    assert np.all(np.array([robot.q[k] for k in KEYS]) > demo.start)


def test_a_dropped_chunk_is_asked_for_again(demo):
    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(np.degrees(demo.start))
    policy = DemoPolicy(demo)
    person = far_human(demo)
    # No measurement before 0.2 s: the first chunks are dropped; the policy is asked again.
    with ShieldedPolicyLoop(policy, robot, shield, KEYS, unit="deg", n_action_steps=8,
                            humans=lambda t: (t, person) if t >= 0.2 else None) as loop:
        loop.run(1.0)
    assert policy.calls >= 8
    assert loop.executed()["chunk"] >= 2
    q = np.radians([robot.q[k] for k in KEYS])
    assert np.linalg.norm(q - demo.start) > 0.02


def test_adapter_argument_errors(demo):
    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    with pytest.raises(pacs.ArgumentTypeError, match="policy"):
        ShieldedPolicyLoop(object(), robot, shield, KEYS)
    with pytest.raises(pacs.InputError, match="joint_keys"):
        ShieldedPolicyLoop(DemoPolicy(demo), robot, shield, KEYS[:6])
    with pytest.raises(pacs.InputError, match="unit"):
        ShieldedPolicyLoop(DemoPolicy(demo), robot, shield, KEYS, unit="grad")


def test_action_step_replaces_actions_by_shield_commands(demo):
    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    shield.measure(0.0, far_human(demo))
    with pacs.ShieldLoop(shield, realtime=True) as loop:
        step = ShieldActionStep(loop, KEYS)
        import time

        while loop.latest() is None:  # the first step (within a millisecond or so)
            time.sleep(0.001)
        target = demo.start + 0.02
        action = dict(zip(KEYS, target))
        action["gripper.pos"] = 40.0
        transition = {"observation": {}, "action": action}
        import time

        out = None
        for _ in range(20):
            out = step(transition)["action"]
            time.sleep(0.01)
    assert out["gripper.pos"] == 40.0  # passed through
    q = np.array([out[k] for k in KEYS])
    # The command moves from the start toward the target, never beyond it.
    assert np.all(q >= demo.start - 1e-12) and np.all(q <= target + 1e-12)
    assert np.linalg.norm(q - demo.start) > 0
    assert step.transform_features({"a": 1}) == {"a": 1}
    with pytest.raises(pacs.InputError, match="joint3.pos"):
        step.action({k: 0.0 for k in KEYS if k != "joint3.pos"})


@pytest.mark.skipif(os.environ.get("PACS_TEST_LEROBOT") != "1",
                    reason="PACS_TEST_LEROBOT=1 tests against the installed lerobot (pulls torch)")
def test_against_lerobot_classes(demo):
    processor = pytest.importorskip("lerobot.processor")
    assert issubclass(ShieldActionStep, processor.RobotActionProcessorStep)
    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    shield.measure(0.0, far_human(demo))
    with pacs.ShieldLoop(shield) as loop:
        step = ShieldActionStep(loop, KEYS)
        import time

        while loop.latest() is None:
            time.sleep(0.001)
        pipe = processor.RobotProcessorPipeline(
            steps=[step],
            to_transition=processor.converters.robot_action_observation_to_transition,
            to_output=processor.converters.transition_to_robot_action,
        )
        action = dict(zip(KEYS, demo.start + 0.01))
        out = pipe((action, {}))
    assert set(KEYS) <= set(out)


def test_action_step_never_passes_the_raw_target(demo):
    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    loop = pacs.ShieldLoop(shield, realtime=False)
    loop.start()
    step = ShieldActionStep(loop, KEYS)
    with pytest.raises(pacs.NotStartedError, match="has not stepped"):
        step.action(dict(zip(KEYS, demo.start + 0.5)))
    loop.run_until(0.01)
    out = step.action(dict(zip(KEYS, demo.start + 0.5)))
    np.testing.assert_array_equal([out[k] for k in KEYS], demo.start)  # no measurement: at rest
    loop.stop()


@pytest.mark.skipif(os.environ.get("PACS_TEST_LEROBOT") != "1",
                    reason="PACS_TEST_LEROBOT=1 tests against the installed lerobot (pulls torch)")
def test_a_real_lerobot_policy_through_the_shield(demo):
    """LeRobot's ACT policy (random weights, tiny) emits (1, H, A) torch chunks; the loop
    integrates them (as deltas, scaled by a stand-in postprocessor) through the shield."""
    torch = pytest.importorskip("torch")
    act = pytest.importorskip("lerobot.policies.act.modeling_act")
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.act.configuration_act import ACTConfig

    torch.manual_seed(0)
    cfg = ACTConfig(
        input_features={
            "observation.state": PolicyFeature(type=FeatureType.STATE, shape=(7,)),
            "observation.environment_state": PolicyFeature(type=FeatureType.ENV, shape=(3,)),
        },
        output_features={"action": PolicyFeature(type=FeatureType.ACTION, shape=(8,))},
        chunk_size=16, n_action_steps=8, dim_model=64, n_heads=2, dim_feedforward=128,
        n_encoder_layers=1, n_decoder_layers=1, use_vae=False, device="cpu",
    )
    policy = act.ACTPolicy(cfg).eval()

    def preprocess(obs):
        q = torch.tensor([[obs[k] for k in KEYS]], dtype=torch.float32)
        return {"observation.state": q, "observation.environment_state": torch.zeros(1, 3)}

    shield = pacs.Shield()
    shield.start(0.0, demo.start)
    robot = FakeRobot(demo.start)
    person = far_human(demo)
    with torch.no_grad(), ShieldedPolicyLoop(
        policy, robot, shield, KEYS, action_kind="delta", n_action_steps=8,
        preprocess=preprocess, postprocess=lambda a: 0.005 * a,
        humans=lambda t: (t, person), extra_keys={"gripper.pos": 7},
    ) as loop:
        loop.run(1.0)
    assert loop.executed()["accepted"] >= 3 and not loop.rejected
    q = np.array([robot.q[k] for k in KEYS])
    assert np.linalg.norm(q - demo.start) > 1e-3
    sent = np.array([[a[k] for k in KEYS] for a in robot.sent])
    # FR3 joint speed limits ≤ 2.62 rad/s: no jump between 30 Hz commands beyond that.
    assert np.max(np.abs(np.diff(sent, axis=0))) <= 2.62 / 30 + 1e-9


@pytest.mark.skipif(os.environ.get("PACS_TEST_LEROBOT") != "1",
                    reason="PACS_TEST_LEROBOT=1 tests against the installed lerobot (pulls torch)")
def test_a_real_diffusion_policy_through_the_shield(demo):
    """LeRobot's DiffusionPolicy (random weights, the small state configuration: n_obs_steps =
    2, horizon 16, 8 executed actions, DDIM at 4 steps) with a (B, state) batch per tick: the
    loop fills its two-frame history, so predict_action_chunk runs (lerobot 0.6.1 asserted on
    such a batch before) and its chunks drive the robot through the shield."""
    torch = pytest.importorskip("torch")
    diffusion = pytest.importorskip("lerobot.policies.diffusion.modeling_diffusion")
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig

    torch.manual_seed(0)
    inputs, outputs = _state_features()
    cfg = DiffusionConfig(
        input_features=inputs, output_features=outputs,
        n_obs_steps=2, horizon=16, n_action_steps=8, down_dims=(32, 64, 128),
        noise_scheduler_type="DDIM", num_inference_steps=4, device="cpu",
    )
    policy = diffusion.DiffusionPolicy(cfg).eval()
    frames = []

    def preprocess(obs):
        q = torch.tensor([[obs[k] for k in KEYS]], dtype=torch.float32)
        frames.append(q)
        return {"observation.state": q, "observation.environment_state": torch.zeros(1, 3)}

    # Without the history LeRobot's own predict_action_chunk fails on this batch.
    policy.reset()
    with pytest.raises(Exception):
        policy.predict_action_chunk(preprocess({k: 0.0 for k in KEYS}))

    loop, robot = _run_torch_deltas(demo, policy, preprocess, n_action_steps=8)
    depth = loop.history.depth()
    assert depth == {"observation.state": 2, "observation.environment_state": 2}
    assert loop.executed()["accepted"] >= 3 and not loop.rejected
    # The queue holds the last two frames, in order.
    last = list(policy._queues["observation.state"])
    assert torch.equal(last[1], frames[-1]) and torch.equal(last[0], frames[-2])
    q = np.array([robot.q[k] for k in KEYS])
    assert np.linalg.norm(q - demo.start) > 1e-4
    sent = np.array([[a[k] for k in KEYS] for a in robot.sent])
    assert np.max(np.abs(np.diff(sent, axis=0))) <= 2.62 / 30 + 1e-9


@pytest.mark.skipif(os.environ.get("PACS_TEST_LEROBOT") != "1",
                    reason="PACS_TEST_LEROBOT=1 tests against the installed lerobot (pulls torch)")
def test_a_real_tdmpc_policy_keeps_its_whole_chunk(demo):
    """LeRobot's TDMPCPolicy (tiny, random weights, horizon 5 = n_action_steps): its planner
    returns time-major (horizon, B, A) chunks; the loop keeps all five actions of each (it kept
    only the first before), with its observation history filled."""
    torch = pytest.importorskip("torch")
    tdmpc = pytest.importorskip("lerobot.policies.tdmpc.modeling_tdmpc")
    from lerobot.policies.tdmpc.configuration_tdmpc import TDMPCConfig

    torch.manual_seed(0)
    inputs, outputs = _state_features()
    cfg = TDMPCConfig(
        input_features=inputs, output_features=outputs,
        horizon=5, n_action_steps=5, n_action_repeats=1, state_encoder_hidden_dim=32,
        latent_dim=16, mlp_dim=32, q_ensemble_size=2, n_gaussian_samples=16, n_pi_samples=4,
        n_elites=4, cem_iterations=2, device="cpu",
    )
    policy = tdmpc.TDMPCPolicy(cfg).eval()
    shapes = []
    plan = policy.predict_action_chunk

    def spy(batch):
        out = plan(batch)
        shapes.append(tuple(out.shape))
        return out

    policy.predict_action_chunk = spy

    def preprocess(obs):
        q = torch.tensor([[obs[k] for k in KEYS]], dtype=torch.float32)
        return {"observation.state": q, "observation.environment_state": torch.zeros(1, 3)}

    loop, _ = _run_torch_deltas(demo, policy, preprocess, n_action_steps=5)
    assert shapes and all(sh == (5, 1, 7) for sh in shapes)  # time-major
    assert all(c.shape == (5, 7) for c in loop.chunks.values())
    assert len(shapes) <= 8 and not loop.rejected

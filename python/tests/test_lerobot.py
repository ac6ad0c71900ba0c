"""The LeRobot adapters against LeRobot's documented interfaces (fake policy and robot with
the same method names and shapes), and against LeRobot's real classes when
PACS_TEST_LEROBOT=1 and lerobot is installed."""

import os

import numpy as np
import pytest

import pacs
from pacs.lerobot import ShieldActionStep, ShieldedPolicyLoop
from conftest import far_human

KEYS = [f"joint{i + 1}.pos" for i in range(7)]


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

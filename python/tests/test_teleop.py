"""Teleoperation-like demonstrations (pacs.teleop_demonstrations) and their LeRobot dataset
(pacs.lerobot.write_dataset, with lerobot installed and PACS_TEST_LEROBOT=1)."""

import os

import numpy as np
import pytest

import pacs
from pacs.lerobot import ENVIRONMENT_STATE_NAMES, environment_state, write_dataset

# FR3 joint limits as operated: speeds (rad/s) and the shield's intended fraction (0.8) of the
# accelerations (10 rad/s²).
V_MAX = np.array([2.62, 2.62, 2.62, 2.62, 5.26, 4.18, 5.26])
A_OPERATED = 0.8 * 10.0


@pytest.mark.parametrize("task", ["sorting", "handover", "feeding", "sphere", "crowded"])
def test_fifty_demonstrations_vary_and_stay_within_the_operated_limits(task):
    demos = pacs.teleop_demonstrations(task, count=50, seed=100)
    assert len(demos) == 50
    dt = 1.0 / 30.0
    for d in demos:
        q = d["q"]
        n = len(q)
        assert q.shape == (n, 7) and d["action"].shape == (n, 7)
        np.testing.assert_allclose(q[:-1] + d["action"][:-1], q[1:], atol=1e-12)
        assert np.all(d["action"][-1] == 0.0)
        assert np.all(np.abs(np.diff(q, axis=0)) <= V_MAX * dt + 1e-12)
        acc = np.abs(np.diff(q, n=2, axis=0)) / dt**2
        assert acc.max() <= A_OPERATED + 1e-9, acc.max()
        # From rest to rest; every sub-goal reached, in order.
        assert np.abs(q[1] - q[0]).max() <= A_OPERATED * dt**2
        assert d["stage"][-1] == d["goals"] and np.all(np.diff(d["stage"]) >= 0)
        np.testing.assert_allclose(d["timestamp"], np.arange(n) * dt)
        # The recorded person distance is the tool's distance to the scenario's person.
        demo = pacs.Demo(task, seed=d["seed"])
        k = n // 2
        tool = np.array(demo.tool_point(q[k]))
        people = demo.keypoints(d["timestamp"][k])
        assert np.linalg.norm(people - tool, axis=1).min() == pytest.approx(
            d["person_distance"][k], abs=1e-9)
        np.testing.assert_allclose(d["person"][k], people.mean(axis=0), atol=1e-12)
    durations = np.array([len(d["q"]) for d in demos]) * dt
    assert durations.max() > 1.3 * durations.min()
    paused = [d for d in demos if np.any(d["pace"][1:-1] == 0.0)]
    assert len(paused) >= 10  # pauses and hesitation stops
    assert sum(d["pauses"] > 0 for d in demos) >= 15
    assert sum(d["detours"] > 0 for d in demos) >= 15
    paces = np.concatenate([d["pace"] for d in demos])
    assert paces.max() > 1.0 and np.mean((paces > 0) & (paces < 0.5)) > 0.02  # pace changes
    if task != "sphere":  # the sphere task has no person near the arm
        assert sum(d["hesitations"] > 0 for d in demos) >= 25
        # Hesitation: the pace near the person is lower than away from it.
        near = np.concatenate([d["pace"][d["person_distance"] < 0.3] for d in demos])
        far = np.concatenate([d["pace"][d["person_distance"] >= 0.45] for d in demos])
        assert near.mean() < 0.8 * far.mean()


def test_demonstrations_are_deterministic_and_bad_arguments_are_refused():
    a = pacs.teleop_demonstrations("feeding", count=2, seed=5)
    b = pacs.teleop_demonstrations("feeding", count=1, seed=6)
    np.testing.assert_array_equal(a[1]["q"], b[0]["q"])
    with pytest.raises(pacs.InputError, match="unknown task"):
        pacs.teleop_demonstrations("juggling")
    with pytest.raises(pacs.InputError, match="fps"):
        pacs.teleop_demonstrations("sorting", count=1, fps=0.0)


def test_environment_state_layout():
    e = environment_state(1, [0.5, -0.25, 1.0], 0.75)
    assert e.dtype == np.float32 and e.tolist() == [1.0, 0.5, -0.25, 1.0, 0.75]
    assert len(ENVIRONMENT_STATE_NAMES) == 5
    with pytest.raises(pacs.InputError, match="person"):
        environment_state(0, [1.0, 2.0], 0.0)


@pytest.mark.skipif(os.environ.get("PACS_TEST_LEROBOT") != "1",
                    reason="PACS_TEST_LEROBOT=1 tests against the installed lerobot (pulls torch)")
def test_demonstrations_as_a_lerobot_dataset(tmp_path):
    pytest.importorskip("lerobot")
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    demos = pacs.teleop_demonstrations("handover", count=3, seed=1)
    root = tmp_path / "handover-teleop"
    write_dataset(demos, str(root))
    ds = LeRobotDataset("pacs/handover-teleop", root=str(root))
    assert ds.fps == 30 and ds.num_episodes == 3
    assert ds.num_frames == sum(len(d["q"]) for d in demos)
    start = len(demos[0]["q"])
    frame = ds[start + 5]  # episode 1, frame 5
    assert int(frame["episode_index"]) == 1 and int(frame["frame_index"]) == 5
    np.testing.assert_allclose(frame["observation.state"].numpy(), demos[1]["q"][5], atol=1e-6)
    np.testing.assert_allclose(frame["action"].numpy(), demos[1]["action"][5], atol=1e-6)
    d = demos[1]
    np.testing.assert_allclose(
        frame["observation.environment_state"].numpy(),
        environment_state(d["stage"][5], d["person"][5], d["person_distance"][5]), atol=1e-6)
    assert frame["task"] == "handover"

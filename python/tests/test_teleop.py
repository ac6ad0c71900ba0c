"""Teleoperation-like demonstrations (pacs.teleop_demonstrations) and their LeRobot dataset
(pacs.lerobot.write_dataset, with lerobot installed and PACS_TEST_LEROBOT=1)."""

import json
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


@pytest.mark.skipif(os.environ.get("PACS_TEST_LEROBOT") != "1",
                    reason="PACS_TEST_LEROBOT=1 tests against the installed lerobot (pulls torch)")
def test_a_lerobot_diffusion_policy_in_the_simulation(tmp_path):
    """A tiny untrained DiffusionPolicy (with processors from the demonstrations' statistics),
    saved and loaded the LeRobot way, runs in pacs.simulate through OFF and PACS; the PACS log
    is audited; the policy sees the two frames the simulation observes."""
    torch = pytest.importorskip("torch")
    from lerobot.configs.types import FeatureType, NormalizationMode, PolicyFeature
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
    from lerobot.policies.factory import make_pre_post_processors
    from pacs.lerobot import SimulationPolicy

    torch.manual_seed(0)
    demos = pacs.teleop_demonstrations("sorting", count=3, seed=1)
    q = np.concatenate([d["q"] for d in demos]).astype(np.float32)
    env = np.stack([environment_state(s, p, r) for d in demos
                    for s, p, r in zip(d["stage"], d["person"], d["person_distance"])])
    a = np.concatenate([d["action"] for d in demos]).astype(np.float32)

    def stats(x):
        return {"min": x.min(0), "max": x.max(0), "mean": x.mean(0), "std": x.std(0) + 1e-6}

    cfg = DiffusionConfig(
        input_features={
            "observation.state": PolicyFeature(type=FeatureType.STATE, shape=(7,)),
            "observation.environment_state": PolicyFeature(type=FeatureType.ENV, shape=(5,)),
        },
        output_features={"action": PolicyFeature(type=FeatureType.ACTION, shape=(7,))},
        n_obs_steps=2, horizon=16, n_action_steps=8, down_dims=(32, 64, 128),
        noise_scheduler_type="DDIM", num_inference_steps=3, device="cpu",
        normalization_mapping={"STATE": NormalizationMode.MIN_MAX,
                               "ENV": NormalizationMode.MIN_MAX,
                               "ACTION": NormalizationMode.MIN_MAX},
    )
    pre, post = make_pre_post_processors(
        cfg, dataset_stats={"observation.state": stats(q),
                            "observation.environment_state": stats(env), "action": stats(a)})
    model = tmp_path / "model"
    DiffusionPolicy(cfg).save_pretrained(model)
    pre.save_pretrained(model)
    post.save_pretrained(model)
    policy = SimulationPolicy.from_pretrained(str(model))
    assert policy.n_action_steps == 8
    seen = []
    feed = policy.history.feed

    def spy(batch):
        out = feed(batch)
        seen.append(len(policy.policy._queues["observation.state"]))
        return out

    policy.history.feed = spy
    out = pacs.simulate("sorting", "off,pacs", seeds=[1], policy=policy, log_dir=tmp_path / "logs")
    assert [r["method"] for r in out["rollouts"]] == ["off", "pacs"]
    assert seen and all(n == 2 for n in seen)
    # Sampling noise seeded per rollout and call: the same rollouts when run again.
    again = pacs.simulate("sorting", "off,pacs", seeds=[1], policy=policy)
    assert json.dumps([r["episode"] for r in again["rollouts"]]) == \
        json.dumps([r["episode"] for r in out["rollouts"]])
    (run,) = pacs.audit(out["rollouts"][1]["log"])
    assert run.verdict in ("pass", "fail", "inconclusive")
    # On a Dask cluster (the policy, torch modules and processors, pickled to the workers):
    # the same rollouts.
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        on_dask = pacs.simulate("sorting", "off,pacs", seeds=[1, 2], policy=policy,
                                client=client, partitions=2)
    local = pacs.simulate("sorting", "off,pacs", seeds=[1, 2], policy=policy)
    assert json.dumps(on_dask) == json.dumps(local)
    assert out["rollouts"][1]["episode"]["violation_fraction"] == 0.0


def test_paced_replays_keep_the_path_and_the_operated_limits():
    from pacs.lerobot import paced_replays

    demos = pacs.teleop_demonstrations("handover", count=4, seed=2)
    reps = paced_replays(demos, per_demo=2, seed=1)
    assert len(reps) == 8 and [r["replay_of"] for r in reps] == [0, 0, 1, 1, 2, 2, 3, 3]
    dt = 1.0 / 30.0
    for r in reps:
        d = demos[r["replay_of"]]
        q = r["q"]
        assert len(q) > len(d["q"])  # slower somewhere
        np.testing.assert_allclose(q[:-1] + r["action"][:-1], q[1:], atol=1e-12)
        assert np.all(np.abs(np.diff(q, axis=0)) <= V_MAX * dt + 1e-12)
        assert (np.abs(np.diff(q, n=2, axis=0)) / dt**2).max() <= A_OPERATED + 1e-9
        np.testing.assert_array_equal(q[-1], d["q"][-1])
        assert r["stage"][-1] == d["stage"][-1] and np.all(np.diff(r["stage"]) >= 0)
        end = (len(d["q"]) - 1) * dt
        if r["events"]["pauses"]:
            (at, hold), = r["events"]["pauses"]
            # The one recipe (pacs_sim::teleop::replay_event): 15-85 % of the way, 0.3-1.5 s.
            assert 0.15 * end <= at <= 0.85 * end and 0.3 <= hold <= 1.5
            stopped = np.sum(r["pace"] == 0.0) * dt
            assert abs(stopped - hold) <= 0.1 + 2 * dt
        else:
            (start, stop, pace), = r["events"]["slows"]
            assert 0.2 <= pace <= 0.6 and 0.2 * end <= stop - start <= 0.33 * end + 1e-9
            assert 0.05 * end <= start and stop <= 0.95 * end + 1e-9
            assert np.isclose(r["pace"], pace).sum() >= 5
    with pytest.raises(pacs.InputError, match=r"pace: \(0\.5, 1\.5\)"):
        paced_replays(demos[:1], pace=(0.5, 1.5))
    with pytest.raises(pacs.InputError, match="hold"):
        paced_replays(demos[:1], hold=(0.0, 1.0))
    with pytest.raises(pacs.InputError, match=r"pauses\[0\]"):
        pacs.paced_replay(demos[0]["q"], pauses=[(1.0, -1.0)])
    with pytest.raises(pacs.InputError, match=r"slows\[0\]"):
        pacs.paced_replay(demos[0]["q"], slows=[(2.0, 1.0, 0.5)])
    with pytest.raises(pacs.InputError, match=r"q\[0\]"):
        pacs.paced_replay(np.zeros((3, 6)))


@pytest.mark.skipif(os.environ.get("PACS_TEST_LEROBOT") != "1",
                    reason="PACS_TEST_LEROBOT=1 tests against the installed lerobot (pulls torch)")
def test_the_diffusion_policy_example_runs_verbatim(tmp_path):
    """python/examples/diffusion_policy.py train and evaluate, as documented, at toy sizes."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "examples" / "diffusion_policy.py"
    out = tmp_path / "sorting"
    run = lambda *a: subprocess.run([sys.executable, str(script), *a], capture_output=True,
                                    text=True, timeout=900)
    p = run("train", "--task", "sorting", "--out", str(out), "--demos", "3", "--replays", "1",
            "--steps", "3", "--log-every", "1")
    assert p.returncode == 0, p.stderr[-2000:]
    info = json.loads((out / "training.json").read_text())
    assert info["demonstrations"] == 6 and info["steps"] == 3
    assert (out / "model" / "model.safetensors").exists() and (out / "dataset").exists()
    p = run("evaluate", "--policy", str(out / "model"), "--task", "sorting", "--method", "pacs",
            "--rollouts", "1", "--out", str(out / "eval"))
    assert p.returncode == 0, p.stderr[-2000:]
    summary = json.loads((out / "eval" / "summary.json").read_text())
    (row,) = summary["rows"]
    assert row["method"] == "pacs" and row["rollouts"] == 1
    assert sum(row["audit_verdicts"].values()) == 1
    svg = (out / "eval" / "summary.svg").read_text()
    assert svg.startswith("<svg") and svg.count("<circle") == 1
    # --resume keeps the methods partial.json holds and runs only the others.
    p = run("evaluate", "--policy", str(out / "model"), "--task", "sorting", "--method",
            "pacs,off", "--rollouts", "1", "--out", str(out / "eval"), "--resume")
    assert p.returncode == 0, p.stderr[-2000:]
    assert "resuming: pacs already done" in p.stdout
    summary = json.loads((out / "eval" / "summary.json").read_text())
    assert [r["method"] for r in summary["rows"]] == ["off", "pacs"]
    assert summary["rows"][1] == row
    # Another evaluation's partial results are refused, not mixed in.
    p = run("evaluate", "--policy", str(out / "model"), "--task", "sorting", "--method", "pacs",
            "--rollouts", "2", "--out", str(out / "eval"), "--resume")
    assert p.returncode != 0 and "made by another evaluation" in p.stderr


def test_bad_arguments_of_the_learning_tools_are_named():
    cases = [
        (lambda: pacs.teleop_demonstrations("sorting", count=-1), pacs.InputError,
         "count: value -1 is negative"),
        (lambda: pacs.teleop_demonstrations("sorting", count="x"), pacs.ArgumentTypeError,
         "count: expected an int, got 'x'"),
        (lambda: pacs.teleop_demonstrations("sorting", count=0), pacs.InputError,
         "count: must be at least 1"),
        (lambda: pacs.teleop_demonstrations(3), pacs.ArgumentTypeError, "task: expected a str"),
        (lambda: pacs.paced_replay(np.zeros((5, 7)), pauses=[(1,)]), pacs.ArgumentTypeError,
         r"pauses: expected a list of \(at_s, hold_s\) pairs"),
        (lambda: pacs.paced_replay(np.zeros((5, 7)), fps="a"), pacs.ArgumentTypeError,
         "fps: expected a number"),
        (lambda: pacs.tolerance("nearest", "sorting", seeds=[-1]), pacs.InputError,
         r"seeds\[0\]: must be at least 0"),
        (lambda: pacs.tolerance("nearest", "sorting", rollouts=0), pacs.InputError,
         "rollouts: must be at least 1"),
    ]
    for call, kind, message in cases:
        with pytest.raises(kind, match=message):
            call()


def test_the_example_compares_evaluations_with_newcombe_intervals(tmp_path):
    """`diffusion_policy.py compare`: each method's success with its Wilson interval and the
    difference's Newcombe interval (method 10), checked against Newcombe (1998)'s own examples:
    56/70 vs 48/80 → [0.0524, 0.3339], 9/10 vs 3/10 → [0.1705, 0.8090], 5/56 vs 0/29 →
    [−0.0381, 0.1926]."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "examples" / "diffusion_policy.py"

    def summary(rows):
        return {"task": "sorting", "policy": "p", "rows": [
            {"method": m, "rollouts": n, "success": k / n,
             "success_ci95": list(pacs_wilson(k, n))} for m, k, n in rows]}

    def pacs_wilson(k, n):
        z = 1.959963984540054
        p = k / n
        d = 1 + z * z / n
        c = (p + z * z / (2 * n)) / d
        h = z * (p * (1 - p) / n + z * z / (4 * n * n)) ** 0.5 / d
        return max(0.0, c - h), min(1.0, c + h)

    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    (a / "summary.json").write_text(json.dumps(summary(
        [("off", 48, 80), ("pacs", 3, 10), ("cbf", 0, 29)])))
    (b / "summary.json").write_text(json.dumps(summary(
        [("off", 56, 70), ("pacs", 9, 10), ("cbf", 5, 56)])))
    p = subprocess.run([sys.executable, str(script), "compare", str(a), str(b), "--out",
                        str(tmp_path / "cmp")], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-2000:]
    out = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    got = {d["method"]: d for d in out["differences"]}
    for m, lo, hi, changed in [("off", 0.0524, 0.3339, True), ("pacs", 0.1705, 0.8090, True),
                               ("cbf", -0.0381, 0.1926, False)]:
        assert got[m]["newcombe95"] == pytest.approx([lo, hi], abs=5e-5), m
        assert got[m]["changed"] is changed
    assert "**changed**" in p.stdout and "0.80 [0.69, 0.88] (n = 70)" in p.stdout
    svg = (tmp_path / "cmp" / "compare.svg").read_text()
    assert svg.startswith("<svg") and svg.count("<circle") == 6
    p = subprocess.run([sys.executable, str(script), "compare", str(tmp_path / "nowhere")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode != 0 and "no such file" in p.stderr

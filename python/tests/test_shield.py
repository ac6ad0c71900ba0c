"""Shield loop invariants: commands on the intended path, the verified flag, a person at the
gripper stops the robot, chunk progress."""

import numpy as np
import pytest

import pacs
from conftest import away, far_human, run


def started(demo, **kw):
    s = pacs.Shield(robot="fr3", humans="default", constraints="sorting", **kw)
    s.start(0.0, demo.start)
    return s


def test_no_measurement_never_verifies_and_the_robot_stays(demo):
    s = started(demo)
    deltas, h = demo.chunk(demo.start)
    assert s.set_chunk(deltas, t=0.0, h=h) == 1
    cmds = run(s, 50)
    assert not any(c.verified for c in cmds)
    assert all(c.binding["kind"] == "no-measurement" for c in cmds)
    for c in cmds:
        np.testing.assert_array_equal(c.q, demo.start)
        np.testing.assert_array_equal(c.dq, np.zeros(7))


def test_free_motion_is_verified_and_follows_the_integrated_waypoints(demo):
    s = started(demo)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    cmds = run(s, 3000, measure=away(demo))
    assert all(c.verified for c in cmds)
    # The chunk ends at rest at the integrated waypoint q̂_h = q_0 + Σ_{i<h} Δq_i.
    goal = demo.start + deltas[:h].sum(axis=0)
    np.testing.assert_allclose(cmds[-1].q, goal, atol=1e-9)
    np.testing.assert_allclose(cmds[-1].dq, 0.0, atol=1e-12)
    assert cmds[-1].chunk == 1 and cmds[-1].passed == h
    assert s.progress() == {"chunk": 1, "passed": h, "executed": h, "accepted": 1}
    # Waypoints are passed in order: `passed` never decreases and reaches h.
    passed = [c.passed for c in cmds]
    assert passed == sorted(passed) and passed[0] == 0
    # Times are the step times plus one safety step.
    assert cmds[0].t == pytest.approx(0.001)


def test_braking_stays_on_the_intended_path(demo):
    """A person stepping next to the robot mid-chunk: the commands brake, but every commanded
    configuration lies on the path the free run took (path consistency)."""
    deltas, h = demo.chunk(demo.start)
    free = started(demo)
    free.set_chunk(deltas, t=0.0, h=h)
    path = np.array([c.q for c in run(free, 3000, measure=away(demo))])

    s = started(demo)
    s.set_chunk(deltas, t=0.0, h=h)
    mid = path[len(path) // 3]
    near = np.tile(demo.tool_point(mid), (9, 1)) + np.array([0.25, 0.0, 0.0])

    def person(t):
        return (t, far_human(demo)) if t < 0.05 else (t, near)

    cmds = run(s, 3000, measure=person)
    assert any(c.on_failsafe for c in cmds), "the person never made the shield brake"
    a, b = path[:-1], path[1:]
    ab = b - a
    len2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    for c in cmds:
        # Distance to the free run's 1 ms polyline (chord error of the path ≲ 1e-6 rad).
        u = np.clip(np.einsum("ij,ij->i", c.q - a, ab) / len2, 0.0, 1.0)
        d = np.min(np.linalg.norm(a + u[:, None] * ab - c.q, axis=1))
        assert d <= 2e-6, f"command off the intended path by {d} rad at t={c.t}"


def test_a_person_at_the_gripper_stops_the_robot(demo):
    s = started(demo)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    cmds = run(s, 60, measure=away(demo))
    assert cmds[-1].verified and np.linalg.norm(cmds[-1].dq) > 0
    at_gripper = np.tile(demo.tool_point(cmds[-1].q), (9, 1))
    cmds = run(s, 1500, t0=0.06, measure=lambda t: (t, at_gripper))
    assert not any(c.verified for c in cmds[5:])
    assert cmds[-1].binding["kind"] == "ssm"
    np.testing.assert_allclose(cmds[-1].dq, 0.0, atol=1e-12)
    np.testing.assert_allclose(cmds[-1].q, cmds[-2].q, atol=0)
    assert cmds[-1].path_speed == 0.0


def test_continuous_chunks_and_progress(demo):
    s = started(demo, config={"chunk_motion": "continuous"})
    measure = away(demo)
    q = demo.start
    t, serials, speeds = 0.0, [], []
    for _ in range(6):
        deltas, h = demo.chunk(q)
        serials.append(s.set_chunk(deltas, t=t, h=h))
        for _ in range(5000):
            m = measure(t)
            if m is not None:
                s.measure(*m)
            c = s.step(t)
            t += 0.001
            speeds.append(np.linalg.norm(c.dq))
            q = c.q
            if s.remaining is not None and s.remaining <= 0.0015 and c.chunk == serials[-1]:
                break
        else:
            pytest.fail(f"chunk {serials[-1]} never reached its end")
    assert serials == [1, 2, 3, 4, 5, 6]
    # Handed over near the end of each chunk, the robot never stops between chunks.
    assert min(speeds[200:]) > 1e-3


def test_objects_and_multiple_humans():
    demo = pacs.Demo("crowded", seed=2)
    args = demo.shield_args()
    s = pacs.Shield(**args)
    assert s.object_ids == demo.object_ids and len(s.object_ids) == 2
    s.start(0.0, demo.start)
    s.measure(0.0, demo.keypoints(0.0))
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    c = s.step(0.0)
    assert not c.verified and c.binding["kind"] == "no-measurement"
    for i, oid in enumerate(s.object_ids):
        p, v = demo.object_state(i, 0.0)
        s.measure_object(oid, 0.0, p, v)
    c = s.step(0.001)
    assert c.verified


def test_every_human_must_be_measured_and_each_can_stop_the_robot(demo):
    s = pacs.Shield(humans=["default", "default"])
    assert s.humans == 2 and s.keypoints == [9, 9]
    s.start(0.0, demo.start)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    far = far_human(demo)
    # With several people, each measurement names its person (by id or index).
    with pytest.raises(pacs.InputError, match=r"human: required with several people .*human0"):
        s.measure(0.0, far)
    with pytest.raises(pacs.InputError, match="human: no person `visitor`"):
        s.measure(0.0, far, human="visitor")
    with pytest.raises(pacs.ArgumentTypeError, match="human: expected a person's id"):
        s.measure(0.0, far, human=1.5)
    s.measure(0.0, far, human="human0")
    c = s.step(0.0)
    assert not c.verified and c.binding["kind"] == "no-measurement"
    s.set_chunk(deltas, t=0.001, h=h)
    s.measure(0.001, far, human=np.int64(1))
    cmds = run(s, 80, t0=0.001,
               measure=lambda t: (t, far, None, 0) if round(t * 1000) % 10 == 0 else None)
    assert cmds[-1].verified and cmds[-1].chunk == 2
    at_gripper = np.tile(demo.tool_point(cmds[-1].q), (9, 1))
    t0 = 0.081
    for k in range(1500):
        t = t0 + k * 0.001
        if k % 10 == 0:
            s.measure(t, far, human=0)
            s.measure(t, at_gripper, human="human1")
        c = s.step(t)
    assert not c.verified and c.binding["kind"] == "ssm" and c.binding.get("human") == 1
    # Names beside the indices: the person's id, the link and the body part.
    assert c.binding["person"] == "human1"
    assert c.binding["link_name"].startswith("fr3_") and isinstance(c.binding["body_part_name"], str)
    assert c.to_dict()["binding"] == c.binding
    np.testing.assert_allclose(c.dq, 0.0, atol=1e-12)
    # Several people are logged too (format v2): python/tests/test_people.py.


def test_humans_none_means_no_human(demo):
    s = pacs.Shield(humans=None)
    assert s.humans == 0
    s.start(0.0, demo.start)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    assert all(c.verified for c in run(s, 100))


def test_the_acc_model_refuses_a_measurement_without_velocities(demo):
    # Without velocities no step could ever verify under `acc`: refused, naming the argument.
    s = pacs.Shield(config={"human_model": "acc"})
    s.start(0.0, demo.start)
    with pytest.raises(pacs.InputError, match="velocities: required with human_model `acc`"):
        s.measure(0.0, far_human(demo))
    s.measure(0.0, far_human(demo), velocities=np.zeros_like(far_human(demo)))


def test_an_empty_list_of_people_is_refused():
    # `humans=[]` would silently mean "no person" (as `humans=None`): refused, pointing at None.
    with pytest.raises(pacs.InputError, match="humans: an empty list"):
        pacs.Shield(humans=[])


def test_steps_keep_the_safety_step_grid_and_measurements_wait_for_their_time(demo):
    s = pacs.Shield()
    s.start(0.0, demo.start)
    with pytest.raises(pacs.InputError, match="before the start"):
        s.step(-0.5)
    s.step(0.0)
    with pytest.raises(pacs.InputError, match="this one is at 0.001 s"):
        s.step(0.0015)
    with pytest.raises(pacs.InputError, match="this one is at 0.001 s"):
        s.step(0.5)
    # A measurement stamped ahead of the shield's time waits for its step; an older one
    # that arrives later is still used meanwhile.
    far = far_human(demo)
    s.measure(0.0035, far)
    s.measure(0.0005, far)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.001, h=h)
    c = s.step(0.001)
    assert c.verified and c.chunk == 1


def test_a_chunk_not_verified_at_its_first_step_is_dropped(demo):
    s = pacs.Shield()
    s.start(0.0, demo.start)
    deltas, h = demo.chunk(demo.start)
    assert s.set_chunk(deltas, t=0.0, h=h) == 1
    c = s.step(0.0)  # no measurement: not verified, chunk 1 dropped (the robot stands still)
    assert not c.verified and c.chunk == 0 and c.path_speed == 0.0
    far = far_human(demo)
    cmds = run(s, 100, t0=0.001, measure=lambda t: (t, far))
    assert cmds[-1].verified and cmds[-1].chunk == 0  # a dropped chunk does not come back
    np.testing.assert_array_equal(cmds[-1].q, demo.start)
    assert s.set_chunk(deltas, t=0.101, h=h) == 2
    cmds = run(s, 100, t0=0.101, measure=lambda t: (t, far))
    assert cmds[-1].verified and cmds[-1].chunk == 2 and cmds[-1].path_speed == 1.0
    # Moving: a chunk handed over when the next step cannot verify (a person at the gripper)
    # is dropped; the robot brakes along chunk 2.
    assert s.set_chunk(deltas, t=0.201, h=h) == 3
    s.measure(0.201, np.tile(demo.tool_point(cmds[-1].q), (9, 1)))
    c = s.step(0.201)
    assert not c.verified and c.on_failsafe and c.chunk == 2
    c = s.step(0.202)
    assert c.chunk == 2 and s.progress()["accepted"] == 3


def test_log_failures_do_not_lose_commands(demo, tmp_path):
    s = pacs.Shield(log="/dev/full")
    s.start(0.0, demo.start)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    cmds = run(s, 500, measure=away(demo))
    assert len(cmds) == 500 and cmds[-1].verified
    with pytest.raises(pacs.OutputError, match="/dev/full"):
        s.close()
    s.close()  # reported once
    with pytest.raises(pacs.NotStartedError, match="runs once"):
        s.start(1.0, demo.start)


def test_urdf_robot(tmp_path):
    spec = pacs.robot_spec("fr3")
    assert len(spec["links"]) >= 7
    with pytest.raises(pacs.InputError, match="URDF"):
        pacs.Shield(robot=str(tmp_path / "missing.urdf"))
    with pytest.raises(pacs.InputError, match="robot\\[\"mesh\"\\]"):
        pacs.Shield(robot={"urdf": "x.urdf", "mesh": 1})


DATA = __import__("pathlib").Path(__file__).resolve().parents[2] / "models" / "tests" / "data"


def test_a_urdf_robot_in_every_form(demo, tmp_path):
    urdf, side = DATA / "fr3.urdf", DATA / "fr3_side.toml"
    spec = pacs.robot_spec(urdf, side=side)
    assert len(spec["links"]) >= 7
    for robot, kw in [(str(urdf), {"side": side}), ({"urdf": urdf, "side": side}, {})]:
        s = pacs.Shield(robot=robot, log=tmp_path / "urdf.jsonl", **kw)
        assert s.dof == 7
        # The header carries the converted spec, so the audit uses the same robot.
        assert isinstance(s.header["robot"], dict)
    s.start(0.0, demo.start)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    cmds = run(s, 400, measure=away(demo))
    assert cmds[-1].verified
    s.close()
    (r,) = pacs.audit(tmp_path / "urdf.jsonl")
    assert r.verdict == "pass", r.to_dict()
    with pytest.raises(pacs.InputError, match="URDF"):
        pacs.Shield(robot=DATA / "planar2.urdf")  # no side file: no masses/capsules

"""Audit from Python: a shield run's log passes, a LogWriter log of a violating run fails, a
gap is inconclusive; reports are written."""

import json

import numpy as np
import pytest

import pacs
from conftest import away, run


def logged_shield(demo, path):
    """A sorting shield logging to `path`, started at the demo's start with its first chunk."""
    s = pacs.Shield(robot="fr3", humans="default", constraints="sorting", log=path)
    s.start(0.0, demo.start)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    return s


def shield_run(demo, path, steps=1500):
    s = logged_shield(demo, path)
    run(s, steps, measure=away(demo))
    s.close()
    return s


def test_a_shield_log_passes_the_audit(demo, tmp_path):
    log = tmp_path / "shield.jsonl"
    shield_run(demo, log)
    runs = pacs.audit(log)
    assert len(runs) == 1
    r = runs[0]
    assert r.verdict == "pass" and r.passed, r.to_dict()
    assert r.violations == [] and r.inconclusive == []
    assert r.metrics["samples"] >= 1500
    assert r.models["robot"] == "fr3"
    verdict = pacs.report(runs, tmp_path / "report")
    assert verdict == "pass"
    doc = json.loads((tmp_path / "report" / "report.json").read_text())
    assert doc["verdict"] == "pass" and doc["runs"][0]["sha256"]
    assert (tmp_path / "report" / "report.html").stat().st_size > 1000


def test_a_measurement_the_others_contradict_is_logged_and_not_a_pass(demo, tmp_path):
    """A measurement of the person at the gripper, superseded in the same step by one 3 m away
    (1 ms newer), is not used by the shield but is logged: the audit checks it against its
    neighbours in time and cannot pass the run (a log of only the newest measurement of each
    step would pass)."""
    from conftest import far_human

    log = tmp_path / "hidden.jsonl"
    s = logged_shield(demo, log)
    far = far_human(demo)
    at_gripper = np.tile(demo.tool_point(demo.start), (9, 1))
    for k in range(600):
        t = k * 0.001
        if k % 10 == 0:
            if k == 300:
                s.measure(t - 0.001, at_gripper)
            s.measure(t, far)
        s.step(t)
    s.close()
    (r,) = pacs.audit([log])
    assert r.verdict != "pass", r.to_dict()
    assert any(i["reason"] == "human_exceeds_model" for i in r.inconclusive), r.to_dict()
    assert r.metrics["human_records"] == 61


def test_a_first_step_later_than_the_start_gives_an_auditable_log(demo, tmp_path):
    """Started at 0 s, stepped from 0.5 s: the start sample is logged at the first step, after
    its measurement (logged before it, it would go back in time and the audit would refuse the
    log as going backwards)."""
    log = tmp_path / "late_first_step.jsonl"
    s = pacs.Shield(robot="fr3", humans="default", constraints="sorting", log=log)
    s.start(0.0, demo.start)
    run(s, 300, t0=0.5, measure=away(demo))
    s.close()
    (r,) = pacs.audit([log])
    assert r.verdict == "pass", r.to_dict()


def moving_through(writer, q0, human, t_end=1.0, dt=0.001, speed=0.5):
    """Joint 1 turning at `speed` rad/s while a person stands at the start pose's gripper."""
    for k in range(int(t_end / dt) + 1):
        t = k * dt
        if k % 10 == 0:
            writer.human(t, t, human)
        q = q0.copy()
        q[0] += speed * t
        dq = np.zeros(7)
        dq[0] = speed
        writer.robot(t, q, dq)


def test_log_writer_round_trip_a_violation_fails(demo, tmp_path):
    log = tmp_path / "violating.jsonl"
    at_gripper = np.tile(demo.tool_point(demo.start), (9, 1))
    with pacs.LogWriter(log, robot="fr3", human="default", constraints="sorting",
                        meta={"operator": "test"}) as w:
        moving_through(w, demo.start, at_gripper)
        w.event(1.0, "success")
    (r,) = pacs.audit([log])
    assert r.verdict == "fail"
    assert r.violations and r.violations[0]["t_start"] <= 0.01
    assert r.meta["operator"] == "test"
    assert r.metrics["violation_fraction"] > 0.5


def test_log_writer_far_person_passes_and_a_gap_is_inconclusive(demo, tmp_path):
    far = tmp_path / "far.jsonl"
    person = np.tile([3.0, 0.0, 1.0], (9, 1))
    with pacs.LogWriter(far) as w:
        moving_through(w, demo.start, person, speed=0.1)
    assert pacs.audit(far)[0].verdict == "pass"
    gap = tmp_path / "gap.jsonl"
    with pacs.LogWriter(gap) as w:
        w.human(0.0, 0.0, person)
        w.robot(0.0, demo.start, np.zeros(7))
        w.human(5.0, 5.0, person)
        w.robot(5.0, demo.start, np.zeros(7))
    (r,) = pacs.audit(gap, config={"max_gap": 0.1})
    assert r.verdict == "inconclusive" and r.inconclusive


def test_audit_errors_name_file_and_field(tmp_path):
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"type": "header", "format": "pacs-log", "version": 1, "robot": "fr4", '
                   '"human": "default", "constraints": "sorting"}\n')
    with pytest.raises(pacs.InputError) as e:
        pacs.audit(bad)
    assert "bad.jsonl" in str(e.value) and "fr4" in str(e.value)
    with pytest.raises(pacs.InputError, match="missing.jsonl"):
        pacs.audit(tmp_path / "missing.jsonl")
    with pytest.raises(pacs.InputError, match="config"):
        pacs.audit(bad, config={"max_gapp": 1})
    with pytest.raises(pacs.ArgumentTypeError, match="paths"):
        pacs.audit(3)


def test_log_writer_refuses_bad_records(demo, tmp_path):
    with pacs.LogWriter(tmp_path / "w.jsonl") as w:
        w.robot(1.0, demo.start)
        with pytest.raises(pacs.InputError, match="backwards|before"):
            w.robot(0.5, demo.start)
        with pytest.raises(pacs.InputError, match=r"q\[3\]: value NaN"):
            w.robot(2.0, np.where(np.arange(7) == 3, np.nan, demo.start))
        with pytest.raises(pacs.InputError, match="ddq"):
            w.robot(2.0, demo.start, None, np.zeros(7))
        with pytest.raises(pacs.InputError, match="positions: shape"):
            w.human(2.0, 2.0, np.zeros((8, 3)))
        with pytest.raises(pacs.InputError, match="no object `ball`"):
            w.object(2.0, 2.0, "ball", [0, 0, 0])
    with pytest.raises(pacs.OutputError):
        pacs.LogWriter(tmp_path / "no" / "such" / "dir.jsonl")
    with pytest.raises(pacs.InputError, match="human: a log names at least one human"):
        pacs.LogWriter(tmp_path / "n.jsonl", human=None)
    with pytest.raises(pacs.ArgumentTypeError, match="path"):
        pacs.LogWriter(3)
    with pytest.raises(pacs.ArgumentTypeError, match="runs"):
        pacs.report([1], tmp_path)


def test_a_report_refuses_a_log_changed_since_its_audit(demo, tmp_path):
    """The report binds the verdict to the audited bytes: a log appended to after `audit` (here
    with a robot sample) is refused by `report` instead of certified with the new file's hash."""
    log = tmp_path / "shield.jsonl"
    shield_run(demo, log, steps=300)
    runs = pacs.audit(log)
    assert runs[0].verdict == "pass"
    with open(log, "a") as f:
        f.write('{"type":"event","t":9.0,"name":"tampered"}\n')
    with pytest.raises(pacs.InputError, match="changed since it was audited"):
        pacs.report(runs, tmp_path / "report")
    assert not (tmp_path / "report" / "report.json").exists()


def test_late_measurements_pending_at_close_are_logged(demo, tmp_path):
    """Frames that arrive after the last step but are stamped within the run (camera latency)
    are logged by `close()`: one showing the person at the gripper makes the run inconclusive
    instead of never reaching the audit."""
    from conftest import far_human

    log = tmp_path / "late.jsonl"
    s = logged_shield(demo, log)
    far = far_human(demo)
    for k in range(600):
        t = k * 0.001
        if k % 10 == 0:
            s.measure(t, far)
        s.step(t)
    s.measure(0.5995, np.tile(demo.tool_point(demo.start), (9, 1)))
    s.close()
    (r,) = pacs.audit([log])
    assert r.verdict != "pass", r.to_dict()
    assert r.metrics["human_records"] == 61


def test_settings_that_would_switch_checks_off_are_refused(tmp_path):
    """A rest speed above 0.05 rad/s would let SSM accept contact with a moving robot: refused
    by the shield and the audit. A config must be a dict (a list would fill fields in order)."""
    with pytest.raises(pacs.InputError, match="rest_speed"):
        pacs.Shield(robot="fr3", humans="default", constraints="sorting",
                    config={"rest_speed": 1e300})
    with pytest.raises(TypeError, match="config: expected a dict"):
        pacs.Shield(config=["off"])
    log = tmp_path / "any.jsonl"
    with pacs.LogWriter(log, robot="fr3", human="default", constraints="sorting",
                        objects=[{"id": "b", "object": "ball", "contact": "ssm"}]) as w:
        w.robot(0.0, np.array([0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398]))
        with pytest.raises(pacs.InputError, match="future"):
            w.object(0.0, 1.0, "b", [0.0, 0.0, 0.0])
    with pytest.raises(pacs.InputError, match="rest_speed"):
        pacs.audit(log, config={"rest_speed": 1.0})

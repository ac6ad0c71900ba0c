"""Several people in one audited run, and logs that cannot be cut short (log format v2)."""

import json

import numpy as np
import pytest

import pacs
from conftest import far_human


def two_person_shield(demo, path):
    s = pacs.Shield(robot="fr3", humans=["default", "default"], constraints="sorting", log=path)
    s.start(0.0, demo.start)
    deltas, h = demo.chunk(demo.start)
    s.set_chunk(deltas, t=0.0, h=h)
    return s


def two_person_run(demo, log, steps=600):
    """Both people 3 m away (1 m apart), measured every 10 ms; the shield closed."""
    s = two_person_shield(demo, log)
    far = far_human(demo)
    other = far + np.array([0.0, 1.0, 0.0])
    for k in range(steps):
        t = k * 0.001
        if k % 10 == 0:
            s.measure(t, far, human=0)
            s.measure(t, other, human=1)
        s.step(t)
    s.close()


def test_a_shield_with_two_people_is_logged_and_audited(demo, tmp_path):
    log = tmp_path / "two.jsonl"
    two_person_run(demo, log)
    lines = log.read_text().splitlines()
    header = json.loads(lines[0])
    assert header["version"] == 2 and header["end_event"] is True
    assert [p["id"] for p in header["humans"]] == ["human0", "human1"]
    assert json.loads(lines[-1]) == {"type": "event", "t": json.loads(lines[-1])["t"], "name": "end"}
    ids = {json.loads(l).get("id") for l in lines if '"type":"human"' in l}
    assert ids == {"human0", "human1"}
    (r,) = pacs.audit(log)
    d = r.to_dict()
    assert r.verdict == "pass", d["inconclusive"]
    assert d["people"] == ["human0", "human1"]
    assert d["evidence"]["completeness"] == "complete"


def test_a_person_at_the_gripper_fails_and_is_named(demo, tmp_path):
    log = tmp_path / "named.jsonl"
    at_gripper = np.tile(demo.tool_point(demo.start), (9, 1))
    far = far_human(demo)
    people = [{"id": "operator", "human": "default"}, {"id": "visitor", "human": "default"}]
    with pacs.LogWriter(log, robot="fr3", human=people, constraints="sorting") as w:
        for k in range(301):
            t = k * 0.001
            if k % 10 == 0:
                w.human(t, t, far, person="operator")
                w.human(t, t, at_gripper, person=1)
            q = demo.start.copy()
            q[0] += 0.5 * t
            w.robot(t, q, np.array([0.5, 0, 0, 0, 0, 0, 0.0]))
    (r,) = pacs.audit(log)
    assert r.verdict == "fail"
    assert {v["person"] for v in r.violations} == {"visitor"}
    # One log given twice would count twice in a report: refused, naming both paths.
    with pytest.raises(pacs.InputError, match=r"named\.jsonl: the same log as .*named\.jsonl"):
        pacs.audit([log, log])
    # Nor can a report count one run twice.
    with pytest.raises(pacs.InputError, match=r"runs: .*named\.jsonl is the same log as .*named\.jsonl"):
        pacs.report([r, r], tmp_path / "twice")
    # Whose measurement it is must be said with several people; bad `person` values are named.
    with pacs.LogWriter(tmp_path / "bad.jsonl", human=people) as w:
        with pytest.raises(pacs.InputError, match=r"person: required with several people"):
            w.human(0.0, 0.0, far)
        with pytest.raises(pacs.InputError, match=r"person: expected an id \(str\) or an index \(int ≥ 0\), got -1"):
            w.human(0.0, 0.0, far, person=-1)
        with pytest.raises(TypeError, match=r"person: expected an id .*got True"):
            w.human(0.0, 0.0, far, person=True)
        w.human(0.0, 0.0, far, person="operator")


def test_a_log_cut_short_is_inconclusive_not_pass(demo, tmp_path):
    log = tmp_path / "whole.jsonl"
    two_person_run(demo, log, steps=400)
    assert pacs.audit(log)[0].verdict == "pass"
    lines = log.read_text().splitlines(keepends=True)
    cut = tmp_path / "cut.jsonl"
    for keep in (len(lines) // 3, len(lines) - 1):
        cut.write_text("".join(lines[:keep]))
        (r,) = pacs.audit(cut)
        d = r.to_dict()
        assert r.verdict != "pass"
        assert d["evidence"]["completeness"] == "incomplete"
        assert any(s["reason"] == "incomplete_log" for s in d["inconclusive"])


def test_the_documented_loop_with_a_duplicate_measurement_passes(demo, tmp_path):
    """docs/python.md measures at t = 0 twice (an exact duplicate): no contradiction."""
    log = tmp_path / "doc.jsonl"
    shield = pacs.Shield(robot="fr3", humans="default", constraints="sorting",
                         config={"chunk_motion": "stop"}, log=log)
    shield.start(0.0, demo.start)
    shield.measure(0.0, demo.keypoints(0.0))
    deltas, h = demo.chunk(demo.start)
    shield.set_chunk(deltas, t=0.0, h=h)
    for k in range(1000):
        t = k * shield.safety_step
        if k % 33 == 0:
            shield.measure(t, demo.keypoints(t))
        shield.step(t)
    shield.close()
    (r,) = pacs.audit(log)
    assert r.verdict == "pass", r.to_dict()["inconclusive"]


def test_a_log_writer_never_closed_is_incomplete(demo, tmp_path):
    log = tmp_path / "open.jsonl"
    w = pacs.LogWriter(log)
    person = np.tile([3.0, 0.0, 1.0], (9, 1))
    w.human(0.0, 0.0, person)
    for k in range(11):
        w.robot(k * 0.001, demo.start, np.zeros(7))
    del w
    import gc

    gc.collect()
    (r,) = pacs.audit(log)
    assert r.verdict != "pass"


def test_the_log_records_the_filter_that_ran(demo, tmp_path):
    """meta.filter is the configured mode (reports group runs by it), as `pacs shield` writes."""
    for mode in ("pacs", "off"):
        log = tmp_path / f"{mode}.jsonl"
        s = pacs.Shield(config={"mode": mode}, log=log)
        s.start(0.0, demo.start)
        s.step(0.0)
        s.close()
        header = json.loads(log.read_text().splitlines()[0])
        assert header["meta"]["filter"] == mode


def test_one_named_person_keeps_its_id_and_bad_people_are_named(demo, tmp_path):
    log = tmp_path / "one.jsonl"
    s = pacs.Shield(robot="fr3", humans=[{"id": "operator", "human": "default"}],
                    constraints="sorting", log=log)
    s.start(0.0, demo.start)
    s.measure(0.0, far_human(demo))
    s.step(0.0)
    s.close()
    header = json.loads(log.read_text().splitlines()[0])
    assert [p["id"] for p in header["humans"]] == ["operator"]
    # `Shield.header` is the header the log holds, its start and end promises included.
    assert s.header == header
    assert header["start_event"] is True and header["end_event"] is True
    (r,) = pacs.audit(log)
    assert r.people == ["operator"]
    assert r.evidence["completeness"] == "complete"
    # An unnamed person's id skips one given to another person.
    log2 = tmp_path / "mixed.jsonl"
    s = pacs.Shield(robot="fr3", humans=[{"id": "human1", "human": "default"}, "default"],
                    constraints="sorting", log=log2)
    s.start(0.0, demo.start)
    s.close()
    header = json.loads(log2.read_text().splitlines()[0])
    assert [p["id"] for p in header["humans"]] == ["human1", "human2"]
    # A person alone (not in a list) is one person too.
    s = pacs.Shield(robot="fr3", humans={"id": "solo", "human": "default"}, constraints="sorting")
    assert s.humans == 1
    # Bad people: what is wrong is named, not blamed on the id.
    bad = [
        ([{"id": "A", "human": "default", "x": 1}], r"humans\[0\]: unknown key `x`"),
        ([{"id": "A"}], r"humans\[0\]\.human: missing"),
        ([{"id": "A,B", "human": "default"}], r"A,B.* is not a valid person id"),
        ([{"id": "a/b", "human": "default"}], r"a/b.* is not a valid person id"),
    ]
    for humans, message in bad:
        with pytest.raises(pacs.InputError, match=message):
            pacs.Shield(robot="fr3", humans=humans, constraints="sorting")


def test_a_log_writer_left_by_an_exception_is_incomplete(demo, tmp_path):
    """Leaving the `with` block by an exception writes no `end`: the run was cut short."""
    log = tmp_path / "raised.jsonl"
    person = np.tile([3.0, 0.0, 1.0], (9, 1))
    with pytest.raises(RuntimeError, match="the policy crashed"):
        with pacs.LogWriter(log) as w:
            w.human(0.0, 0.0, person)
            for k in range(11):
                w.robot(k * 0.001, demo.start, np.zeros(7))
            raise RuntimeError("the policy crashed")
    assert '"name":"end"' not in log.read_text()
    (r,) = pacs.audit(log)
    assert r.verdict == "inconclusive"
    assert r.evidence["completeness"] == "incomplete"
    # The same loop left normally: complete, and it passes.
    with pacs.LogWriter(tmp_path / "ok.jsonl") as w:
        w.human(0.0, 0.0, person)
        for k in range(11):
            w.robot(k * 0.001, demo.start, np.zeros(7))
    (r,) = pacs.audit(tmp_path / "ok.jsonl")
    assert r.verdict == "pass", r.inconclusive

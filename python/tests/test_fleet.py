"""pacs.fleet: a fleet's archive audited locally in parallel and on a Dask LocalCluster (two
worker processes) gives the same runs and the same fleet report, equal to `pacs audit DIR --out`'s
report.json `fleet`; runs pickle whole; pacs.simulate on Dask equals the local run of the same
seeds; bad input is named."""

import json
import os
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pacs

distributed = pytest.importorskip("dask.distributed")

ROOT = Path(__file__).resolve().parents[2]
# 2026-11-28T12:00:00Z: the modification time of the archive's log without a date in its header.
MTIME = 1_795_867_200


def write_log(path, q0, person, meta, seconds=0.2, human=True):
    """Joint 1 turning at 0.3 rad/s for `seconds` at 1 kHz, `person` (keypoints) measured every
    10 ms (never if not `human`)."""
    with pacs.LogWriter(path, robot="fr3", human="default", constraints="ssm", meta=meta) as w:
        for k in range(int(round(seconds / 0.001)) + 1):
            t = k * 0.001
            if human and k % 10 == 0:
                w.human(t, t, person)
            q = q0.copy()
            q[0] += 0.3 * t
            dq = np.zeros(7)
            dq[0] = 0.3
            w.robot(t, q, dq)


@pytest.fixture(scope="module")
def archive(tmp_path_factory):
    """Four logs of two robots on three days (a date, an RFC 3339 start time, the file's mtime),
    one in a subdirectory, beside files that are not logs."""
    demo = pacs.Demo("sorting", seed=1)
    far = np.tile([3.0, 0.0, 1.0], (9, 1))
    at_gripper = np.tile(demo.tool_point(demo.start), (9, 1))
    a = tmp_path_factory.mktemp("fleet") / "archive"
    (a / "2026-11-27").mkdir(parents=True)
    arm1 = {"robot_id": "arm-1", "task": "sorting", "date": "2026-11-27"}
    write_log(a / "2026-11-27" / "arm1-pass.jsonl", demo.start, far, arm1)
    write_log(a / "2026-11-27" / "arm1-fail.jsonl", demo.start, at_gripper, arm1)
    arm2 = {"robot_id": "arm-2", "task": "packing"}
    write_log(a / "arm2-fail.jsonl", demo.start, at_gripper,
              {**arm2, "start_time": "2026-11-28T23:30:00-05:00"}, seconds=0.3)
    write_log(a / "arm2-inconclusive.jsonl", demo.start, far, arm2, human=False)
    os.utime(a / "arm2-inconclusive.jsonl", (MTIME, MTIME))
    (a / "notes.txt").write_text("not a log")
    (a / "header.json").write_text("{}")
    return a


LOGS = ["2026-11-27/arm1-fail.jsonl", "2026-11-27/arm1-pass.jsonl", "arm2-fail.jsonl",
        "arm2-inconclusive.jsonl"]


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as c:
            yield c


def as_json(runs):
    return json.dumps([r.to_dict() for r in runs], sort_keys=True)


def report_files(runs, out):
    """report.json without its generation time, and report.md without its date line."""
    pacs.report(runs, out)
    doc = json.loads((out / "report.json").read_text())
    doc.pop("generated_utc")
    md = [l for l in (out / "report.md").read_text().splitlines() if "Generated" not in l]
    return doc, md


@pytest.fixture(scope="module")
def local(archive):
    return pacs.fleet.audit(str(archive))


def test_the_local_audit_runs_every_log_in_path_order_with_the_fleet_report(archive, local):
    runs, report = local
    assert [r.log for r in runs] == [str(archive / f) for f in LOGS]
    assert [r.verdict for r in runs] == ["fail", "pass", "fail", "inconclusive"]
    # Each run is pacs.audit's run of that log.
    for r in runs:
        assert r.to_dict() == pacs.audit(r.log)[0].to_dict()
    groups = [(g["robot"], g["scene"], g["day"], g["runs"], g["pass"], g["fail"], g["inconclusive"])
              for g in report["groups"]]
    assert groups == [
        ("arm-1", "sorting", "2026-11-27", 2, 1, 1, 0),
        ("arm-2", "packing", "2026-11-28", 1, 0, 0, 1),  # the file's mtime
        ("arm-2", "packing", "2026-11-29", 1, 0, 1, 0),  # 23:30 at UTC-5 is the 29th in UTC
    ]
    assert [r["day_source"] for r in report["runs"]] == [
        "meta.date", "meta.date", "meta.start_time", "file_mtime"]
    # Violation time: the union of each run's violation intervals.
    for r, placed in zip(runs, report["runs"]):
        spans = sorted((v["t_start"], v["t_end"]) for v in r.violations)
        union, cur = 0.0, None
        for s, e in spans:
            if cur is not None and s <= cur[1]:
                cur = (cur[0], max(cur[1], e))
            else:
                if cur is not None:
                    union += cur[1] - cur[0]
                cur = (s, e)
        if cur is not None:
            union += cur[1] - cur[0]
        assert placed["violation_time_s"] == union
    assert report["runs"][2]["violation_time_s"] > report["runs"][0]["violation_time_s"] > 0
    assert [w["log"] for w in report["worst"]] == [runs[2].log, runs[0].log]
    assert report["total"]["runs"] == 4 and report["total"]["fail"] == 2


def test_dask_gives_the_same_runs_and_report_as_the_local_audit(archive, local, client, tmp_path):
    on_dask = pacs.fleet.audit(str(archive), client=client)
    assert as_json(on_dask.runs) == as_json(local.runs)
    assert json.dumps(on_dask.report) == json.dumps(local.report)
    # The runs came back whole: their reports (plot series, hashes, model parameters) are equal.
    assert report_files(on_dask.runs, tmp_path / "dask") == report_files(local.runs, tmp_path / "local")
    # Any batch size: the same runs in the same order.
    for batch in (1, 3):
        assert as_json(pacs.fleet.audit(archive, client=client, batch=batch).runs) == \
            as_json(local.runs)
    # A list of files in another order is audited in that order, as `pacs audit` does.
    files = [str(archive / f) for f in reversed(LOGS)]
    assert [r.log for r in pacs.fleet.audit(files, client=client).runs] == files


def cli():
    """The `pacs` binary of this checkout, built as `cargo test --workspace` builds it (so a
    no-op after ./test.sh's `cargo test --workspace`; the same units, features unified over
    the workspace)."""
    out = subprocess.run(
        ["cargo", "test", "-q", "--workspace", "--no-run", "--message-format=json"],
        cwd=ROOT, check=True, capture_output=True, text=True).stdout
    for line in out.splitlines():
        msg = json.loads(line)
        target = msg.get("target", {})
        # The binary itself, not the test harness cargo also builds from the bin target
        # (same name and kind, `profile.test` true).
        if msg.get("reason") == "compiler-artifact" and target.get("name") == "pacs" \
                and "bin" in target.get("kind", []) and not msg.get("profile", {}).get("test"):
            return msg["executable"]
    raise AssertionError("cargo built no `pacs` binary")


def test_the_cli_fleet_section_equals_pythons(archive, local, tmp_path):
    out = tmp_path / "report"
    done = subprocess.run([cli(), "audit", str(archive), "--json", "--out", str(out)],
                          capture_output=True, text=True)
    assert done.returncode == 1, done.stderr
    cli_runs = json.loads(done.stdout)["runs"]
    assert [r["log"] for r in cli_runs] == [r.log for r in local.runs]
    # Each run's dict is what the CLI prints for it, episodes included.
    assert any(r["episodes"] for r in cli_runs)
    assert cli_runs == [r.to_dict() for r in local.runs]
    assert [r.episodes for r in local.runs] == [r["episodes"] for r in cli_runs]
    assert json.loads((out / "report.json").read_text())["fleet"] == local.report
    assert "## Fleet (per robot, scene and day)" in (out / "report.md").read_text()


def test_a_pickled_run_is_the_whole_run(local, tmp_path):
    runs = local.runs
    back = pickle.loads(pickle.dumps(runs))
    assert as_json(back) == as_json(runs)
    assert report_files(back, tmp_path / "b") == report_files(runs, tmp_path / "a")
    with pytest.raises(pacs.InputError, match="state: not a pacs Run state"):
        pacs.fleet._run_from_state(b"\x00garbage")
    with pytest.raises(pacs.ArgumentTypeError, match="state: expected the bytes"):
        pacs.fleet._run_from_state("text")


def test_bad_input_is_named(archive, client, tmp_path):
    missing = tmp_path / "missing"
    for c in (None, client):
        with pytest.raises(pacs.InputError, match=re.escape(str(missing))):
            pacs.fleet.audit(missing, client=c)
    empty = tmp_path / "empty"
    (empty / "sub").mkdir(parents=True)
    with pytest.raises(pacs.InputError, match=re.escape(f"{empty}: a directory without log files")):
        pacs.fleet.audit(empty)
    with pytest.raises(pacs.ArgumentTypeError, match="client: .*str 'tcp://localhost:8786'"):
        pacs.fleet.audit(archive, client="tcp://localhost:8786")
    with pytest.raises(pacs.ArgumentTypeError, match="paths: expected a path"):
        pacs.fleet.audit(3)
    with pytest.raises(pacs.InputError, match="paths: no log given"):
        pacs.fleet.audit([])
    with pytest.raises(pacs.InputError, match="batch: must be at least 1, got 0"):
        pacs.fleet.audit(archive, client=client, batch=0)
    with pytest.raises(pacs.InputError, match="batch: only with a client"):
        pacs.fleet.audit(archive, batch=2)
    with pytest.raises(pacs.InputError, match="threads: must be at least 1, got 0"):
        pacs.fleet.audit(archive, threads=0)
    # An invalid log among good ones: the worker's error names it.
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "a.jsonl").write_bytes((archive / "arm2-fail.jsonl").read_bytes())
    (bad / "b.jsonl").write_text('{"type": "header", "format": "pacs-log", "version": 1, '
                                 '"robot": "fr4", "human": "default", "constraints": "ssm"}\n')
    for c in (None, client):
        with pytest.raises(pacs.InputError, match=r"b\.jsonl.*fr4"):
            pacs.fleet.audit(bad, client=c)
    # Several invalid logs in batches of one (tasks that may fail in any order): the first in path
    # order is raised, on the cluster as locally.
    for name in ("c.jsonl", "d.jsonl", "e.jsonl"):
        (bad / name).write_text("not json\n")
    for _ in range(3):
        with pytest.raises(pacs.InputError, match=r"b\.jsonl.*fr4"):
            pacs.fleet.audit(bad, client=client, batch=1)
    # A log given twice would count twice: refused, naming both paths.
    with pytest.raises(pacs.InputError, match=r"a\.jsonl: the same log as .*a\.jsonl"):
        pacs.fleet.audit([bad, bad / "a.jsonl"])


def test_simulate_on_dask_equals_the_local_run_of_the_same_seeds(client):
    args = dict(task="sorting", method=["pacs", "off"], rollouts=5, seed=3)
    here = pacs.simulate(**args)
    assert [(r["method"], r["seed"]) for r in here["rollouts"]] == \
        [("off", s) for s in range(3, 8)] + [("pacs", s) for s in range(3, 8)]
    assert [(r["method"], r["rollouts"]) for r in here["rows"]] == [("off", 5), ("pacs", 5)]
    assert json.dumps(pacs.simulate(**args, threads=1)) == json.dumps(here)
    for partitions in (None, 3, 5):
        on_dask = pacs.simulate(**args, client=client, partitions=partitions)
        assert json.dumps(on_dask) == json.dumps(here), partitions
    # Other seeds give other rollouts.
    assert json.dumps(pacs.simulate(**{**args, "seed": 4})) != json.dumps(here)
    # The same seeds as a list, in any order, locally or split over the cluster.
    listed = dict(task="sorting", method=["pacs", "off"], seeds=[7, 3, 5, 4, 6])
    assert json.dumps(pacs.simulate(**listed)) == json.dumps(here)
    assert json.dumps(pacs.simulate(**listed, client=client, partitions=2)) == json.dumps(here)
    # Seeds with gaps: each rollout as in a run of its own seed.
    gaps = pacs.simulate(task="sorting", method="pacs", seeds=[9, 3], client=client)
    assert [r["seed"] for r in gaps["rollouts"]] == [3, 9]
    assert gaps["rollouts"][0] == here["rollouts"][5]


def test_simulate_names_bad_input(client):
    with pytest.raises(pacs.InputError, match="task: unknown task `sortng`"):
        pacs.simulate(task="sortng", client=client)
    with pytest.raises(pacs.InputError, match="method: unknown method `pax`"):
        pacs.simulate(method="pacs,pax")
    with pytest.raises(pacs.InputError, match="rollouts: must be at least 1, got 0"):
        pacs.simulate(rollouts=0)
    with pytest.raises(pacs.ArgumentTypeError, match="seed: expected an int, got 1.5"):
        pacs.simulate(seed=1.5)
    with pytest.raises(pacs.InputError, match="partitions: must be at least 1, got 0"):
        pacs.simulate(rollouts=2, client=client, partitions=0)
    with pytest.raises(pacs.ArgumentTypeError, match="client: expected None or a dask.distributed.Client, got int 7"):
        pacs.simulate(client=7)
    with pytest.raises(pacs.InputError, match="seeds: seed 3 is given twice"):
        pacs.simulate(seeds=[3, 4, 3])
    # A task or method named twice would count its rollouts twice.
    with pytest.raises(pacs.InputError, match="task: `sorting` is given twice"):
        pacs.simulate(task="sorting,sorting")
    with pytest.raises(pacs.InputError, match="method: `pacs` is given twice"):
        pacs.simulate(method=["pacs", "off", "pacs"])
    with pytest.raises(pacs.InputError, match="seeds: give either seeds or rollouts"):
        pacs.simulate(seeds=[3], rollouts=2)
    with pytest.raises(pacs.ArgumentTypeError, match=r"seeds\[1\]: expected an int, got 'x'"):
        pacs.simulate(seeds=[3, "x"])
    with pytest.raises(pacs.InputError, match=r"seeds\[0\]: must be at least 0, got -1"):
        pacs.simulate(seeds=[-1])
    with pytest.raises(pacs.InputError, match="chunk_motion: unknown `smooth`"):
        pacs.simulate(chunk_motion="smooth")
    for bad in (0, -1.0, float("nan"), float("inf"), 3600.5):
        with pytest.raises(pacs.InputError, match=r"time_limit: expected seconds in \(0, 3600\]"):
            pacs.simulate(rollouts=1, time_limit=bad)
        with pytest.raises(pacs.InputError, match="time_limit: expected seconds"):
            pacs.simulate(rollouts=1, time_limit=bad, policy=DemoSetPolicy())
    with pytest.raises(pacs.ArgumentTypeError, match="time_limit: expected seconds, got '5'"):
        pacs.simulate(time_limit="5")


def test_simulate_time_limit_ends_every_rollout_there(client):
    """Sorting takes seconds: at a 0.3 s limit every rollout fails there, with the built-in
    policy (locally and on Dask) and with a policy object alike; a limit above the task's own
    changes no rollout that ended before it."""
    args = dict(task="sorting", method=["off", "pacs"], rollouts=2)
    for run in (pacs.simulate(**args, time_limit=0.3),
                pacs.simulate(**args, time_limit=0.3, client=client),
                pacs.simulate(**args, time_limit=0.3, policy=DemoSetPolicy())):
        assert len(run["rollouts"]) == 4
        for r in run["rollouts"]:
            assert r["episode"]["duration"] == 0.3 and not r["episode"]["success"], r["episode"]
    own, longer = pacs.simulate(**args), pacs.simulate(**args, time_limit=40)
    for a, b in zip(own["rollouts"], longer["rollouts"]):
        if a["episode"]["success"]:
            assert a == b


class DemoSetPolicy:
    """The built-in `nearest` policy as a policy object: pacs.Demo's chunks for the rollout's
    task and seed (a fresh one per rollout), 8 executed actions."""

    n_action_steps = 8

    def __init__(self):
        self.demo = None
        self.calls = 0

    def reset(self):
        self.demo = None

    def act(self, obs):
        if self.demo is None:
            self.demo = pacs.Demo(obs["task"], seed=obs["seed"])
        assert obs["person"].shape[1] == 3 and len(obs["tool"]) == 3
        self.calls += 1
        deltas, h = self.demo.chunk(obs["q"])
        assert h == self.n_action_steps
        return deltas

    def __getstate__(self):  # a pacs.Demo is not pickled: rebuilt per rollout
        return {"demo": None, "calls": self.calls}


def same_rollouts(a, b):
    """The rollouts agree in everything but the policy's name."""
    strip = [{**r, "policy": None} for r in a["rollouts"]]
    return json.dumps(strip) == json.dumps([{**r, "policy": None} for r in b["rollouts"]])


def test_a_policy_object_runs_as_the_built_in_policy_does(client):
    """A Python policy object that returns the built-in policy's chunks gives exactly the
    built-in policy's rollouts (success, times, violations, deviation, OOD chunks, audit),
    here, and on Dask (the object pickled to the workers)."""
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    args = dict(task="sorting", method=["off", "pacs"], seeds=[1, 2])
    built_in = pacs.simulate(**args, policy="nearest")
    p = DemoSetPolicy()
    ticks = []
    external = pacs.simulate(**args, policy=p, progress=lambda d, n: ticks.append((d, n)))
    assert ticks == [(1, 4), (2, 4), (3, 4), (4, 4)]
    assert p.calls >= 8
    assert [r["policy"] for r in external["rollouts"]] == ["external"] * 4
    assert [r["policy"] for r in external["rows"]] == ["external"] * 2
    assert [r["policy"] for r in built_in["rows"]] == ["nearest"] * 2
    assert same_rollouts(external, built_in)
    on_dask = pacs.simulate(**args, policy=DemoSetPolicy(), client=client, partitions=2)
    assert json.dumps(on_dask) == json.dumps(external)


def test_a_policy_objects_errors_are_raised():
    class Broken:
        def act(self, obs):
            raise ValueError("no chunk today")

    class Wrong:
        def act(self, obs):
            return np.zeros((4, 6))

    with pytest.raises(ValueError, match="no chunk today"):
        pacs.simulate("sorting", "pacs", seeds=[1], policy=Broken())
    with pytest.raises(pacs.InputError, match=r"policy.act: expected a non-empty \(H, 7\)"):
        pacs.simulate("sorting", "pacs", seeds=[1], policy=Wrong())
    with pytest.raises(pacs.ArgumentTypeError, match="policy: expected a name or an object"):
        pacs.simulate("sorting", "pacs", seeds=[1], policy=3)
    with pytest.raises(pacs.InputError, match="threads: a policy object"):
        pacs.simulate("sorting", "pacs", seeds=[1], policy=Wrong(), threads=2)


def test_tolerance_stops_the_robot_and_measures_success(tmp_path):
    """The intruder's hand stops the shield on the policy's own path; the nearest-neighbour
    policy (it sees only the joint angles) still finishes; a policy object that returns its
    chunks gives the same runs; the one-page plot is written; bad input is named."""
    svg = tmp_path / "t.svg"
    res = pacs.tolerance("nearest", "sorting", holds=[0.5, 2.0], at=[0.4], seeds=[1, 2],
                         plot=svg)
    assert [r["hold_s"] for r in res["rows"]] == [0.0, 0.5, 2.0]
    assert [r["rollouts"] for r in res["rows"]] == [2, 2, 2]
    assert all(r["success"] == 1.0 for r in res["rows"])
    for run in res["runs"]:
        assert run["stopped"] > 0.3 * run["hold"] and run["violation_fraction"] == 0.0
        assert run["duration"] >= run["baseline_duration"]
    by_hold = {r["hold_s"]: r for r in res["rows"]}
    assert by_hold[2.0]["mean_stopped_s"] > by_hold[0.5]["mean_stopped_s"]
    assert by_hold[2.0]["mean_extra_duration_s"] > 0.5
    text = svg.read_text()
    assert text.startswith("<svg") and "Tolerance to being stopped" in text
    obj = pacs.tolerance(DemoSetPolicy(), "sorting", holds=[0.5, 2.0], at=[0.4], seeds=[1, 2])
    assert obj["runs"] == res["runs"]
    with pytest.raises(pacs.InputError, match="does not brake along the path"):
        pacs.tolerance("nearest", "sorting", method="off", seeds=[1])
    with pytest.raises(pacs.InputError, match=r"at\[0\]: 1.5"):
        pacs.tolerance("nearest", "sorting", at=[1.5], seeds=[1])
    with pytest.raises(pacs.InputError, match=r"holds\[1\]"):
        pacs.tolerance("nearest", "sorting", holds=[1.0, -1.0], seeds=[1])


def test_the_tolerance_cli(tmp_path):
    out = tmp_path / "tol"
    p = subprocess.run([sys.executable, "-m", "pacs", "tolerance", "--policy", "nearest",
                        "--rollouts", "1", "--holds", "1", "--at", "0.5", "--out", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "hold    1 s: success 1.00" in p.stdout
    assert json.loads((out / "tolerance.json").read_text())["rows"][1]["hold_s"] == 1.0
    assert (out / "tolerance.svg").exists()
    bad = subprocess.run([sys.executable, "-m", "pacs", "tolerance", "--method", "cbf",
                          "--rollouts", "1", "--out", str(out)], capture_output=True, text=True)
    assert bad.returncode == 2 and "does not brake" in bad.stderr

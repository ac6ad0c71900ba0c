"""ROS 2 sqlite3 bags written by rosbags (PyPI; an independent writer) audited by pacs.audit:
a fresh bag directory, its lone .db3 file, and a bag with a violation; a report on a bag
directory; a bag without a header is an InputError."""

import json
import sys
from pathlib import Path

import pytest

import pacs

pytest.importorskip("rosbags")
sys.path.insert(0, str(Path(__file__).parent / "fixtures"))
import make_db3_bags as bags  # noqa: E402


def test_a_fresh_clean_bag_passes(tmp_path):
    bag = bags.write_bag(tmp_path / "clean", bags.messages(violation=False, mapped=False))
    runs = pacs.audit(bag)
    r = runs[0]
    assert r.verdict == "pass", r.to_dict()
    assert r.metrics["samples"] == bags.N + 1
    assert r.metrics["duration"] == 1.0
    assert r.meta["db3_time_base_s"] == 1_700_000_000
    # The lone .db3 file (its header in the db's metadata table) gives the same run.
    lone = pacs.audit(bag / "clean.db3")[0]
    assert lone.verdict == "pass" and lone.metrics == r.metrics
    assert pacs.report(runs, tmp_path / "report") == "pass"
    assert (tmp_path / "report" / "report.json").exists()


def test_a_fresh_bag_with_a_person_stepping_in_fails_at_the_step(tmp_path):
    msgs = bags.messages(violation=True, mapped=True, near_from=60)
    r = pacs.audit(bags.write_bag(tmp_path / "v", msgs))[0]
    assert r.verdict == "fail"
    assert min(v["t_start"] for v in r.violations) == 0.6


def test_a_bag_without_a_header_needs_one_given(tmp_path):
    bag = bags.write_bag(tmp_path / "nohdr", bags.messages(violation=False, mapped=False), header=None)
    with pytest.raises(pacs.InputError, match="missing header"):
        pacs.audit(bag)
    # Given as a dict or a file (as `pacs audit --header`).
    assert pacs.audit(bag, header=bags.HEADER)[0].verdict == "pass"
    f = tmp_path / "header.json"
    f.write_text(json.dumps(dict(bags.HEADER, constraints="handover")))
    r = pacs.audit(bag, header=f)[0]
    assert r.verdict == "pass" and r.models["constraints"] == "handover"
    with pytest.raises(pacs.InputError, match="header: header.version: 7 is not supported"):
        pacs.audit(bag, header=dict(bags.HEADER, version=7))
    with pytest.raises(TypeError, match="header: expected None, a dict or a path"):
        pacs.audit(bag, header=3)
    # A JSON Lines log carries its own header.
    log = tmp_path / "run.jsonl"
    log.write_text(json.dumps(bags.HEADER) + "\n")
    with pytest.raises(pacs.InputError, match="applies to MCAP logs and ROS 2 bags only"):
        pacs.audit(log, header=bags.HEADER)


def test_fresh_bags_in_the_mcap_storage_audit_as_the_sqlite3_ones(tmp_path):
    # rosbags writes the same runs in the MCAP storage (ROS 2 Iron's and Jazzy's default): the
    # bag directory is one log, named by the directory, with the sqlite3 bag's result.
    from rosbags.rosbag2 import StoragePlugin

    for violation in (False, True):
        msgs = bags.messages(violation=violation, mapped=violation)
        mcap_bag = bags.write_bag(tmp_path / f"mcap{violation}", msgs, storage=StoragePlugin.MCAP)
        db3_bag = bags.write_bag(tmp_path / f"db3{violation}", msgs)
        a = pacs.audit(mcap_bag)[0]
        b = pacs.audit(db3_bag)[0]
        assert a.verdict == ("fail" if violation else "pass")
        assert a.log == str(mcap_bag)
        assert a.metrics == b.metrics and a.violations == b.violations
        assert a.meta["mcap_time_base_s"] == 1_700_000_000


def test_a_fresh_bag_with_zstd_message_compression_reads_as_the_uncompressed_one(tmp_path):
    # rosbag2's `--compression-mode message --compression-format zstd`, written by rosbags.
    msgs = bags.messages(violation=True, mapped=True)
    a = pacs.audit(bags.write_bag(tmp_path / "z", msgs, zstd_messages=True))[0]
    b = pacs.audit(bags.write_bag(tmp_path / "plain", msgs))[0]
    assert a.verdict == "fail"
    assert a.metrics == b.metrics and a.violations == b.violations

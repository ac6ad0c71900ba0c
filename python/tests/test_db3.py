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


FIXTURES = Path(__file__).parent / "fixtures" / "db3"


def test_one_part_of_a_split_bag_is_not_the_run(tmp_path):
    """split/ fails as a whole; its first part alone would pass: refused, naming the bag."""
    assert pacs.audit(FIXTURES / "split")[0].verdict == "fail"
    with pytest.raises(pacs.InputError, match=r"one of 2 parts of the bag .*audit the bag directory"):
        pacs.audit(FIXTURES / "split" / "split_0.db3")


def test_a_bag_whose_files_contradict_its_metadata_is_refused(tmp_path):
    """Rows cut from a file (the metadata still counting them), and a part taken out of
    relative_file_paths but still listed in `files`: refused, never audited as the run."""
    import shutil
    import sqlite3

    bag = bags.write_bag(tmp_path / "cut", bags.messages(violation=True, mapped=True, near_from=60))
    assert pacs.audit(bag)[0].verdict == "fail"
    db = sqlite3.connect(bag / "cut.db3")
    (n,) = db.execute("SELECT count(*) FROM messages").fetchone()
    db.execute("DELETE FROM messages WHERE id > ?", (n // 2,))
    db.commit()
    db.close()
    with pytest.raises(pacs.InputError, match=rf"metadata counts {n} messages in this file.*holds {n // 2}"):
        pacs.audit(bag)
    # The second part of a split bag dropped from relative_file_paths only.
    split = tmp_path / "split"
    shutil.copytree(FIXTURES / "split", split)
    meta = (split / "metadata.yaml").read_text()
    assert "- split_1.db3" in meta
    (split / "metadata.yaml").write_text(meta.replace("  - split_1.db3\n", "", 1))
    (split / "split_1.db3").unlink()
    with pytest.raises(pacs.InputError, match=r"contradicts itself: files\[1\]\.path `split_1\.db3`"):
        pacs.audit(split)


def test_a_fleet_of_bags_without_a_header_takes_one(tmp_path):
    """A bag without a pacs header (as ROS 2 Humble records) beside a JSON Lines log: the given
    header is for the bag, the JSON Lines log keeps its own; a bag's day is its recording's."""
    archive = tmp_path / "archive"
    archive.mkdir()
    bags.write_bag(archive / "bag", bags.messages(violation=False, mapped=False), header=None)
    log = archive / "run.jsonl"
    with pacs.LogWriter(log, meta={"date": "2026-11-28"}) as w:
        w.human(0.0, 0.0, [[3.0, 0.0, 1.0]] * 9)
        for k in range(11):
            w.robot(k * 0.001, [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785], [0.0] * 7)
    with pytest.raises(pacs.InputError, match="missing header"):
        pacs.fleet.audit(archive)
    runs, report = pacs.fleet.audit(archive, header=bags.HEADER)
    assert [r.verdict for r in runs] == ["pass", "pass"], [r.to_dict()["inconclusive"] for r in runs]
    days = {Path(r["log"]).name: (r["day"], r["day_source"]) for r in report["runs"]}
    assert days["bag"] == ("2023-11-14", "meta.db3_time_base_s")
    assert days["run.jsonl"] == ("2026-11-28", "meta.date")

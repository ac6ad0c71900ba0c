"""ShieldLoop: the step loop on a Rust thread, in real time and in simulated time."""

import time

import numpy as np
import pytest

import pacs
from conftest import far_human


def test_simulated_loop_matches_direct_steps(demo):
    deltas, h = demo.chunk(demo.start)
    person = far_human(demo)

    direct = pacs.Shield()
    direct.start(0.0, demo.start)
    direct.measure(0.0, person)
    direct.set_chunk(deltas, t=0.0, h=h)
    ref = [direct.step(k * 0.001) for k in range(300)]

    s = pacs.Shield()
    s.start(0.0, demo.start)
    s.measure(0.0, person)
    loop = pacs.ShieldLoop(s, realtime=False)
    loop.start()
    loop.set_chunk(deltas, h=h, t=0.0)
    loop.run_until(0.2995)
    out = loop.commands()
    assert out["q"].shape == (300, 7) and out["t"].shape == (300,)
    np.testing.assert_allclose(out["t"], [c.t for c in ref])
    np.testing.assert_array_equal(out["q"], np.array([c.q for c in ref]))
    assert out["verified"].all()
    assert loop.stats()["steps"] == 300
    with pytest.raises(pacs.NotStartedError, match="ShieldLoop"):
        s.step(1.0)
    loop.stop()
    s.step(loop.time + 0.001)  # direct steps again after stop
    # The same loop again, in simulated time, after stop.
    loop.run_until(0.31)
    assert loop.stats()["steps"] >= 310
    loop.stop()


def test_a_unix_time_clock_keeps_the_grid(demo):
    t0 = 1.7e9  # time.time()-like start: ulps of 2.4e-7 s
    s = pacs.Shield()
    s.start(t0, demo.start)
    s.measure(t0, far_human(demo))
    for k in range(50):
        s.step(t0 + k * 0.001)
    loop = pacs.ShieldLoop(s, realtime=False)
    loop.start()
    loop.run_until(t0 + 0.5)
    assert loop.stats()["steps"] == 451
    loop.stop()


def test_one_loop_per_shield_and_bounded_runs(demo):
    s = pacs.Shield()
    s.start(0.0, demo.start)
    a = pacs.ShieldLoop(s, realtime=False)
    b = pacs.ShieldLoop(s, realtime=False)
    a.start()
    with pytest.raises(pacs.NotStartedError, match="another ShieldLoop"):
        b.start()
    with pytest.raises(pacs.InputError, match="steps ahead"):
        a.run_until(1e300)
    a.stop()
    b.start()
    b.run_until(0.01)
    b.stop()
    with pytest.raises(pacs.InputError, match="human: value -1 is negative"):
        a.measure(0.0, far_human(demo), human=-1)
    with pytest.raises(pacs.ArgumentTypeError, match="history"):
        pacs.ShieldLoop(s, history="many")


def test_realtime_loop_steps_at_the_safety_rate(demo):
    s = pacs.Shield()
    s.start(0.0, demo.start)
    s.measure(0.0, far_human(demo))
    with pacs.ShieldLoop(s, realtime=True) as loop:
        deltas, h = demo.chunk(demo.start)
        loop.set_chunk(deltas, h=h)
        time.sleep(0.3)
        c = loop.latest()
        p = loop.progress()
    st = loop.stats()
    # 0.3 s at 1 kHz: about 300 steps (the thread keeps the grid t_k = t_0 + k·α_s).
    assert 150 <= st["steps"] <= 400, st
    assert c is not None and c.chunk == 1 and p["accepted"] == 1
    out = loop.commands()
    np.testing.assert_allclose(np.diff(out["t"]), 0.001, atol=1e-12)


def test_realtime_chunks_are_handed_over_while_moving(demo):
    """Chunks handed to a running real-time loop are planned off the loop from the state a few
    steps ahead and taken over there: each returns its serial once a step took it over, and the
    commands never jump (FR3's joint limits: libfranka's velocities, 10 rad/s²)."""
    s = pacs.Shield(config={"chunk_motion": "continuous"})
    s.start(0.0, demo.start)
    s.measure(0.0, far_human(demo))
    serials = []
    with pacs.ShieldLoop(s, realtime=True, history=100_000) as loop:
        deltas, h = demo.chunk(demo.start)
        serials.append(loop.set_chunk(deltas, h=h))
        for _ in range(12):
            time.sleep(0.03)
            loop.measure(loop.time, far_human(demo))
            c = loop.latest()
            assert c.dq.any(), "moving when the next chunk comes"
            deltas, h = demo.chunk(c.q)
            n = loop.set_chunk(deltas, h=h)
            # Returned once a step took it over: the commands follow it (or a newer one).
            assert loop.progress()["chunk"] >= n
            serials.append(n)
        out = loop.commands()
    assert serials == list(range(1, 14)), serials
    v_max = np.array([2.62, 2.62, 2.62, 2.62, 5.26, 4.18, 5.26])
    dq = np.abs(np.diff(out["q"], axis=0))
    assert (dq <= v_max * 1e-3 + 1e-12).all(), dq.max(axis=0)
    ddq = np.abs(np.diff(out["dq"], axis=0))
    assert ddq.max() <= 10.0e-3 + 1e-12, ddq.max()
    assert out["verified"].mean() > 0.95


def test_realtime_priority_is_checked_and_reported(demo):
    s = pacs.Shield()
    s.start(0.0, demo.start)
    with pytest.raises(pacs.InputError, match="priority: value 0"):
        pacs.ShieldLoop(s, priority=0)
    with pytest.raises(pacs.ArgumentTypeError, match="priority"):
        pacs.ShieldLoop(s, priority="high")
    with pacs.ShieldLoop(s, realtime=True, priority=10) as loop:
        time.sleep(0.02)
    st = loop.stats()
    # Granted (root or CAP_SYS_NICE) or refused with the reason; the loop runs either way.
    assert st["rt_priority"] == 10 or "refused" in st["rt_priority_error"], st
    assert st["steps"] > 0 and st["max_late_us"] >= 0.0


def test_concurrent_set_chunk_calls_get_their_own_serials(demo):
    """Python threads handing chunks to one running loop at once: each call returns the serial
    of its own chunk (hand-overs are serialized per shield), all distinct."""
    import threading

    s = pacs.Shield(config={"chunk_motion": "continuous"})
    s.start(0.0, demo.start)
    s.measure(0.0, far_human(demo))
    serials, errors = [], []

    def worker(loop):
        for _ in range(4):
            try:
                c = loop.latest()
                q = c.q if c is not None else demo.start
                deltas, h = demo.chunk(q)
                serials.append(loop.set_chunk(deltas, h=h))
            except Exception as e:  # noqa: BLE001 - reported below
                errors.append(e)

    with pacs.ShieldLoop(s, realtime=True) as loop:
        threads = [threading.Thread(target=worker, args=(loop,)) for _ in range(6)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        p = loop.progress()
    assert not errors, errors
    assert sorted(serials) == list(range(1, 25)), serials
    assert p["accepted"] == 24

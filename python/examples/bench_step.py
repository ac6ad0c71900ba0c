"""Per-step overhead of the Python call over the Rust step.

    python python/examples/bench_step.py [--steps 20000] [--repeats 5]

The same shield run (the FR3 sorting chunk, a person 3 m away measured every 10 ms) is stepped
(a) from Python, one `Shield.step(t)` call per step, and (b) by `ShieldLoop.run_until` (Rust steps,
10 per call, no Python per step), whose stats time the Rust step alone (lock + `Shield::step`).
The overhead is (a)'s wall time per step minus (b)'s Rust step time; medians over the repeats
(µs). `rust_loop_wall_us` is (b)'s wall time per step including its 10-step batching.
"""

import argparse
import json
import statistics
import time

import numpy as np

import pacs


def fresh(demo, person):
    s = pacs.Shield()
    s.start(0.0, demo.start)
    s.measure(0.0, person)
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    demo = pacs.Demo("sorting", seed=0)
    k = demo.keypoints(0.0)
    person = k - k.mean(axis=0) + np.array([3.0, 0.0, 1.0])
    deltas, h = demo.chunk(demo.start)
    n = args.steps
    py_us, rust_us, rust_inner_us, verified = [], [], [], 0
    for _ in range(args.repeats):
        # (a) Python calls.
        s = fresh(demo, person)
        s.set_chunk(deltas, t=0.0, h=h)
        times = [i * 0.001 for i in range(n)]
        t0 = time.perf_counter()
        for i, t in enumerate(times):
            if i % 10 == 0:
                s.measure(t, person)
            c = s.step(t)
            verified += c.verified
        py_us.append((time.perf_counter() - t0) / n * 1e6)
        # (b) the Rust thread, measured in the same way (one measurement per 10 ms at most:
        # the loop takes the latest; hand them over in batches of 10 steps).
        s = fresh(demo, person)
        loop = pacs.ShieldLoop(s, realtime=False, history=0)
        loop.start()
        loop.set_chunk(deltas, h=h, t=0.0)
        t0 = time.perf_counter()
        for j in range(0, n, 10):
            loop.measure(j * 0.001, person)
            loop.run_until((j + 9) * 0.001)
        rust_us.append((time.perf_counter() - t0) / n * 1e6)
        rust_inner_us.append(loop.stats()["mean_step_us"])
        loop.stop()
    py = statistics.median(py_us)
    rust = statistics.median(rust_us)
    inner = statistics.median(rust_inner_us)
    print(json.dumps({
        "steps": n,
        "repeats": args.repeats,
        "python_step_us": round(py, 3),
        "rust_step_us": round(inner, 3),
        "overhead_us": round(py - inner, 3),
        "rust_loop_wall_us": round(rust, 3),
        "verified_fraction": verified / (n * args.repeats),
    }, indent=2))


if __name__ == "__main__":
    main()

"""The shield's 1 kHz loop on a Rust thread in real time, fed from a Python policy loop.

    python python/examples/realtime_loop.py [--seconds 10] [--task sorting] [--priority 80]

A Python loop at 30 Hz hands the demonstration policy's chunks and the person's keypoints to a
`pacs.ShieldLoop(realtime=True)`; the loop thread steps the shield every millisecond of wall
time (`--priority`: under SCHED_FIFO, needs root or CAP_SYS_NICE). Chunks are planned on the
Python thread without holding the shield and taken over a few steps ahead. Prints the loop's
statistics: steps, late starts (a step begun more than one safety step after its deadline), the
latest start (µs), the longest and the mean Rust step (µs), the chunks taken over and rejected,
and the verified fraction.
"""

import argparse
import json
import time

import numpy as np

import pacs


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--task", default="sorting")
    ap.add_argument("--priority", type=int, default=None, help="SCHED_FIFO priority 1..99")
    args = ap.parse_args()
    demo = pacs.Demo(args.task, seed=0)
    shield = pacs.Shield(**demo.shield_args(), config={"chunk_motion": "continuous"})
    shield.start(0.0, demo.start)
    shield.measure(0.0, demo.keypoints(0.0))
    verified = []
    taken = rejected = 0
    with pacs.ShieldLoop(shield, realtime=True, priority=args.priority) as loop:
        wall0 = time.monotonic()
        last = 0
        while time.monotonic() - wall0 < args.seconds:
            t = loop.time
            loop.measure(t, demo.keypoints(t))
            for i, oid in enumerate(demo.object_ids):
                p, v = demo.object_state(i, t)
                loop.measure_object(oid, t, p, v)
            p = loop.progress()
            if p["chunk"] != last or p["executed"] - p["passed"] <= 1:
                c = loop.latest()
                q = c.q if c is not None else demo.start
                deltas, h = demo.chunk(q)
                try:
                    last = loop.set_chunk(deltas, h=h)
                    taken += 1
                except pacs.ChunkRejected:
                    rejected += 1
            verified.extend(loop.commands()["verified"].tolist())
            time.sleep(1 / 30)
        stats = loop.stats()
    print(json.dumps({
        "task": args.task,
        "wall_s": args.seconds,
        **stats,
        "steps_per_s": stats["steps"] / args.seconds,
        "chunks_taken": taken,
        "chunks_rejected": rejected,
        "verified_fraction": float(np.mean(verified)) if verified else 0.0,
    }, indent=2))


if __name__ == "__main__":
    main()

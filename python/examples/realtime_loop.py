"""The shield's 1 kHz loop on a Rust thread in real time, fed from a Python policy loop.

    python python/examples/realtime_loop.py [--seconds 10] [--task sorting]

A Python loop at 30 Hz hands the demonstration policy's chunks and the person's keypoints to a
`pacs.ShieldLoop(realtime=True)`; the loop thread steps the shield every millisecond of wall
time. Prints the loop's statistics: steps, late starts (a step begun more than one safety step
after its deadline), the longest and the mean Rust step (µs), and the verified fraction.
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
    args = ap.parse_args()
    demo = pacs.Demo(args.task, seed=0)
    shield = pacs.Shield(**demo.shield_args(), config={"chunk_motion": "continuous"})
    shield.start(0.0, demo.start)
    shield.measure(0.0, demo.keypoints(0.0))
    verified = []
    with pacs.ShieldLoop(shield, realtime=True) as loop:
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
                except pacs.ChunkRejected:
                    pass
            verified.extend(loop.commands()["verified"].tolist())
            time.sleep(1 / 30)
        stats = loop.stats()
    print(json.dumps({
        "task": args.task,
        "wall_s": args.seconds,
        **stats,
        "steps_per_s": stats["steps"] / args.seconds,
        "verified_fraction": float(np.mean(verified)) if verified else 0.0,
    }, indent=2))


if __name__ == "__main__":
    main()

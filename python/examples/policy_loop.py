"""Drive the built-in FR3 sorting scene with the simulation's demonstration policy through the
PACS shield from Python, the way a LeRobot loop would, then audit the logged run.

    python python/examples/policy_loop.py [--task sorting] [--out pacs-python-out]

The policy is wrapped in LeRobot's policy interface (predict_action_chunk -> (B, H, A)) and the
simulated arm in LeRobot's robot interface (get_observation / send_action with "<joint>.pos"
keys); a person reaches across the table (a camera sees them every 33 ms, 20 ms late). The
shield runs at 1 kHz in simulated time; the run is logged and audited (SSM/PFL) and a
certification report is written.
"""

import argparse
import json
import pathlib

import numpy as np

import pacs
from pacs.lerobot import ShieldedPolicyLoop

KEYS = [f"fr3_joint{i + 1}.pos" for i in range(7)]


class DemoPolicy:
    """The demonstration policy behind LeRobot's PreTrainedPolicy interface."""

    def __init__(self, demo):
        self.demo = demo

    def predict_action_chunk(self, batch):
        q = np.array([batch[k] for k in KEYS])
        deltas, _ = self.demo.chunk(q)
        return deltas[None]  # (B=1, H, 7): joint-position deltas (rad)

    def reset(self):
        pass


class SimulatedArm:
    """A perfectly tracking arm behind LeRobot's Robot interface (radians)."""

    def __init__(self, q0):
        self.obs = dict(zip(KEYS, map(float, q0)))

    def get_observation(self):
        return dict(self.obs)

    def send_action(self, action):
        self.obs.update(action)
        return action


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="sorting",
                    choices=["sorting", "handover", "feeding", "sphere", "crowded"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--duration", type=float, default=8.0, help="simulated seconds")
    ap.add_argument("--out", default="pacs-python-out", help="log and report directory")
    args = ap.parse_args()

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    demo = pacs.Demo(args.task, seed=args.seed)
    shield = pacs.Shield(**demo.shield_args(), log=out / "run.jsonl")
    shield.start(0.0, demo.start)
    shield.measure(0.0, demo.keypoints(0.0))  # the robot waits for the camera's first frame

    def camera(t, period=0.033, delay=0.02):
        """The newest frame at time t: taken at k·period, available `delay` later."""
        k = np.floor((t - delay) / period)
        if k < 0:
            return None
        t_meas = k * period
        return t_meas, demo.keypoints(t_meas)

    def objects(t):
        for i, oid in enumerate(demo.object_ids):
            p, v = demo.object_state(i, t)
            loop.loop.measure_object(oid, t, p, v)

    arm = SimulatedArm(demo.start)
    verified = []
    with ShieldedPolicyLoop(DemoPolicy(demo), arm, shield, KEYS, action_kind="delta",
                            n_action_steps=8, fps=30.0, humans=camera) as loop:
        steps = int(args.duration * 30)
        for _ in range(steps):
            objects(loop.time)
            loop.tick()
            verified.extend(loop.loop.commands()["verified"].tolist())
    shield.close()

    (run,) = pacs.audit(out / "run.jsonl")
    verdict = pacs.report([run], out / "report")
    q = np.array([arm.obs[k] for k in KEYS])
    print(json.dumps({
        "task": args.task,
        "simulated_s": args.duration,
        "verified_fraction": float(np.mean(verified)),
        "tool_point_m": demo.tool_point(q),
        "deviation_from_demonstrations_rad": demo.deviation(q),
        "audit_verdict": run.verdict,
        "violations": len(run.violations),
        "report": str(out / "report" / "report.html"),
        "overall": verdict,
    }, indent=2))


if __name__ == "__main__":
    main()

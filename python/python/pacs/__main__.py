"""Command-line tools of the pacs Python package.

    python -m pacs tolerance --policy kernel --task sorting --out tolerance/
    python -m pacs tolerance --policy path/to/lerobot/model --task sorting --holds 0.5,1,2,4

``tolerance``: does a policy still succeed when PACS slows or stops it along its path
(:func:`pacs.tolerance`)? ``--policy`` is a built-in policy's name (nearest, kernel,
kernel-paced, kernel-shield-paced) or a LeRobot policy directory (``save_pretrained``; needs lerobot). Writes
``tolerance.json`` and the one-page plot ``tolerance.svg`` into ``--out``.
Exit codes: 0 done, 2 bad input, 1 other errors.
"""

import argparse
import json
import os
import sys

from . import InputError, ArgumentTypeError, tolerance


def _floats(s: str) -> list:
    try:
        return [float(v) for v in s.split(",") if v.strip()]
    except ValueError as e:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers: {e}") from None


def _progress(done: int, total: int) -> None:
    """A one-line progress bar on stderr."""
    width = 30
    filled = width * done // max(total, 1)
    print(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} rollouts", end="",
          file=sys.stderr, flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m pacs", description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("tolerance", help="success when slowed or stopped along the path")
    t.add_argument("--policy", default="nearest",
                   help="built-in policy name or a LeRobot policy directory (default nearest)")
    t.add_argument("--task", default="sorting",
                   choices=["sorting", "handover", "feeding", "sphere", "crowded"])
    t.add_argument("--method", default="pacs", help="pacs, pacs-ssm or pacs-pfl (default pacs)")
    t.add_argument("--holds", type=_floats, default=[0.5, 1.0, 2.0, 4.0],
                   help="seconds the intruder's hand stays (default 0.5,1,2,4)")
    t.add_argument("--at", type=_floats, default=[0.3, 0.6],
                   help="when the hand rises, as fractions of the rollout (default 0.3,0.6)")
    t.add_argument("--rollouts", type=int, default=10, help="seeds (default 10)")
    t.add_argument("--seed", type=int, default=1, help="first seed (default 1)")
    t.add_argument("--out", default="tolerance", help="output directory (default tolerance/)")
    args = ap.parse_args(argv)
    policy = args.policy
    if os.path.isdir(policy):
        from .lerobot import SimulationPolicy

        try:
            policy = SimulationPolicy.from_pretrained(policy)
        except ImportError as e:
            print(f"python -m pacs tolerance: --policy {args.policy}: a LeRobot policy directory "
                  f"needs lerobot (pip install 'lerobot>=0.6'): {e}", file=sys.stderr)
            return 1
    try:
        os.makedirs(args.out, exist_ok=True)
        result = tolerance(policy, args.task, holds=args.holds, at=args.at,
                           rollouts=args.rollouts, seed=args.seed, method=args.method,
                           plot=os.path.join(args.out, "tolerance.svg"),
                           progress=_progress)
        print(file=sys.stderr)
    except (InputError, ArgumentTypeError) as e:
        print(f"python -m pacs tolerance: {e}", file=sys.stderr)
        return 2
    with open(os.path.join(args.out, "tolerance.json"), "w", encoding="utf-8") as f:
        json.dump(result, f, indent=1)
    for r in result["rows"]:
        lo, hi = r["success_wilson95"]
        print(f"hold {r['hold_s']:4g} s: success {r['success']:.2f} [{lo:.2f}, {hi:.2f}] "
              f"({r['rollouts']} rollouts), at rest {r['mean_stopped_s']:.2f} s, "
              f"+{r['mean_extra_duration_s']:.2f} s")
    print(f"wrote {os.path.join(args.out, 'tolerance.json')} and tolerance.svg")
    return 0


if __name__ == "__main__":
    sys.exit(main())

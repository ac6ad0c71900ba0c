"""LeRobot's diffusion policy on the simulation's tasks, on CPU: teleoperation-like
demonstrations -> a LeRobot dataset -> a trained DiffusionPolicy -> rollouts through OFF, PACS,
single-action and CBF, scored against the true people and objects (every PACS log audited).

    # 1. demonstrations (50 per task) as a LeRobot dataset, and a policy trained on them only
    python python/examples/diffusion_policy.py train --task sorting --out policies/sorting
    # the same with two paced (paused / slowed) replays per demonstration added
    python python/examples/diffusion_policy.py train --task sorting --replays 2 \
        --out policies/sorting-paced
    # 2. rollouts of the trained policy (10 seeds per method; --workers N for N local processes,
    #    --client for a Dask scheduler):
    #    summary.json, summary.svg (success per method, 95 % Wilson intervals), the logs
    python python/examples/diffusion_policy.py evaluate --policy policies/sorting/model \\
        --task sorting --rollouts 10 --out policies/sorting/eval
    # 3. two evaluations compared method by method: each success with its Wilson interval and
    #    their difference with Newcombe's 95 % interval (it excludes 0: the result changed)
    python python/examples/diffusion_policy.py compare policies/sorting/eval \\
        policies/sorting-paced/eval --out policies/compare

Needs lerobot 0.6 (``pip install 'lerobot[diffusion]>=0.6,<0.7'``, Python >= 3.12; it pulls
torch) and pacs. Nothing is downloaded: the weights are trained here from the simulation's
demonstrations. The policy: ``observation.state`` (7 joint angles, rad) and
``observation.environment_state`` (stage, person centroid, tool-person distance) over the
last two frames (1/30 s apart), 16 predicted joint-position deltas of which 8 are executed,
U-Net widths (64, 128, 256) (4.5 M parameters), DDPM training (100 steps), DDIM at inference
(10 steps).
"""

import argparse
import json
import math
import pathlib
import time

import numpy as np

import pacs
from pacs.lerobot import (ENVIRONMENT_STATE_SPAN, STATE_SPAN, SimulationPolicy,
                          environment_state, normalization_stats, paced_replays, write_dataset)


def windows(demos, n_obs, horizon, drop_last):
    """Training samples as index arrays: for frame t of each demonstration, the observation
    frames t-n_obs+1..t and the action frames t-n_obs+1..t-n_obs+horizon, clamped into the
    demonstration (LeRobot's padding: the first/last frame repeated), with the pad mask."""
    obs_idx, act_idx, pad = [], [], []
    offset = 0
    for d in demos:
        n = len(d["q"])
        for t in range(0, max(1, n - drop_last)):
            o = np.arange(t - n_obs + 1, t + 1)
            a = np.arange(t - n_obs + 1, t - n_obs + 1 + horizon)
            pad.append((a < 0) | (a > n - 1))
            obs_idx.append(offset + np.clip(o, 0, n - 1))
            act_idx.append(offset + np.clip(a, 0, n - 1))
        offset += n
    return np.array(obs_idx), np.array(act_idx), np.array(pad)


def stats_of(x):
    return {"min": x.min(0), "max": x.max(0), "mean": x.mean(0), "std": x.std(0),
            "count": np.array([len(x)])}


def train(args):
    import torch
    from lerobot.configs.types import FeatureType, NormalizationMode, PolicyFeature
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
    from lerobot.policies.factory import make_pre_post_processors

    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    demos = pacs.teleop_demonstrations(args.task, count=args.demos, seed=args.demo_seed)
    if args.replays:
        # Path-consistent paused and slowed replays (PACS's braking and resuming profiles).
        demos = demos + paced_replays(demos, per_demo=args.replays, seed=args.seed)
    if not args.no_dataset:
        ds_root = out / "dataset"
        if not ds_root.exists():
            write_dataset(demos, str(ds_root))
    state = np.concatenate([d["q"] for d in demos]).astype(np.float32)
    env = np.concatenate([
        np.stack([environment_state(s, p, r) for s, p, r in
                  zip(d["stage"], d["person"], d["person_distance"])]) for d in demos])
    action = np.concatenate([d["action"] for d in demos]).astype(np.float32)
    cfg = DiffusionConfig(
        input_features={
            "observation.state": PolicyFeature(type=FeatureType.STATE, shape=(7,)),
            "observation.environment_state": PolicyFeature(type=FeatureType.ENV,
                                                           shape=(env.shape[1],)),
        },
        output_features={"action": PolicyFeature(type=FeatureType.ACTION, shape=(7,))},
        n_obs_steps=2, horizon=16, n_action_steps=8, down_dims=(64, 128, 256),
        noise_scheduler_type="DDIM", num_train_timesteps=100, num_inference_steps=10,
        device="cpu",
        normalization_mapping={"VISUAL": NormalizationMode.MEAN_STD,
                               "STATE": NormalizationMode.MIN_MAX,
                               "ENV": NormalizationMode.MIN_MAX,
                               "ACTION": NormalizationMode.MIN_MAX},
    )
    # The observations' ranges with a span floor (`normalization_stats`: a joint or a person
    # coordinate the demonstrations hold still must not be scaled by 1/1e-8).
    stats = {"observation.state": normalization_stats(state, STATE_SPAN),
             "observation.environment_state": normalization_stats(env, ENVIRONMENT_STATE_SPAN),
             "action": stats_of(action)}
    pre, post = make_pre_post_processors(cfg, dataset_stats=stats)
    policy = DiffusionPolicy(cfg)
    policy.train()
    o_idx, a_idx, pad = windows(demos, cfg.n_obs_steps, cfg.horizon, cfg.drop_n_last_frames)
    # Normalized tensors once (the preprocessor's normalizer on the whole arrays).
    norm = pre({"observation.state": torch.from_numpy(state),
                "observation.environment_state": torch.from_numpy(env),
                "action": torch.from_numpy(action)})
    S, E, A = (norm["observation.state"], norm["observation.environment_state"],
               norm["action"])
    for name, x in (("state", S), ("environment", E), ("action", A)):
        if x.shape[0] != len(state) or float(x.abs().max()) > 1.0 + 1e-5:
            raise SystemExit(f"normalized {name}: shape {tuple(x.shape)}, max |x| "
                             f"{float(x.abs().max()):.3f} (expected min-max to [-1, 1])")
    opt = torch.optim.AdamW(policy.parameters(), lr=cfg.optimizer_lr, betas=cfg.optimizer_betas,
                            eps=cfg.optimizer_eps, weight_decay=cfg.optimizer_weight_decay)
    warm = cfg.scheduler_warmup_steps

    def lr_at(step):
        if step < warm:
            return (step + 1) / warm
        return 0.5 * (1 + math.cos(math.pi * (step - warm) / max(1, args.steps - warm)))

    sched = torch.optim.lr_scheduler.LambdaLR(opt, lr_at)
    rng = np.random.default_rng(args.seed)
    t0, losses = time.time(), []
    for step in range(args.steps):
        i = rng.integers(0, len(o_idx), args.batch_size)
        batch = {
            "observation.state": S[o_idx[i]],
            "observation.environment_state": E[o_idx[i]],
            "action": A[a_idx[i]],
            "action_is_pad": torch.from_numpy(pad[i]),
        }
        loss, _ = policy.forward(batch)
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(policy.parameters(), 10.0)
        opt.step()
        sched.step()
        losses.append(float(loss.detach()))
        if (step + 1) % args.log_every == 0 or step + 1 == args.steps:
            rate = (step + 1) / (time.time() - t0)
            print(f"step {step + 1}/{args.steps} loss {np.mean(losses[-args.log_every:]):.4f} "
                  f"({rate:.1f} steps/s)", flush=True)
    policy.eval()
    model = out / "model"
    policy.save_pretrained(model)
    pre.save_pretrained(model)
    post.save_pretrained(model)
    info = {
        "task": args.task, "demonstrations": len(demos), "frames": int(len(state)),
        "demo_seed": args.demo_seed, "replays_per_demo": args.replays, "steps": args.steps, "batch_size": args.batch_size,
        "seconds": round(time.time() - t0, 1), "final_loss": float(np.mean(losses[-100:])),
        "parameters": sum(p.numel() for p in policy.parameters()),
        "command": "python python/examples/diffusion_policy.py train " + " ".join(
            f"--{k.replace('_', '-')} {v}" for k, v in vars(args).items()
            if k not in ("cmd", "no_dataset") and v is not None),
    }
    (out / "training.json").write_text(json.dumps(info, indent=2))
    print(json.dumps(info, indent=2))


def evaluate(args):
    import torch

    torch.set_num_threads(1)
    policy = SimulationPolicy.from_pretrained(args.policy)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    client = cluster = None
    if args.client:
        from dask.distributed import Client

        client = Client(args.client)
    elif args.workers > 1:
        # A Dask cluster on this machine: one process per worker, one thread each (the policy
        # runs one torch thread per call, so a rollout is the same on any worker).
        from dask.distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    t0 = time.time()
    def progress(done, total):
        print(f"\r{done}/{total} rollouts ({time.time() - t0:.0f} s)", end="", flush=True)

    # One method at a time, each method's rows and rollouts saved to partial.json as it ends:
    # a long evaluation that stops (a full disk, a reboot) resumes with --resume from the
    # methods it finished. A rollout depends only on its task, method and seed, so the rows are
    # those of one call with every method.
    methods = [m.strip() for m in args.method.split(",") if m.strip()]
    key = {"task": args.task, "policy": str(args.policy), "rollouts": args.rollouts,
           "seed": args.seed}
    if args.time_limit is not None:
        key["time_limit"] = args.time_limit
    partial_path = out / "partial.json"
    result = {"rows": [], "rollouts": []}
    if args.resume and partial_path.exists():
        saved = json.loads(partial_path.read_text())
        if saved.get("key") != key:
            raise SystemExit(f"{partial_path}: made by another evaluation ({saved.get('key')}), "
                             f"not {key}; remove it or use another --out")
        result = {"rows": saved["rows"], "rollouts": saved["rollouts"]}
        print(f"resuming: {', '.join(r['method'] for r in result['rows'])} already done")
    for m in methods:
        if any(r["method"] == m for r in result["rows"]):
            continue
        part = pacs.simulate(args.task, m, rollouts=args.rollouts, seed=args.seed,
                             policy=policy, client=client, log_dir=out / "logs",
                             progress=None if client else progress,
                             time_limit=args.time_limit)
        result["rows"] += part["rows"]
        result["rollouts"] += part["rollouts"]
        partial_path.write_text(json.dumps({"key": key, **result}, default=str))
    # The evaluation's order (`pacs.simulate`'s): by method, each method's rollouts by seed.
    result["rows"].sort(key=lambda r: r["method"])
    result["rollouts"].sort(key=lambda r: r["method"])
    print()
    if cluster is not None:
        client.close()
        cluster.close()
    # The evaluation's own rows (success with its 95 % Wilson interval, durations, ...), with
    # the rollouts that truly violated and the audit of every PACS log added.
    rows = []
    for row in result["rows"]:
        rs = [r for r in result["rollouts"] if r["method"] == row["method"]]
        logs = [r["log"] for r in rs if r.get("log")]
        audited = pacs.audit(logs) if row["method"].startswith("pacs") and logs else []
        rows.append({
            **row,
            "rollouts_with_violation": sum(r["episode"]["violation_fraction"] > 0 for r in rs),
            "max_deviation_rad": float(max(r["episode"]["max_deviation"] for r in rs)),
            "audit_verdicts": {v: sum(a.verdict == v for a in audited)
                               for v in sorted({a.verdict for a in audited})},
        })
    summary = {"task": args.task, "policy": args.policy, "seconds": round(time.time() - t0, 1),
               "rows": rows}
    if args.time_limit is not None:  # absent: each task's own limit
        summary["time_limit"] = args.time_limit
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    (out / "summary.svg").write_text(summary_svg([summary], [args.policy]))
    (out / "rollouts.json").write_text(json.dumps(result["rollouts"], indent=1, default=str))
    print(json.dumps(summary, indent=2))


# The paper's Table I (robomimic, 100 rollouts per cell, the average over Lift, Can and Square):
# the reference points drawn in summary.svg.
PAPER_AVERAGE = {"off": 0.70, "pacs": 0.69, "pacs-pfl": 0.72, "single-action": 0.41,
                 "single-action-pfl": 0.44, "cbf": 0.04}


def newcombe95(p1, ci1, p2, ci2):
    """Newcombe's hybrid score interval (his method 10, 1998) for p1 - p2 of two independent
    proportions, from each one's 95 % Wilson interval (`ci1`, `ci2`: the rows' `success_ci95`,
    computed by the evaluation): (difference, lower, upper)."""
    (l1, u1), (l2, u2) = ci1, ci2
    d = p1 - p2
    return (d, d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2),
            d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2))


def interval(row):
    """A row's 95 % Wilson interval of success (`success_ci95`, as `pacs.simulate` writes it;
    `success_wilson95` in summaries of earlier versions)."""
    return row["success_ci95"] if "success_ci95" in row else row["success_wilson95"]


def summary_svg(summaries, labels):
    """One page: success per method (points with 95 % Wilson intervals) for each evaluation in
    `summaries` (their `rows`), the paper's averages as grey ticks."""
    import html

    methods = []
    for s in summaries:
        for r in s["rows"]:
            if r["method"] not in methods:
                methods.append(r["method"])
    order = ["off", "pacs", "pacs-pfl", "single-action", "single-action-pfl", "cbf"]
    methods.sort(key=lambda m: (order.index(m) if m in order else len(order), m))
    w, h, left, top, ph = 760, 470, 80, 80, 300
    pw = w - left - 40
    colours = ["#1f5fa8", "#b5462b", "#2b8a3e", "#7048a8"]
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
             f'viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="13">',
             '<rect width="100%" height="100%" fill="white"/>',
             f'<text x="{w / 2}" y="30" text-anchor="middle" font-size="18">Task success per '
             f'method: {html.escape(summaries[0]["task"])}</text>',
             f'<text x="{w / 2}" y="52" text-anchor="middle">points: success rate; bars: 95 % '
             f'Wilson interval; grey ticks: the paper\'s robomimic average</text>']
    bottom = top + ph
    for i in range(6):
        y = bottom - ph * i / 5
        parts.append(f'<line x1="{left}" y1="{y}" x2="{left + pw}" y2="{y}" stroke="#ddd"/>')
        parts.append(f'<text x="{left - 8}" y="{y + 4}" text-anchor="end">{i / 5:.1f}</text>')
    parts.append(f'<text transform="translate({left - 50},{top + ph / 2}) rotate(-90)" '
                 f'text-anchor="middle">success</text>')
    slot = pw / max(len(methods), 1)
    for m_i, m in enumerate(methods):
        cx = left + slot * (m_i + 0.5)
        parts.append(f'<text x="{cx}" y="{bottom + 20}" text-anchor="middle">'
                     f'{html.escape(m)}</text>')
        if m in PAPER_AVERAGE:
            y = bottom - ph * PAPER_AVERAGE[m]
            parts.append(f'<line x1="{cx - slot * 0.4}" y1="{y}" x2="{cx + slot * 0.4}" '
                         f'y2="{y}" stroke="#999" stroke-width="3"/>')
        for k, s in enumerate(summaries):
            row = next((r for r in s["rows"] if r["method"] == m), None)
            if row is None:
                continue
            x = cx + (k - (len(summaries) - 1) / 2) * 18
            lo, hi = interval(row)
            c = colours[k % len(colours)]
            parts.append(f'<line x1="{x}" y1="{bottom - ph * lo}" x2="{x}" '
                         f'y2="{bottom - ph * hi}" stroke="{c}" stroke-width="2"/>')
            parts.append(f'<circle cx="{x}" cy="{bottom - ph * row["success"]}" r="5" '
                         f'fill="{c}"/>')
    for k, (s, label) in enumerate(zip(summaries, labels)):
        n = {r["rollouts"] for r in s["rows"]}
        parts.append(f'<text x="{left}" y="{bottom + 50 + 18 * k}" '
                     f'fill="{colours[k % len(colours)]}">● {html.escape(label)} '
                     f'({"/".join(str(x) for x in sorted(n))} rollouts per method)</text>')
    parts.append("</svg>")
    return "\n".join(parts)


def compare(args):
    """Compare evaluations (each a directory or summary.json `evaluate` wrote) with the first."""
    paths = [pathlib.Path(p) for p in args.evaluations]
    paths = [p / "summary.json" if p.is_dir() else p for p in paths]
    summaries = []
    for p in paths:
        if not p.exists():
            raise SystemExit(f"compare: {p}: no such file (run `evaluate --out DIR` first)")
        summaries.append(json.loads(p.read_text()))
    labels = [str(p.parent) for p in paths]
    base = summaries[0]
    lines = ["| method | " + " | ".join(f"{html_free(l)} success [95 % Wilson]" for l in labels)
             + " | " + " | ".join(f"difference {i + 1} − 1 [Newcombe 95 %]"
                                  for i in range(1, len(labels))) + " |",
             "|---" * (2 * len(labels)) + "|"]
    result = []
    for row in base["rows"]:
        m = row["method"]
        cells, diffs = [], []
        for k, s in enumerate(summaries):
            r = next((x for x in s["rows"] if x["method"] == m), None)
            cells.append("—" if r is None else
                         f"{r['success']:.2f} [{interval(r)[0]:.2f}, "
                         f"{interval(r)[1]:.2f}] (n = {r['rollouts']})")
            if k == 0:
                continue
            if r is None:
                diffs.append("—")
                continue
            d, lo, hi = newcombe95(r["success"], interval(r), row["success"], interval(row))
            diffs.append(f"{d:+.2f} [{lo:+.2f}, {hi:+.2f}]"
                         + (" **changed**" if lo > 0 or hi < 0 else ""))
            result.append({"method": m, "evaluation": labels[k], "difference": d,
                           "newcombe95": [lo, hi], "changed": lo > 0 or hi < 0})
        lines.append(f"| {m} | " + " | ".join(cells) + " | " + " | ".join(diffs) + " |")
    table = "\n".join(lines)
    print(table)
    if args.out:
        out = pathlib.Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "compare.md").write_text(table + "\n")
        (out / "compare.json").write_text(json.dumps(
            {"evaluations": labels, "differences": result}, indent=2))
        (out / "compare.svg").write_text(summary_svg(summaries, labels))


def html_free(text):
    """A table cell's text without Markdown's column separator."""
    return text.replace("|", "/")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    tasks = ["sorting", "handover", "feeding", "sphere", "crowded"]
    t = sub.add_parser("train", help="demonstrations, dataset and a trained policy")
    t.add_argument("--task", default="sorting", choices=tasks)
    t.add_argument("--out", required=True, help="directory: dataset/, model/, training.json")
    t.add_argument("--demos", type=int, default=50, help="demonstrations (default 50)")
    t.add_argument("--demo-seed", type=int, default=1000,
                   help="first demonstration's scene seed (default 1000: disjoint from the "
                        "evaluation's seeds 1..)")
    t.add_argument("--replays", type=int, default=0,
                   help="paced replays per demonstration added to the training data "
                        "(pacs.lerobot.paced_replays; default 0)")
    t.add_argument("--steps", type=int, default=6000, help="gradient steps (default 6000)")
    t.add_argument("--batch-size", type=int, default=64)
    t.add_argument("--seed", type=int, default=0, help="torch / sampling seed")
    t.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    t.add_argument("--log-every", type=int, default=200)
    t.add_argument("--no-dataset", action="store_true", help="skip writing the LeRobot dataset")
    e = sub.add_parser("evaluate", help="rollouts of a trained policy")
    e.add_argument("--policy", required=True, help="the model/ directory `train` wrote")
    e.add_argument("--task", default="sorting", choices=tasks)
    e.add_argument("--method", default="off,pacs,single-action,cbf")
    e.add_argument("--rollouts", type=int, default=10)
    e.add_argument("--seed", type=int, default=1)
    e.add_argument("--client", default=None, help="a Dask scheduler address (default: here)")
    e.add_argument("--workers", type=int, default=1,
                   help="without --client: rollouts in parallel on a Dask cluster of this many "
                        "local processes (default 1: in this process)")
    e.add_argument("--time-limit", type=float, default=None,
                   help="every rollout's time limit in seconds (default: the task's own, "
                        "20 s; feeding 60 s)")
    e.add_argument("--out", required=True)
    e.add_argument("--resume", action="store_true",
                   help="keep the methods OUT/partial.json already holds (an evaluation that "
                        "stopped) and run only the others")
    c = sub.add_parser("compare", help="evaluations compared method by method (Newcombe 95 %% "
                                         "intervals of the differences in success)")
    c.add_argument("evaluations", nargs="+",
                   help="directories (or summary.json files) `evaluate` wrote; the first is "
                        "the reference")
    c.add_argument("--out", default=None, help="directory: compare.md, compare.json, compare.svg")
    args = ap.parse_args()
    {"train": train, "evaluate": evaluate, "compare": compare}[args.cmd](args)


if __name__ == "__main__":
    main()

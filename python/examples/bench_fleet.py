"""Benchmark: a fleet's archive audited on a Dask LocalCluster of 1 and of 2 worker processes
(one thread each), and locally on 1 and 2 threads, end to end (files -> runs + fleet report).

    python python/examples/bench_fleet.py [--dir /tmp/pacs-fleet-bench] [--logs 200] [--repeat 3]

The archive is made once with pacs.simulate (its rollouts' audit logs, like `pacs simulate`'s:
every task with the methods off and pacs, seeds 1, 2, ... until --logs logs) and reused. Prints
one JSON object: the archive (logs, robot samples, bytes), each configuration's wall-clock times,
the speed-ups, and the load average before and after. docs/performance-audit.md has the figures.
"""

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import pacs


def make_archive(d: Path, n: int) -> None:
    tasks = ["sorting", "handover", "feeding", "sphere", "crowded"]
    methods = ["off", "pacs"]
    per = -(-n // (len(tasks) * len(methods)))  # rollouts per task and method
    d.mkdir(parents=True, exist_ok=True)
    pacs.simulate(task=tasks, method=methods, rollouts=per, seed=1, log_dir=str(d))
    logs = sorted(d.glob("*.jsonl"))
    for extra in logs[n:]:
        extra.unlink()


def timed(fn, repeat):
    times = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return out, times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dir", default="/tmp/pacs-fleet-bench")
    ap.add_argument("--logs", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    from dask.distributed import Client, LocalCluster

    d = Path(args.dir)
    if len(list(d.glob("*.jsonl"))) != args.logs:
        t = time.perf_counter()
        make_archive(d, args.logs)
        print(f"archive: {args.logs} logs made in {time.perf_counter() - t:.1f} s", flush=True)
    load_before = os.getloadavg()
    result = {"dir": str(d), "logs": args.logs, "load_before": load_before}
    reference = None
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            pacs.fleet.audit(sorted(d.glob("*.jsonl"))[:4], client=client)  # workers import pacs
            (runs, report), times = timed(lambda: pacs.fleet.audit(str(d), client=client),
                                          args.repeat)
        result[f"dask_{workers}_workers_s"] = times
        digest = json.dumps(report)
        assert reference is None or digest == reference, "Dask results differ"
        reference = digest
    for threads in (1, 2):
        (runs, report), times = timed(lambda: pacs.fleet.audit(str(d), threads=threads),
                                      args.repeat)
        result[f"local_{threads}_threads_s"] = times
        assert json.dumps(report) == reference, "local results differ from Dask's"
    samples = sum(r.metrics["samples"] for r in runs)
    result["robot_samples"] = samples
    result["bytes"] = sum(p.stat().st_size for p in d.glob("*.jsonl"))
    result["verdicts"] = {v: sum(r.verdict == v for r in runs) for v in ("pass", "fail", "inconclusive")}
    med = {k: statistics.median(v) for k, v in result.items() if k.endswith("_s")}
    result["speedup_dask_2_over_1"] = med["dask_1_workers_s"] / med["dask_2_workers_s"]
    result["speedup_local_2_over_1"] = med["local_1_threads_s"] / med["local_2_threads_s"]
    result["samples_per_s_dask_1_worker"] = samples / med["dask_1_workers_s"]
    result["samples_per_s_dask_2_workers"] = samples / med["dask_2_workers_s"]
    import pickle
    result["pickled_run_bytes_mean"] = statistics.mean(len(pickle.dumps(r)) for r in runs)
    result["load_after"] = os.getloadavg()
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()

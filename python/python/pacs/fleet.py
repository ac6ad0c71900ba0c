"""A fleet's archive: many logs audited in parallel, locally or on a Dask cluster, with the fleet
report; and simulation rollouts on the same cluster.

>>> import pacs
>>> runs, report = pacs.fleet.audit("archive/")                 # local threads
>>> from dask.distributed import Client
>>> with Client("tcp://scheduler:8786") as client:              # doctest: +SKIP
...     runs, report = pacs.fleet.audit("archive/", client=client)
...     sim = pacs.simulate(task="sorting", rollouts=100, client=client)

The audit of each log, the fleet report (per robot, scene and UTC day: verdict counts, audited
and violation time, worst runs) and the simulation's summary are the Rust code of
``pacs audit DIR --out`` and ``pacs simulate``; this module only distributes the work. With a
client, every log is audited on a worker (the workers must read the paths as given, e.g. on a
shared file system) and the :class:`pacs.Run` objects come back pickled, whole. Results are the
same with and without a client. See docs/fleet.md.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any, NamedTuple, Sequence

from . import _pacs
from .errors import ArgumentTypeError, InputError

__all__ = ["FleetAudit", "audit", "simulate"]


class FleetAudit(NamedTuple):
    """What :func:`audit` returns: the runs (in the order of the sorted log paths) and the
    fleet report (a dict, equal to ``report.json["fleet"]`` of ``pacs audit DIR --out``)."""

    runs: list
    report: dict


def _check_client(client: Any) -> None:
    """``client`` must be None or a ``dask.distributed.Client``."""
    if client is None:
        return
    try:
        from dask.distributed import Client
    except ImportError as e:
        raise ArgumentTypeError(
            f"client: a dask.distributed.Client is needed, but dask.distributed cannot be "
            f"imported ({e}); pip install 'dask[distributed]' — got {client!r}"
        ) from None
    if not isinstance(client, Client):
        raise ArgumentTypeError(
            f"client: expected None or a dask.distributed.Client, got "
            f"{type(client).__name__} {client!r}"
        )


def _threads(threads: Any) -> int:
    if threads is None:
        try:
            return max(1, len(os.sched_getaffinity(0)))
        except AttributeError:  # not Linux
            return max(1, os.cpu_count() or 1)
    if isinstance(threads, bool) or not isinstance(threads, int):
        raise ArgumentTypeError(f"threads: expected None or an int, got {threads!r}")
    if threads < 1:
        raise InputError(f"threads: must be at least 1, got {threads}")
    return threads


# What workers run: module-level Python functions (pickled by reference to ``pacs.fleet``; the
# extension's own functions are not importable under their ``__module__``).


def _run_from_state(state: bytes) -> Any:
    """Rebuild a :class:`pacs.Run` pickled by ``Run.__reduce__``."""
    return _pacs._run_from_state(state)


def _list_logs(paths: Any) -> list:
    return _pacs._fleet_logs(paths)


def _audit_one(path: str, config: Any, header: Any = None) -> Any:
    """The audit of one log; a given header only for a log that takes one (MCAP logs and ROS 2
    bags; JSON Lines and CSV keep their own: the CLI's rule, ``_pacs._takes_header``)."""
    if header is not None and not _pacs._takes_header(path):
        header = None
    (run,) = _pacs.audit(path, config, header)
    return run


def _audit_batch(paths: list, config: Any, header: Any = None) -> list:
    """The audits of several logs (what a worker runs: one Dask task), each ``(True, run)`` or
    ``(False, error)``: the client raises the first error in path order, whichever task failed
    first."""
    out = []
    for p in paths:
        try:
            out.append((True, _audit_one(p, config, header)))
        except Exception as e:  # noqa: BLE001 - handed to the client, raised there in path order
            out.append((False, e))
    return out


def _batches(n: int, slots: int, batch: Any) -> list:
    """The indices of ``n`` logs in batches of at most ``batch`` (by default as many batches as
    four per worker thread: fewer, larger tasks cost the scheduler and the client less), each
    batch every k-th log (k the number of batches), so that the batches mix the archive's
    kinds of logs (sorted paths put like logs together) and take about equally long."""
    if batch is None:
        batch = max(1, -(-n // (4 * max(1, slots))))
    elif isinstance(batch, bool) or not isinstance(batch, int):
        raise ArgumentTypeError(f"batch: expected None or an int, got {batch!r}")
    elif batch < 1:
        raise InputError(f"batch: must be at least 1, got {batch}")
    k = -(-n // batch)
    return [list(range(j, n, k)) for j in range(k)]


def audit(
    paths: Any,
    client: Any = None,
    config: Any = None,
    threads: Any = None,
    batch: Any = None,
    header: Any = None,
) -> FleetAudit:
    """Audit many logs and build the fleet report.

    ``paths``: a log, a directory (its ``*.jsonl``, ``*.csv``, ``*.mcap`` and ``*.db3`` files and
    ROS 2 bag directories, also in subdirectories, sorted by path) or a list of them — as
    ``pacs audit`` takes them (a log given twice is refused: it would count twice).
    ``client``: None (the logs are audited here on ``threads`` threads, default: the usable
    cores) or a ``dask.distributed.Client`` (one task per batch of at most ``batch`` logs, by
    default four tasks per worker thread, each batch every k-th log; directories are listed on
    a worker; the workers must be able to read the logs and use the same pacs version).
    ``config``: the audit settings, as for :func:`pacs.audit`.
    ``header``: the pacs header (a dict or a JSON/TOML file the workers can read) of every ROS 2
    bag and MCAP log of the archive (it replaces the header of one that carries its own: give it
    to recordings without one, such as ROS 2 Humble bags); ``*.jsonl`` and ``*.csv`` logs keep
    their own (as ``pacs audit DIR --header FILE``).

    Returns ``FleetAudit(runs, report)``: one :class:`pacs.Run` per log in the order of the
    sorted paths, and the fleet report. An invalid log raises :class:`pacs.InputError` naming
    it (the first in path order); ``pacs.report(runs, dir)`` writes the full report.
    """
    _check_client(client)
    if client is None:
        if batch is not None:
            raise InputError("batch: only with a client")
        logs = _pacs._fleet_logs(paths)
        n = min(_threads(threads), len(logs))
        with ThreadPoolExecutor(max_workers=n) as pool:
            runs = list(pool.map(lambda p: _audit_one(p, config, header), logs))
    else:
        if threads is not None:
            raise InputError("threads: set the workers' threads on the Dask cluster, not here")
        logs = client.submit(_list_logs, paths, pure=False).result()
        batches = _batches(len(logs), sum(client.nthreads().values()), batch)
        futures = client.map(_audit_batch, [[logs[i] for i in b] for b in batches],
                             config=config, header=header, pure=False)
        try:
            parts = client.gather(futures)
        finally:
            for f in futures:
                f.release()
        runs = [None] * len(logs)
        errors = [None] * len(logs)
        for b, part in zip(batches, parts):
            for i, (ok, r) in zip(b, part):
                if ok:
                    runs[i] = r
                else:
                    errors[i] = r
        # The first invalid log in path order, as locally (not the first task to fail).
        for e in errors:
            if e is not None:
                raise e
    return FleetAudit(runs, _pacs._fleet_report(runs))


def _names(value: Any, name: str) -> list:
    if isinstance(value, str):
        names = [n.strip() for n in value.split(",") if n.strip()]
    elif isinstance(value, Sequence) and all(isinstance(v, str) for v in value):
        names = list(value)
    else:
        raise ArgumentTypeError(
            f"{name}: expected a name, a comma-separated str or a list of str, got {value!r}"
        )
    if not names:
        raise InputError(f"{name}: no name given")
    for i, n in enumerate(names):
        if n in names[:i]:
            raise InputError(f"{name}: `{n}` is given twice (its rollouts would count twice)")
    return names


def _count(value: Any, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ArgumentTypeError(f"{name}: expected an int, got {value!r}")
    if value < least:
        raise InputError(f"{name}: must be at least {least}, got {value}")
    return value


def _seed_list(rollouts: Any, seed: Any, seeds: Any) -> list:
    """The seeds to run, sorted: ``seeds`` as given (distinct ints >= 0), or ``seed`` ..
    ``seed + rollouts - 1`` (defaults 10 and 1)."""
    if seeds is None:
        n = 10 if rollouts is None else _count(rollouts, "rollouts", 1)
        first = 1 if seed is None else _count(seed, "seed", 0)
        return list(range(first, first + n))
    if rollouts is not None or seed is not None:
        raise InputError("seeds: give either seeds or rollouts and seed, not both")
    if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__iter__"):
        raise ArgumentTypeError(f"seeds: expected a list of ints, got {seeds!r}")
    out = [_count(s, f"seeds[{i}]", 0) for i, s in enumerate(seeds)]
    if not out:
        raise InputError("seeds: no seed given")
    seen = set()
    for s in out:
        if s in seen:
            raise InputError(f"seeds: seed {s} is given twice")
        seen.add(s)
    return sorted(out)


def _ranges(seeds: list) -> list:
    """Sorted distinct seeds as contiguous ranges ``(first, count)``."""
    out = []
    for s in seeds:
        if out and out[-1][0] + out[-1][1] == s:
            out[-1] = (out[-1][0], out[-1][1] + 1)
        else:
            out.append((s, 1))
    return out


def _rollouts_of(ranges: list, threads: Any, common: dict) -> list:
    """The encoded rollouts of seed ranges (what a worker runs: one Dask task)."""
    return [_pacs._simulate_rollouts(seed=s, rollouts=n, threads=threads, **common)
            for s, n in ranges]


def _seed_parts(seed_list: list, partitions: Any, client: Any) -> list:
    """Consecutive parts of the sorted seeds, of near-equal size: ``partitions`` of them
    (default one per worker thread), at most one per seed."""
    if partitions is None:
        partitions = max(1, sum(client.nthreads().values()))
    partitions = min(_count(partitions, "partitions", 1), len(seed_list))
    base, extra = divmod(len(seed_list), partitions)
    chunks, start = [], 0
    for i in range(partitions):
        size = base + (1 if i < extra else 0)
        chunks.append(seed_list[start:start + size])
        start += size
    return chunks


def _gather_merge(client: Any, tasks: list) -> dict:
    """Run each ``(function, *args)`` as one Dask task; the merged rollouts of all."""
    futures = [client.submit(*t, pure=False) for t in tasks]
    try:
        done = client.gather(futures)
    finally:
        for f in futures:
            f.release()
    return _pacs._simulate_merge([part for parts in done for part in parts])


def _external_of(policy: Any, seeds: list, common: dict, progress: Any = None) -> list:
    """The encoded rollouts of a policy object on some seeds (what a worker runs)."""
    return [_pacs._simulate_external(policy, seeds=list(seeds), progress=progress, **common)]


def simulate(
    task: Any = "sorting",
    method: Any = "pacs",
    rollouts: Any = None,
    seed: Any = None,
    *,
    seeds: Any = None,
    client: Any = None,
    partitions: Any = None,
    with_human: bool = True,
    chunk_motion: str = "continuous",
    policy: Any = "nearest",
    log_dir: Any = None,
    threads: Any = None,
    progress: Any = None,
    time_limit: Any = None,
) -> dict:
    """The simulation's evaluation (``pacs simulate``): one rollout per seed for every task and
    method (the same people for every method): the seeds ``seed`` .. ``seed + rollouts - 1``
    (defaults 10 rollouts from seed 1, as ``pacs simulate``), or the list ``seeds``.

    ``task``, ``method``: a name, a comma-separated str, a list, or ``"all"``. ``client``: None
    (here, on ``threads`` threads) or a ``dask.distributed.Client``: the sorted seeds are split
    into ``partitions`` consecutive parts (default: one per worker thread, at most one per
    seed), one task each on one thread; the rollouts are merged in the evaluation's order and
    summarised once, so the result is identical to one local run with the same seeds.
    ``log_dir``: write every rollout's audit log there (on a cluster: a directory the workers
    share).

    ``policy``: a built-in policy's name (``"nearest"``, ``"kernel"``, ``"kernel-paced"``, ``"kernel-shield-paced"``) or a
    policy object with ``act(obs) -> (H, 7)`` joint-position deltas (rad) and optionally
    ``n_action_steps`` (executed actions per chunk, default 8) and ``reset()`` (called before
    each rollout): e.g. :class:`pacs.lerobot.SimulationPolicy` around a LeRobot policy. ``obs``
    is a dict: ``task`` and ``seed`` (the rollout's), ``t`` (s), ``q`` and ``q_before`` (rad, now and one policy step of 33 ms
    earlier), ``stage`` (sub-goals reached), ``person`` and ``person_before`` ((K, 3) m),
    ``tool`` and ``tool_before`` (m). A policy object runs its rollouts one after another on
    the calling thread (``threads`` must be None), or, with a ``client``, on the workers (the
    policy is pickled to them; each partition runs one after another); rows and rollouts say
    ``policy: "external"``. ``progress``: with a policy object run here, called as
    ``progress(done, total)`` after each rollout. ``time_limit``: every rollout's time limit in
    seconds (default: each task's own, 20 s, feeding 60 s; ``pacs simulate --time-limit``); a
    rollout that has not reached all its sub-goals by then fails. Returns ``{"rows": [...], "rollouts": [...]}``: the summary rows (summary.json of
    ``pacs simulate``) and every rollout (rollouts.json), in the evaluation's order.
    """
    _check_client(client)
    tasks = _names(task, "task")
    methods = _names(method, "method")
    seed_list = _seed_list(rollouts, seed, seeds)
    if not isinstance(with_human, bool):
        raise ArgumentTypeError(f"with_human: expected True or False, got {with_human!r}")
    external = not isinstance(policy, str)
    if external and not hasattr(policy, "act"):
        raise ArgumentTypeError(
            f"policy: expected a name or an object with act(obs), got {type(policy).__name__}"
        )
    if not isinstance(chunk_motion, str):
        raise ArgumentTypeError(f"chunk_motion: expected a str, got {chunk_motion!r}")
    if log_dir is not None:
        log_dir = os.fspath(log_dir)
    if time_limit is not None:
        if isinstance(time_limit, bool) or not isinstance(time_limit, (int, float)):
            raise ArgumentTypeError(f"time_limit: expected seconds, got {time_limit!r}")
        time_limit = float(time_limit)
    _pacs._simulate_check(
        tasks, methods, with_human, chunk_motion, "nearest" if external else policy
    )
    if external:
        if threads is not None:
            raise InputError("threads: a policy object runs its rollouts on one thread")
        ext = dict(tasks=tasks, methods=methods, with_human=with_human,
                   chunk_motion=chunk_motion, log_dir=log_dir, time_limit=time_limit)
        if client is None:
            if partitions is not None:
                raise InputError("partitions: only with a client")
            return _pacs._simulate_merge(_external_of(policy, seed_list, ext, progress))
        chunks = _seed_parts(seed_list, partitions, client)
        return _gather_merge(client, [(_external_of, policy, c, ext) for c in chunks])
    common = dict(
        tasks=tasks,
        methods=methods,
        with_human=with_human,
        chunk_motion=chunk_motion,
        policy=policy,
        log_dir=log_dir,
        time_limit=time_limit,
    )
    if client is None:
        if partitions is not None:
            raise InputError("partitions: only with a client")
        parts = _rollouts_of(_ranges(seed_list), _threads(threads), common)
        return _pacs._simulate_merge(parts)
    if threads is not None:
        raise InputError("threads: set the workers' threads on the Dask cluster, not here")
    chunks = _seed_parts(seed_list, partitions, client)
    return _gather_merge(client, [(_rollouts_of, _ranges(c), 1, common) for c in chunks])

"""Tolerance of a policy to being slowed and stopped along its path (:func:`tolerance`)."""

from __future__ import annotations

import html
import json
import math
import os
from typing import Any, Sequence

from . import _pacs
from .errors import ArgumentTypeError, InputError

__all__ = ["tolerance", "tolerance_svg"]


def _floats(x: Any, name: str) -> list[float]:
    try:
        out = [float(v) for v in x]
    except TypeError as e:
        raise ArgumentTypeError(f"{name}: expected a list of numbers, got {x!r}") from e
    if not out:
        raise InputError(f"{name}: empty")
    return out


def tolerance(
    policy: Any = "nearest",
    task: str = "sorting",
    *,
    holds: Sequence[float] = (0.5, 1.0, 2.0, 4.0),
    at: Sequence[float] = (0.3, 0.6),
    rollouts: int = 10,
    seed: int = 1,
    seeds: Sequence[int] | None = None,
    method: str = "pacs",
    plot: str | os.PathLike | None = None,
    progress: Any = None,
) -> dict:
    """Does ``policy`` still succeed on ``task`` when PACS slows or stops it along its path?

    Each seed's rollout runs once undisturbed (``method``, a PACS method, in the task's scene)
    and then once per ``at`` × ``holds`` with an intruder: a person who walks in beside the
    table, reaches a hand to where the tool was at ``at`` (a fraction of the undisturbed
    rollout's duration), holds it there for ``hold`` s, withdraws and leaves. The real shield
    brakes along the path (to rest under SSM), holds and resumes; the policy does not observe
    the intruder, so only the timing of its own motion changes.

    ``policy``: a built-in policy's name (``"nearest"``, ``"kernel"``, ``"kernel-paced"``, ``"kernel-shield-paced"``) or a
    policy object as :func:`pacs.simulate` takes (``act(obs)``, e.g.
    :class:`pacs.lerobot.SimulationPolicy`). Returns ``{"task", "policy", "runs": [...],
    "rows": [...]}``: every interrupted rollout (seed, at, hold, baseline and interrupted
    success and duration, the time the robot stood still and moved slowly while the hand was
    there, deviation, ground-truth violation fraction), and per hold the success rate with a
    95 % Wilson interval, next to the undisturbed rollouts', the mean time at rest and the mean
    extra duration over the rollouts that succeeded both ways (``extra_duration_pairs`` of
    them; ``pacs_sim::tolerance::rows``). ``plot``: also write a one-page SVG of it there.
    ``progress``: called as ``progress(done, total)`` after each rollout.
    """
    from .fleet import _seed_list

    seeds = _seed_list(None if seeds is not None else rollouts,
                       None if seeds is not None else seed, seeds)
    holds_f, at_f = _floats(holds, "holds"), _floats(at, "at")
    if not isinstance(task, str):
        raise ArgumentTypeError(f"task: expected a task name, got {task!r}")
    res = _pacs._tolerance(policy, task, method, seeds, at_f, holds_f, progress)
    runs, rows = res["runs"], res["rows"]
    name = policy if isinstance(policy, str) else type(policy).__name__
    out = {"task": task, "policy": name, "method": method, "seeds": seeds, "at": at_f,
           "runs": runs, "rows": rows}
    if plot is not None:
        with open(os.fspath(plot), "w", encoding="utf-8") as f:
            f.write(tolerance_svg(out))
    return out


def tolerance_svg(result: dict) -> str:
    """A one-page SVG of a :func:`tolerance` result: success rate against the hold time (95 %
    Wilson intervals; hold 0 = undisturbed), and the time the robot stood still and the extra
    duration against it."""
    rows = result["rows"]
    w, h = 820, 1060
    left, right = 90, 60
    pw = w - left - right
    hmax = max(r["hold_s"] for r in rows) or 1.0

    def x(hold: float) -> float:
        return left + pw * hold / hmax

    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
        f'viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="13">',
        '<rect width="100%" height="100%" fill="white"/>',
        f'<text x="{w / 2}" y="36" text-anchor="middle" font-size="20">Tolerance to being '
        f'stopped along the path</text>',
        f'<text x="{w / 2}" y="60" text-anchor="middle">task {html.escape(result["task"])} · '
        f'policy {html.escape(str(result["policy"]))} · {html.escape(result["method"])} · '
        f'{len(result["seeds"])} seeds × intrusions at {", ".join(f"{a:.0%}" for a in result["at"])} '
        f'of the rollout</text>',
    ]

    def panel(top: float, height: float, title: str, ylabel: str, ymax: float,
              series: list[tuple[str, str, list[tuple[float, float, float, float]]]]) -> None:
        bottom = top + height
        parts.append(f'<text x="{left}" y="{top - 14}" font-size="15">{html.escape(title)}</text>')
        parts.append(f'<line x1="{left}" y1="{bottom}" x2="{left + pw}" y2="{bottom}" '
                     f'stroke="black"/>')
        parts.append(f'<line x1="{left}" y1="{top}" x2="{left}" y2="{bottom}" stroke="black"/>')
        for i in range(6):
            v = ymax * i / 5
            y = bottom - height * i / 5
            parts.append(f'<line x1="{left - 4}" y1="{y}" x2="{left + pw}" y2="{y}" '
                         f'stroke="#ddd"/>')
            parts.append(f'<text x="{left - 8}" y="{y + 4}" text-anchor="end">{v:.2g}</text>')
        for r in rows:
            parts.append(f'<text x="{x(r["hold_s"])}" y="{bottom + 18}" '
                         f'text-anchor="middle">{r["hold_s"]:g}</text>')
        parts.append(f'<text x="{left + pw / 2}" y="{bottom + 38}" text-anchor="middle">'
                     f'hand held beside the tool (s); 0 = undisturbed</text>')
        parts.append(f'<text transform="translate({left - 52},{top + height / 2}) rotate(-90)" '
                     f'text-anchor="middle">{html.escape(ylabel)}</text>')
        for k, (label, colour, pts) in enumerate(series):
            def y(v: float) -> float:
                return bottom - height * min(max(v / ymax, 0.0), 1.0)
            path = " ".join(f"{'M' if i == 0 else 'L'}{x(px):.1f},{y(py):.1f}"
                            for i, (px, py, _, _) in enumerate(pts))
            parts.append(f'<path d="{path}" fill="none" stroke="{colour}" stroke-width="2"/>')
            for px, py, lo, hi in pts:
                parts.append(f'<line x1="{x(px):.1f}" y1="{y(lo):.1f}" x2="{x(px):.1f}" '
                             f'y2="{y(hi):.1f}" stroke="{colour}"/>')
                parts.append(f'<circle cx="{x(px):.1f}" cy="{y(py):.1f}" r="4" '
                             f'fill="{colour}"/>')
            parts.append(f'<text x="{left + pw - 8}" y="{top + 18 + 18 * k}" text-anchor="end" '
                         f'fill="{colour}">{html.escape(label)}</text>')

    panel(110, 380, "Success rate", "success (95 % Wilson interval)", 1.0,
          [("success", "#1f5fa8",
            [(r["hold_s"], r["success"], *r["success_wilson95"]) for r in rows])])
    ymax = max([r["mean_extra_duration_s"] for r in rows] + [r["mean_stopped_s"] for r in rows]
               + [1.0])
    panel(600, 330, "Time lost", "seconds (mean over rollouts)", math.ceil(ymax),
          [("extra duration (pairs that succeeded both ways)", "#b5462b",
            [(r["hold_s"], r["mean_extra_duration_s"], r["mean_extra_duration_s"],
              r["mean_extra_duration_s"]) for r in rows]),
           ("robot at rest while the hand was there", "#2b8a3e",
            [(r["hold_s"], r["mean_stopped_s"], r["mean_stopped_s"], r["mean_stopped_s"])
             for r in rows])])
    viol = max((r["violation_fraction"] for r in result["runs"]), default=0.0)
    parts.append(f'<text x="{left}" y="{h - 40}">Largest ground-truth violation fraction over '
                 f'the interrupted rollouts: {viol:g}. Rows: '
                 f'{html.escape(json.dumps([round(r["success"], 3) for r in rows]))}</text>')
    parts.append("</svg>")
    return "\n".join(parts)

"""Crowds read back (``copi crowd``): a summary per method and density, the figure of
success and time to goal against density, and the animation of one run. The summary and
the figure come from the results store only (table ``lifelong``, runs of experiment
``crowd``: one row per agent); the animation from a run's recorded frames
(:attr:`copi.world.crowd.Crowd.frames`)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import atomic_path
from copi.errors import InvalidArgumentError
from copi.reports import check_frames, finish_figure, new_figure
from copi.results import ResultsStore
from copi.world import World, rasterize

__all__ = ["CrowdSummary", "crowd_summary", "save_crowd_figure", "save_crowd_gif"]


@dataclass(frozen=True)
class CrowdSummary:
    """One method at one density, over its runs' agents (each agent's first trip)."""

    method: str
    sensing: str
    density: float
    """Agents per square agent step."""
    agents: int
    """Agents in each crowd."""
    runs: int
    success: float
    """Share of agents that reached their goal without a contact."""
    collision: float
    timeout: float
    time_median: float
    """Median steps to the goal of those that reached it (NaN: none did)."""
    excess_median: float
    """Median path excess over the straight line of those that reached it."""
    decision_us: float
    """Mean wall time of one agent's decision, microseconds."""


def crowd_summary(results: str | os.PathLike[str]) -> list[CrowdSummary]:
    """The crowds of ``results`` by method and density (in the order the runs were
    registered, densities ascending)."""
    with ResultsStore(results, readonly=True) as store:
        runs = {r.run_id: r for r in store.runs() if r.experiment == "crowd"}
        rows = [r for r in store.lifelong() if r.run_id in runs]
    by: dict[str, list[Any]] = {}
    for r in rows:
        by.setdefault(r.run_id, []).append(r)
    out = []
    for rid, run in runs.items():
        got = by.get(rid, [])
        if not got:
            continue
        ok = [r for r in got if r.success]
        n = len(got)
        us = [r.decision_us for r in got if r.decision_us is not None]
        out.append(CrowdSummary(
            method=run.method, sensing=str(run.config.get("sensing")),
            density=float(run.config["density"]), agents=int(run.config["agents"]),
            runs=len({r.life for r in got}), success=len(ok) / n,
            collision=sum(r.outcome == "collision" for r in got) / n,
            timeout=sum(r.outcome == "timeout" for r in got) / n,
            time_median=float(np.median([r.steps for r in ok])) if ok else math.nan,
            excess_median=float(np.median([r.excess for r in ok if r.excess is not None]))
            if any(r.excess is not None for r in ok) else math.nan,
            decision_us=float(np.mean(us)) if us else math.nan,
        ))  # fmt: skip
    order = {m: i for i, m in enumerate(dict.fromkeys(s.method for s in out))}
    return sorted(out, key=lambda s: (order[s.method], s.agents, s.density))


def save_crowd_figure(
    results: str | os.PathLike[str], path: str | os.PathLike[str]
) -> Path:
    """Success and median time to goal against density, a line per method (and crowd
    size), from the store ``results``; written to ``path`` (a PNG)."""
    summary = crowd_summary(results)
    if not summary:
        raise InvalidArgumentError(f"{results}: no crowd runs to draw")
    fig = new_figure(8.0, 3.4)
    ax_s, ax_t = fig.subplots(1, 2)
    lines: dict[tuple[str, int], list[CrowdSummary]] = {}
    for s in summary:
        lines.setdefault((s.method, s.agents), []).append(s)
    many = len({n for _, n in lines}) > 1
    for (method, n), pts in lines.items():
        x = [p.density for p in pts]
        label = f"{method} ({n:,})" if many else method
        style = {"marker": "o", "lw": 1.5, "ms": 4}
        ax_s.plot(x, [100 * p.success for p in pts], label=label, **style)
        ax_t.plot(x, [p.time_median for p in pts], label=label, **style)
    for ax, what in ((ax_s, "success (% of agents)"), (ax_t, "median steps to goal")):
        ax.set_xlabel("density (agents per square agent step)")
        ax.set_ylabel(what)
        ax.grid(alpha=0.3)
        if len({p.density for p in summary}) > 1 and max(p.density for p in summary) > 4 * min(
            p.density for p in summary
        ):
            ax.set_xscale("log")
    ax_s.set_ylim(0, 100)
    ax_s.legend(fontsize=8)
    agents = sorted({s.agents for s in summary})
    fig.suptitle(f"crowds of {', '.join(f'{a:,}' for a in agents)} agents: each agent's first "
                 "trip (success: its goal, no contact)", fontsize=9)  # fmt: skip
    return finish_figure(fig, path)


def save_crowd_gif(
    world: World,
    frames: Sequence[tuple[int, NDArray[np.float32], NDArray[np.bool_]]],
    path: str | os.PathLike[str],
    *,
    radius: float = 0.3,
    goal: Any = None,
    size: int = 480,
    fps: int = 10,
) -> Path:
    """Animate a crowd's recorded frames (t, positions, in the world) as a GIF: every
    agent still in the world a blue disc, agent 0 red with its path so far (and its
    ``goal``, a green star, when given).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from copi.world.crowd import Crowd, crowd_room
    >>> crowd = Crowd.draw(crowd_room(20, 0.1), 20, seed=0, record_every=1)
    >>> _ = crowd.step(crowd.goals - crowd.positions)
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "crowd.gif"
    >>> save_crowd_gif(crowd.world, crowd.frames, out, size=64).stat().st_size > 0
    True
    """
    from PIL import Image

    target = Path(path)
    if target.suffix.lower() != ".gif":
        raise InvalidArgumentError(f"the animation must end in .gif; got {target.name!r}")
    if not frames:
        raise InvalidArgumentError("no frames recorded: make the crowd with record_every >= 1")
    if fps < 1:
        raise InvalidArgumentError(f"fps must be >= 1; got {fps}")
    check_frames(size, len(frames))
    track = np.array([f[1][0] for f in frames], dtype=np.float64)
    pictures = []
    for n, (_, pos, active) in enumerate(frames):
        inside = np.asarray(active, dtype=bool)
        others = inside.copy()
        others[0] = False
        here = track[: n + 1] if inside[0] else track[:n]
        pictures.append(Image.fromarray(rasterize(
            world, width=size, centers=np.asarray(pos, dtype=np.float64)[others],
            radii=radius, path=here if len(here) else None,
            position=track[n] if inside[0] else None, agent_radius=radius, goal=goal,
        )))  # fmt: skip
    durations = [round(1000 / fps)] * (len(pictures) - 1) + [2000]  # hold the last frame
    with atomic_path(target, "gif") as tmp:
        pictures[0].save(tmp, format="GIF", save_all=True, append_images=pictures[1:],
                         duration=durations, loop=0)  # fmt: skip
    return target

"""Pictures of worlds and episodes, written to files."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import atomic_path, save_figure
from copi.world import Simulator, World, draw_simulator, draw_world

__all__ = [
    "finish_figure",
    "new_figure",
    "save_episode_gif",
    "save_episode_png",
    "save_overview_png",
    "save_plan_png",
]


def new_figure(width: float, height: float, dpi: int = 110) -> Any:
    """A matplotlib figure of ``width`` x ``height`` inches drawn off screen (no pyplot,
    no global state: safe in worker processes and threads)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def finish_figure(
    fig: Any, path: str | os.PathLike[str], *, tight: bool = True, **savefig: Any
) -> Path:
    """Every figure's last step: laid out tight (``tight=False``: as the caller laid it
    out) and written to ``path`` atomically, in the format its suffix names."""
    if tight:
        fig.tight_layout()
    target = Path(path)
    save_figure(fig, target, **savefig)
    return target


def _title(sim: Simulator) -> str:
    return f"{sim.world.name}  ({sim.t} steps, {len(sim.radii)} obstacles)"


def save_episode_png(sim: Simulator, path: str | os.PathLike[str]) -> Path:
    """One episode as a picture: walls, obstacles with their traces, the agent's path in
    red, the goal, and the sensor rays at the last step (the paper's Fig. 3 style)."""
    fig = new_figure(5.0, 5.0)
    ax = fig.add_subplot()
    draw_simulator(ax, sim, title=_title(sim))
    return finish_figure(fig, Path(path))


def save_plan_png(
    world: World, path: Any, out: str | os.PathLike[str], *, title: str | None = None
) -> Path:
    """A world with a planned path (red) from its start (ring) to its goal (star)."""
    pts = np.asarray(path, dtype=float)
    w, h = _aspect(world)
    fig = new_figure(w, h)
    ax = fig.add_subplot()
    draw_world(ax, world, path=pts, start=pts[0], goal=pts[-1], agent_radius=0.0, title=title)
    ax.plot(pts[:, 0], pts[:, 1], ".", color="#d62728", ms=4, zorder=6)
    return finish_figure(fig, Path(out))


def _aspect(world: World) -> tuple[float, float]:
    xmin, ymin, xmax, ymax = world.bounds
    ratio = (ymax - ymin) / max(xmax - xmin, 1e-9)
    return (6.0, max(2.5, min(9.0, 6.0 * ratio)))


def save_overview_png(sims: Sequence[Simulator], path: str | os.PathLike[str]) -> Path:
    """Several episodes side by side in a grid (at most 4 columns)."""
    n = len(sims)
    cols = min(4, n)
    rows = math.ceil(n / cols)
    fig = new_figure(3.4 * cols, 3.4 * rows)
    for k, sim in enumerate(sims):
        ax = fig.add_subplot(rows, cols, k + 1)
        draw_simulator(ax, sim, rays=False, title=_title(sim))
    return finish_figure(fig, Path(path))


def save_episode_gif(
    sim: Simulator, path: str | os.PathLike[str], *, fps: int = 12, max_frames: int = 100
) -> Path:
    """Animate a recorded episode (``Simulator(record=True)``) as a GIF.

    The walls are drawn once; each frame moves the obstacles, extends the traces and the
    agent's path, and redraws the sensor rays. Long episodes are shown every k-th step so
    that at most ``max_frames`` frames are written.
    """
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.artist import Artist
    from matplotlib.patches import Circle

    if len(sim.path) < 2:
        raise ValueError("the simulator recorded no steps; create it with record=True and step it")
    path_arr = np.asarray(sim.path)
    traces = np.asarray(sim.traces)
    fig = new_figure(4.0, 4.0, dpi=72)
    ax = fig.add_subplot()
    draw_world(ax, sim.world, goal=sim.goal, start=path_arr[0], title=sim.world.name)
    trace_lines = [
        ax.plot([], [], color="#3b6fb6", lw=0.6, alpha=0.45)[0] for _ in range(traces.shape[1])
    ]
    discs = [ax.add_patch(Circle((0, 0), r, fc="#3b6fb6", ec="none", alpha=0.8)) for r in sim.radii]
    (agent_line,) = ax.plot([], [], color="#d62728", lw=1.4, zorder=6)
    agent = ax.add_patch(Circle((0, 0), sim.agent_radius, fc="#d62728", ec="none", zorder=7))
    angles = sim.sensor.angles
    directions = np.column_stack([np.cos(angles), np.sin(angles)])
    rays = ax.plot([], [], color="#f0a030", lw=0.4, zorder=4)[0]
    fig.tight_layout()

    def frame(t: int) -> list[Artist]:
        for k, line in enumerate(trace_lines):
            line.set_data(traces[: t + 1, k, 0], traces[: t + 1, k, 1])
            discs[k].center = tuple(traces[t, k])
        agent_line.set_data(path_arr[: t + 1, 0], path_arr[: t + 1, 1])
        agent.center = tuple(path_arr[t])
        ranges = sim.sensor.scan(sim.world, path_arr[t], traces[t], sim.radii)
        ends = path_arr[t] + ranges[:, None] * directions
        xs = np.column_stack(
            [np.full(len(ends), path_arr[t, 0]), ends[:, 0], np.full(len(ends), np.nan)]
        )
        ys = np.column_stack(
            [np.full(len(ends), path_arr[t, 1]), ends[:, 1], np.full(len(ends), np.nan)]
        )
        rays.set_data(xs.ravel(), ys.ravel())
        return [*trace_lines, *discs, agent_line, agent, rays]

    stride = max(1, math.ceil(len(path_arr) / max_frames))
    frames = [*range(0, len(path_arr) - 1, stride), len(path_arr) - 1]
    anim = FuncAnimation(fig, frame, frames=frames, blit=False)
    out = Path(path)
    with atomic_path(out, "gif") as tmp:
        anim.save(tmp, writer=PillowWriter(fps=fps))
    return out

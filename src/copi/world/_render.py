"""Drawing worlds and episodes on Matplotlib axes (no files: saving is the
experiments' job)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from copi.world._world import World

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from copi.world._simulator import Simulator

__all__ = ["draw_simulator", "draw_world", "render_rgb"]

WALL = "#222222"
HOLE = "#9a9a9a"
OBSTACLE = "#3b6fb6"
AGENT = "#d62728"
GOAL = "#2ca02c"


def draw_world(
    ax: Axes,
    world: World,
    *,
    centers: Any = None,
    radii: Any = None,
    traces: Any = None,
    path: Any = None,
    start: Any = None,
    goal: Any = None,
    rays: tuple[Any, Any, Any] | None = None,
    agent_radius: float = 0.3,
    title: str | None = None,
) -> Axes:
    """Draw a world and, optionally, an episode in it, on ``ax``.

    Parameters
    ----------
    ax : matplotlib Axes
    world : World
    centers, radii : (d, 2), (d,), optional
        Moving obstacles now (blue discs).
    traces : (t, d, 2), optional
        Obstacle centres over time (thin blue lines, as the paper's Fig. 3).
    path : (t, 2), optional
        The agent's centre over time (red line); the agent is drawn at its last point.
    start, goal : (2,), optional
        Start (red ring) and goal (green star).
    rays : (position, ranges, angles), optional
        Sensor rays from ``position``.
    """
    from matplotlib.patches import Circle
    from matplotlib.patches import Polygon as MplPolygon

    ax.add_patch(MplPolygon(world.boundary, closed=True, fc="white", ec=WALL, lw=1.5, zorder=0))
    for hole in world.holes:
        ax.add_patch(MplPolygon(hole, closed=True, fc=HOLE, ec=WALL, lw=1.0, zorder=1))
    if traces is not None:
        tr = np.asarray(traces)
        for k in range(tr.shape[1]):
            ax.plot(tr[:, k, 0], tr[:, k, 1], color=OBSTACLE, lw=0.6, alpha=0.45, zorder=2)
    if centers is not None:
        c = np.asarray(centers).reshape(-1, 2)
        r = np.broadcast_to(np.asarray(radii if radii is not None else 0.5), (len(c),))
        for (x, y), rad in zip(c, r, strict=True):
            ax.add_patch(Circle((x, y), rad, fc=OBSTACLE, ec="none", alpha=0.8, zorder=3))
    if rays is not None:
        pos, ranges, angles = (np.asarray(v, dtype=float) for v in rays)
        ends = pos + ranges[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
        for e in ends:
            ax.plot([pos[0], e[0]], [pos[1], e[1]], color="#f0a030", lw=0.5, zorder=4)
    if start is not None:
        ax.plot(*np.asarray(start), "o", mfc="none", mec=AGENT, ms=7, zorder=5)
    if goal is not None:
        ax.plot(*np.asarray(goal), "*", color=GOAL, ms=14, zorder=5)
    if path is not None:
        p = np.asarray(path).reshape(-1, 2)
        ax.plot(p[:, 0], p[:, 1], color=AGENT, lw=1.4, zorder=6)
        if agent_radius > 0:
            ax.add_patch(Circle(tuple(p[-1]), agent_radius, fc=AGENT, ec="none", zorder=7))
    xmin, ymin, xmax, ymax = world.bounds
    pad = 0.03 * max(xmax - xmin, ymax - ymin)
    ax.set_xlim(xmin - pad, xmax + pad)
    ax.set_ylim(ymin - pad, ymax + pad)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)
    return ax


def draw_simulator(
    ax: Axes, sim: Simulator, *, rays: bool = True, title: str | None = None
) -> Axes:
    """Draw the current state of a simulator, with its recorded path and traces."""
    return draw_world(
        ax,
        sim.world,
        centers=sim.centers,
        radii=sim.radii,
        traces=np.asarray(sim.traces) if sim.traces else None,
        path=np.asarray(sim.path) if sim.path else sim.position[None],
        start=sim.path[0] if sim.path else None,
        goal=sim.goal,
        rays=(sim.position, sim.ranges, sim.sensor.angles) if rays else None,
        agent_radius=sim.agent_radius,
        title=title,
    )


def render_rgb(sim: Simulator, *, pixels: int = 400) -> NDArray[np.uint8]:
    """The simulator's state as an RGB image of shape (pixels, pixels, 3)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    dpi = 100
    fig = Figure(figsize=(pixels / dpi, pixels / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0.02, 0.02, 0.96, 0.96))
    draw_simulator(ax, sim, title=None)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()

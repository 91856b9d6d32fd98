"""Drawing worlds and episodes: on Matplotlib axes for figures, and straight into an RGB
array (Pillow, no Matplotlib) for environments' ``render()`` and animations. No files:
saving is the experiments' job."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from copi.world._world import World

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from copi.world._simulator import Simulator

__all__ = ["draw_simulator", "draw_world", "rasterize", "render_rgb"]

WALL = "#222222"
HOLE = "#9a9a9a"
OBSTACLE = "#3b6fb6"
AGENT = "#d62728"
GOAL = "#2ca02c"
RAY = "#f0a030"
FUTURE = "#f2a7c3"
PURSUER = "#222222"
MOVE = "#444444"
CHOSEN = "#7b2cbf"


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


def rasterize(
    world: World,
    *,
    width: int = 400,
    height: int | None = None,
    centers: Any = None,
    radii: Any = None,
    traces: Any = None,
    path: Any = None,
    position: Any = None,
    agent_radius: float = 0.3,
    start: Any = None,
    goal: Any = None,
    rays: tuple[Any, Any, Any] | None = None,
    pursuer: tuple[Any, float, float] | None = None,
    pursuer_path: Any = None,
    moves: tuple[Any, Any] | None = None,
    futures: Any = None,
    supersample: int | None = None,
) -> NDArray[np.uint8]:
    """Draw a world and an episode's state into an RGB image, without Matplotlib.

    The same picture as :func:`draw_world` (walls dark, holes grey, moving obstacles
    blue with their traces, rays orange, the agent's path and disc red, the goal a green
    star), rasterised with Pillow at ``supersample`` times the size and reduced, so
    that it is fast enough for ``render()`` every step (about 1 ms at 64 x 64, a few at
    400 x 400). The world is fitted into the image with its aspect ratio kept.

    Parameters
    ----------
    world : World
    width, height : int
        Image size in pixels (height defaults to width).
    centers, radii : (d, 2), (d,), optional
        Moving obstacles now.
    traces : (t, d, 2), optional
        Obstacle centres over time.
    path : (t, 2), optional
        The agent's centre over time; the agent is drawn at its last point unless
        ``position`` is given.
    position : (2,), optional
        The agent's centre now.
    start, goal : (2,), optional
    rays : (position, ranges, angles), optional
    pursuer : (position (2,), heading in radians, capture radius), optional
        The homicidal chauffeur's car: a dark arrowhead along its heading inside a ring
        of its capture radius.
    pursuer_path : (t, 2), optional
    moves : (candidates (k, 2), chosen (2,)), optional
        Moves the agent could make from where it stands (dark grey lines) and the one it
        made (a thick purple line), drawn three times their length.
    futures : (s, t, d, 2), optional
        Futures of the moving obstacles an agent expected (``s`` samples of ``t`` steps of
        ``d`` bodies): thin pink lines, one per sample and body.
    supersample : int, optional
        Drawing scale before the reduction (anti-aliasing); default 4 below 200 pixels,
        else 2.

    Returns
    -------
    ndarray of shape (height, width, 3), uint8

    Examples
    --------
    >>> from copi.world import World, rasterize
    >>> room = World([[0, 0], [10, 0], [10, 10], [0, 10]])
    >>> rasterize(room, width=64, position=[5, 5], goal=[8, 8]).shape
    (64, 64, 3)
    """
    from PIL import Image, ImageDraw

    h_px = int(width if height is None else height)
    w_px = int(width)
    s = int(supersample or (4 if min(w_px, h_px) < 200 else 2))
    W, H = w_px * s, h_px * s
    xmin, ymin, xmax, ymax = world.bounds
    pad = 0.03 * max(xmax - xmin, ymax - ymin)
    xmin, ymin, xmax, ymax = xmin - pad, ymin - pad, xmax + pad, ymax + pad
    scale = min(W / (xmax - xmin), H / (ymax - ymin))
    ox = 0.5 * (W - scale * (xmax - xmin)) - scale * xmin
    oy = 0.5 * (H - scale * (ymax - ymin)) + scale * ymax

    def px(points: Any) -> list[tuple[float, float]]:
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        return list(
            zip((ox + scale * p[:, 0]).tolist(), (oy - scale * p[:, 1]).tolist(), strict=True)
        )

    def disc(
        center: Any, r: float, fill: str | None, outline: str | None = None, lw: int = 0
    ) -> None:
        ((cx, cy),) = px(center)
        rr = max(scale * r, 0.75 * s)
        draw.ellipse((cx - rr, cy - rr, cx + rr, cy + rr), fill=fill, outline=outline, width=lw)

    line = max(1, round(max(W, H) / 400))
    img = Image.new("RGB", (W, H), "#e8e8e8")
    draw = ImageDraw.Draw(img)
    draw.polygon(px(world.boundary), fill="white", outline=WALL, width=2 * line)
    for hole in world.holes:
        draw.polygon(px(hole), fill=HOLE, outline=WALL, width=line)
    if traces is not None:
        tr = np.asarray(traces, dtype=np.float64)
        if tr.ndim == 3 and tr.shape[0] > 1:
            for k in range(tr.shape[1]):
                draw.line(px(tr[:, k]), fill="#aabfdf", width=line)
    if centers is not None:
        c = np.asarray(centers, dtype=np.float64).reshape(-1, 2)
        r = np.broadcast_to(np.asarray(radii if radii is not None else 0.5, dtype=float), (len(c),))
        for ck, rk in zip(c, r, strict=True):
            disc(ck, float(rk), OBSTACLE)
    if futures is not None:
        fu = np.asarray(futures, dtype=np.float64)
        if fu.ndim == 4 and fu.shape[1] > 1:
            for smp in fu:
                for k in range(fu.shape[2]):
                    draw.line(px(smp[:, k]), fill=FUTURE, width=line)
    if pursuer_path is not None and len(pursuer_path) > 1:
        draw.line(px(pursuer_path), fill="#777777", width=line)
    if rays is not None:
        pos, ranges, angles = (np.asarray(v, dtype=float) for v in rays)
        ends = pos + ranges[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
        (p0,) = px(pos)
        for e in px(ends):
            draw.line([p0, e], fill=RAY, width=line)
    if start is not None:
        disc(start, 0.4, None, AGENT, line)
    if goal is not None:
        ((gx, gy),) = px(goal)
        rr = max(scale * 1.0, 4 * s)
        tips = np.arange(10)
        rad = np.where(tips % 2 == 0, rr, 0.45 * rr)
        ang = np.pi / 2 + tips * np.pi / 5
        draw.polygon(
            list(
                zip(
                    (gx + rad * np.cos(ang)).tolist(),
                    (gy - rad * np.sin(ang)).tolist(),
                    strict=True,
                )
            ),
            fill=GOAL,
        )
    if path is not None:
        p = np.asarray(path, dtype=np.float64).reshape(-1, 2)
        if len(p) > 1:
            draw.line(px(p), fill=AGENT, width=2 * line, joint="curve")
        if position is None:
            position = p[-1]
    if position is not None:
        disc(position, agent_radius, AGENT)
    if moves is not None and position is not None:
        candidates, chosen = moves
        (p0,) = px(position)
        here = np.asarray(position, dtype=np.float64)
        for v in np.asarray(candidates, dtype=np.float64).reshape(-1, 2):
            draw.line([p0, px(here + 3 * v)[0]], fill=MOVE, width=2 * line)
        draw.line([p0, px(here + 3 * np.asarray(chosen, dtype=float))[0]], fill=CHOSEN,
                  width=3 * line)  # fmt: skip
    if pursuer is not None:
        ppos, heading, capture = pursuer
        disc(ppos, float(capture), None, PURSUER, line)
        ((cx, cy),) = px(ppos)
        size = max(scale * 1.3, 5 * s)
        a = np.array([0.0, 2.5, -2.5]) + float(heading)
        rad = np.array([size, 0.8 * size, 0.8 * size])
        draw.polygon(
            list(
                zip((cx + rad * np.cos(a)).tolist(), (cy - rad * np.sin(a)).tolist(), strict=True)
            ),
            fill=PURSUER,
        )
    if s > 1:
        img = img.reduce(s)
    return np.asarray(img, dtype=np.uint8)


def render_rgb(
    sim: Simulator,
    *,
    pixels: int = 400,
    height: int | None = None,
    rays: bool = True,
    goal: bool = True,
    pursuer: tuple[Any, float, float] | None = None,
    pursuer_path: Any = None,
) -> NDArray[np.uint8]:
    """The simulator's state as an RGB image of shape (height, pixels, 3) (square by
    default), drawn by :func:`rasterize`: walls, obstacles and their traces, the rays,
    the agent's path and disc, the goal (unless ``goal=False``) and, for the chase, the
    pursuer."""
    return rasterize(
        sim.world,
        width=pixels,
        height=height,
        centers=sim.centers,
        radii=sim.radii,
        traces=np.asarray(sim.traces) if sim.traces else None,
        path=np.asarray(sim.path) if sim.path else None,
        position=sim.position,
        agent_radius=sim.agent_radius,
        start=sim.path[0] if sim.path else None,
        goal=sim.goal if goal else None,
        rays=(sim.position, sim.ranges, sim.sensor.angles) if rays else None,
        pursuer=pursuer,
        pursuer_path=pursuer_path,
    )

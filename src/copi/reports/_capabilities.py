"""The paper's Fig. 1 (the representation-building process) and Fig. 2 (the permutation
automaton), drawn from a capabilities file."""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from copi.geometry import ring_angles
from copi.learning import Capabilities, Operator, PermutationAutomaton, local_world
from copi.reports._figures import finish_figure, new_figure

__all__ = ["fig2_operators", "save_capability_figures"]

def _palette(n: int) -> list[tuple[float, float, float, float]]:
    """``n`` distinct colours, one per template: Matplotlib's qualitative tab10, tab20,
    then tab20 + tab20b + tab20c (60); beyond that, evenly spaced hues (not cycled, so
    two templates never share a colour)."""
    from matplotlib import colormaps

    if n <= 10:
        return [colormaps["tab10"](i) for i in range(n)]
    if n <= 20:
        return [colormaps["tab20"](i) for i in range(n)]
    if n <= 60:
        return [colormaps[m](i) for m in ("tab20", "tab20b", "tab20c") for i in range(20)][:n]
    return [colormaps["hsv"](i / n) for i in range(n)]


def _direction_colours(n: int) -> list[tuple[float, float, float, float]]:
    """A colour per compass direction (E first, counter-clockwise), on a cyclic map of
    hues so that neighbouring directions look alike and none fades into the paper."""
    from matplotlib import colormaps

    return [colormaps["hsv"](0.9 * i / n) for i in range(n)]


def fig2_operators() -> tuple[Operator, Operator]:
    """The toy domain of the paper's Fig. 2: a 7-element state (1-4 wall distances, 5
    speed, 6-7 target distances), o rotating elements 1-4 (order 4), p swapping 6-7."""
    return (
        Operator("o", [3, 0, 1, 2, 4, 5, 6]),
        Operator("p", [0, 1, 2, 3, 4, 6, 5]),
    )


def save_context_map(caps: Capabilities, out: Path) -> Path:
    """Fig. 1(c, d): the context map projected on its two principal axes, nodes coloured
    by landmark, edges in grey, landmarks as large labelled markers."""
    nodes = caps.nodes
    mean = nodes.mean(0)
    _, _, vt = np.linalg.svd(nodes - mean, full_matrices=False)
    xy = (nodes - mean) @ vt[:2].T
    lm_xy = (caps.landmarks.points - mean) @ vt[:2].T
    fig = new_figure(7.0, 6.0)
    ax = fig.add_subplot()
    from matplotlib.collections import LineCollection

    # All of the map's edges are a hairball (thousands); its minimum spanning tree over
    # the readings' distances keeps the map's shape with one edge per node.
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import minimum_spanning_tree

    e = np.asarray(caps.edges, dtype=np.int64).reshape(-1, 2)
    weights = np.linalg.norm(nodes[e[:, 0]] - nodes[e[:, 1]], axis=1) + 1e-12
    tree = minimum_spanning_tree(coo_matrix((weights, (e[:, 0], e[:, 1])),
                                            shape=(len(nodes), len(nodes)))).tocoo()  # fmt: skip
    segs = xy[np.stack([tree.row, tree.col], axis=1)]
    ax.add_collection(LineCollection(segs, colors="#bbbbbb", linewidths=0.5, zorder=1))
    palette = _palette(len(caps.reduction.templates))
    colours = [palette[int(t)] for t in caps.node_template]
    ax.scatter(xy[:, 0], xy[:, 1], s=6, c=colours, zorder=2)
    for j, (x, y) in enumerate(lm_xy):
        t = int(caps.reduction.template_of[j])
        ax.scatter([x], [y], s=90, color=palette[t], edgecolors="black", linewidths=0.8, zorder=3)
        ax.annotate(str(j), (x, y), fontsize=6, ha="center", va="center", zorder=4)
    ax.set_title(
        f"context map: {len(nodes)} nodes ({len(caps.edges)} edges; drawn: their minimum "
        f"spanning tree) -> {caps.landmarks.n_landmarks} landmarks (colour: template)",
        fontsize=9,
    )
    ax.set_xlabel("first principal axis of the readings")
    ax.set_ylabel("second principal axis")
    return finish_figure(fig, out / "fig1_context_map.png")


def save_skeleton_curve(caps: Capabilities, out: Path) -> Path:
    """Fig. 1(d) aside: H(k) against the number of contractions, the chosen k marked."""
    lm = caps.landmarks
    fig = new_figure(7.0, 4.5)
    ax = fig.add_subplot()
    k = np.arange(len(lm.curve))
    ax.plot(k, lm.curve, color="#1f77b4", lw=1.2, label="H(k), Hausdorff distance to the map")
    ax.annotate(
        f"k = {lm.k}\n{lm.n_landmarks} landmarks",
        (lm.k, lm.curve[lm.k]),
        xytext=(-90, 30),
        textcoords="offset points",
        arrowprops={"arrowstyle": "->"},
        fontsize=8,
    )
    ax.set_xlabel("contractions k")
    ax.set_ylabel("H(k), agent steps")
    twin = ax.twinx()
    (crit,) = twin.plot(k, lm.criterion, color="#7f7f7f", lw=0.6, alpha=0.6,
                        label="the rule's criterion (right axis)")  # fmt: skip
    twin.set_ylabel("criterion", color="#7f7f7f")
    chosen = ax.axvline(lm.k, color="#d62728", lw=1, ls="--", label="the refinement kept")
    handles, labels = ax.get_legend_handles_labels()
    ax.legend([*handles[:1], crit, chosen], [labels[0], crit.get_label(), chosen.get_label()],
              loc="upper left", fontsize=8)  # fmt: skip
    return finish_figure(fig, out / "fig1_skeleton_curve.png")


def _polar(ax, ranges: np.ndarray, max_range: float, colour: Any) -> None:  # type: ignore[no-untyped-def]
    a = ring_angles(len(ranges))
    pts = np.column_stack([ranges * np.cos(a), ranges * np.sin(a)])
    loop = np.vstack([pts, pts[:1]])
    ax.fill(loop[:, 0], loop[:, 1], color=colour, alpha=0.25)
    ax.plot(loop[:, 0], loop[:, 1], color=colour, lw=1)
    ax.plot([0], [0], "k.", ms=3)
    ax.set_xlim(-max_range, max_range)
    ax.set_ylim(-max_range, max_range)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def save_landmarks(caps: Capabilities, out: Path) -> Path:
    """Fig. 1(d, e): every landmark as the region its readings enclose (agent at the
    centre, rays in the world frame), coloured by template, with the operator word that
    maps it onto its template; templates framed."""
    max_range = float(caps.params.get("max_range", caps.nodes.max()))
    pts = caps.landmarks.points[:, : caps.n_rays]  # the reading block (motion aside)
    n = len(pts)
    cols = min(10, n)
    rows = math.ceil(n / cols)
    fig = new_figure(1.5 * cols, 1.6 * rows + 0.4)
    red = caps.reduction
    templates = set(red.templates.tolist())
    palette = _palette(len(red.templates))
    for j in range(n):
        ax = fig.add_subplot(rows, cols, j + 1)
        t = int(red.template_of[j])
        _polar(ax, pts[j], max_range, palette[t])
        word = caps.group.words[int(red.element[j])] or "id"
        ax.set_title(f"{j} -> T{t} [{word}]", fontsize=6)
        if j in templates:
            for side in ax.spines.values():
                side.set_linewidth(2.0)
    fig.suptitle(
        f"{n} landmarks -> {len(red.templates)} templates (framed); [word]: the group element "
        "mapping the landmark onto its template",
        fontsize=8,
    )
    return finish_figure(fig, out / "fig1_landmarks.png")


def save_policies(caps: Capabilities, out: Path) -> Path:
    """Fig. 1(f): each template's local world with its policies, one path per passable
    direction, in the template's frame."""
    max_range = float(caps.params.get("max_range", caps.nodes.max()))
    red, pol = caps.reduction, caps.policies
    templates = caps.landmarks.points[red.templates][:, : caps.n_rays]  # the reading block
    n = len(templates)
    cols = min(8, n)
    rows = math.ceil(n / cols)
    fig = new_figure(1.9 * cols, 2.0 * rows + 0.4)
    colours = _direction_colours(len(pol.names))
    for t in range(n):
        ax = fig.add_subplot(rows, cols, t + 1)
        world = local_world(templates[t], max_range)
        b = np.vstack([world.boundary, world.boundary[:1]])
        ax.fill(b[:, 0], b[:, 1], color="#f2f2f2")
        ax.plot(b[:, 0], b[:, 1], color="#444444", lw=0.8)
        for d in range(len(pol.names)):
            path = pol.path(t, d)
            if len(path):
                ax.plot(path[:, 0], path[:, 1], color=colours[d], lw=1.1)
                ax.annotate(
                    "",
                    xy=tuple(path[-1]),
                    xytext=tuple(path[-2]),
                    arrowprops={"arrowstyle": "->", "color": colours[d], "lw": 1.1},
                )
        ax.plot([0], [0], "ko", ms=3)
        ax.set_xlim(-max_range, max_range)
        ax.set_ylim(-max_range, max_range)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        names = [pol.names[d] for d in range(len(pol.names)) if pol.passable[t, d]]
        listed = " ".join(names) if len(names) <= 5 else f"{len(names)} of {len(pol.names)}"
        ax.set_title(f"T{t}: {listed or 'none'}", fontsize=6)
    fig.suptitle(f"{pol.n_policies} local policies ({pol.learner}) on {n} templates", fontsize=8)
    return finish_figure(fig, out / "fig1_policies.png")


def _exponents(labels: Iterable[tuple[int, ...]], orders: tuple[int, int]) -> str:
    """The exponents (a, b) of the permutations o^a p^b using a transition, summarised:
    "a=0,1,2" when every b goes with those a, "b=0" when every a goes with that b."""
    na, nb = orders
    labels = [(int(a), int(b)) for a, b in labels]
    by_a: dict[int, set[int]] = {}
    for a, b in labels:
        by_a.setdefault(a, set()).add(b)
    if all(len(bs) == nb for bs in by_a.values()):
        return "a=" + ",".join(str(a) for a in sorted(by_a))
    by_b: dict[int, set[int]] = {}
    for a, b in labels:
        by_b.setdefault(b, set()).add(a)
    if all(len(az) == na for az in by_b.values()):
        return "b=" + ",".join(str(b) for b in sorted(by_b))
    return " ".join(f"{a}{b}" for a, b in sorted(labels))


def save_automaton(out: Path) -> Path:
    """Fig. 2: the automaton built from the toy operators, each transition labelled with
    the exponents (a, b) of the permutations o^a p^b that use it."""
    from matplotlib.patches import Circle, FancyArrowPatch

    fa = PermutationAutomaton.from_operators(fig2_operators())
    orders = (
        1 + max(a for labels in fa.transitions.values() for a, _ in labels),
        1 + max(b for labels in fa.transitions.values() for _, b in labels),
    )
    fig = new_figure(6.0, 4.8)
    ax = fig.add_subplot()
    # the wheel 1-4 around 5 (o rotates the ring; every ring element feeds 5), then 6, 7
    r = 1.7
    ring = {
        i: (r * math.cos(math.radians(135 - 90 * i)), r * math.sin(math.radians(135 - 90 * i)))
        for i in range(4)
    }
    pos = {**ring, 4: (0.0, 0.0), 5: (3.3, 1.1), 6: (3.3, -1.1)}
    circles = {}
    for i, (x, y) in pos.items():
        circles[i] = ax.add_patch(Circle((x, y), 0.26, fc="white", ec="black", lw=1.0, zorder=3))
        ax.text(x, y, str(i + 1), ha="center", va="center", zorder=4, fontsize=11)
    for (u, v), labels in sorted(fa.transitions.items()):
        (x0, y0), (x1, y1) = pos[u], pos[v]
        rad = 0.3 if (v, u) in fa.transitions else 0.0
        ax.add_patch(
            FancyArrowPatch(
                (x0, y0), (x1, y1), patchA=circles[u], patchB=circles[v], shrinkA=1,
                shrinkB=1, arrowstyle="-|>", mutation_scale=11,
                connectionstyle=f"arc3,rad={rad}", color="#444444", lw=0.9, zorder=2,
            )
        )  # fmt: skip
        # on the curve's midpoint: a quadratic arc's peak is half its control offset
        dx, dy = x1 - x0, y1 - y0
        mx, my = (x0 + x1) / 2 + 0.5 * rad * dy, (y0 + y1) / 2 - 0.5 * rad * dx
        ax.text(
            mx, my, _exponents(labels, orders), fontsize=7.5, color="#1f4e99", ha="center",
            va="center", zorder=5,
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.9},
        )  # fmt: skip
    ax.set_xlim(-2.3, 4.0)
    ax.set_ylim(-2.2, 2.2)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(
        "Fig. 2: automaton of o (rotate elements 1-4) and p (swap 6-7)\n"
        "label: exponents of the permutations o^a p^b using the transition\n"
        "(a=0,1: those a, with any b; b=0: that b, with any a)",
        fontsize=8,
    )
    return finish_figure(fig, out / "fig2_automaton.png")


def save_capability_figures(caps: Capabilities, directory: str | os.PathLike[str]) -> list[Path]:
    """Write the paper's Fig. 1 panels and Fig. 2 into ``directory``."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    return [
        save_context_map(caps, out),
        save_skeleton_curve(caps, out),
        save_landmarks(caps, out),
        save_policies(caps, out),
        save_automaton(out),
    ]

"""The paper's Fig. 1 (the representation-building process) and Fig. 2 (the permutation
automaton), drawn from a capabilities file."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from copi.experiments.figures import _figure
from copi.geometry import ring_angles
from copi.learning import Capabilities, Operator, PermutationAutomaton, local_world

__all__ = ["fig2_operators", "save_capability_figures"]

_COLOURS = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
]  # fmt: skip


def _colour(i: int) -> str:
    return _COLOURS[i % len(_COLOURS)]


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
    fig = _figure(7.0, 6.0)
    ax = fig.add_subplot()
    from matplotlib.collections import LineCollection

    segs = xy[caps.edges]
    ax.add_collection(LineCollection(segs, colors="#bbbbbb", linewidths=0.3, zorder=1))
    colours = [_colour(int(t)) for t in caps.node_template]
    ax.scatter(xy[:, 0], xy[:, 1], s=6, c=colours, zorder=2)
    for j, (x, y) in enumerate(lm_xy):
        t = int(caps.reduction.template_of[j])
        ax.scatter([x], [y], s=90, c=_colour(t), edgecolors="black", linewidths=0.8, zorder=3)
        ax.annotate(str(j), (x, y), fontsize=6, ha="center", va="center", zorder=4)
    ax.set_title(
        f"context map: {len(nodes)} nodes, {len(caps.edges)} edges -> "
        f"{caps.landmarks.n_landmarks} landmarks (colour: template)",
        fontsize=9,
    )
    ax.set_xlabel("first principal axis of the readings")
    ax.set_ylabel("second principal axis")
    fig.tight_layout()
    target = out / "fig1_context_map.png"
    fig.savefig(target)
    return target


def save_skeleton_curve(caps: Capabilities, out: Path) -> Path:
    """Fig. 1(d) aside: H(k) against the number of contractions, the chosen k marked."""
    lm = caps.landmarks
    fig = _figure(7.0, 4.5)
    ax = fig.add_subplot()
    k = np.arange(len(lm.curve))
    ax.plot(k, lm.curve, color="#1f77b4", lw=1.2, label="H(k), Hausdorff distance to the map")
    ax.axvline(lm.k, color="#d62728", lw=1, ls="--")
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
    twin.plot(k, lm.criterion, color="#7f7f7f", lw=0.6, alpha=0.6)
    twin.set_ylabel("criterion maximised", color="#7f7f7f")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    target = out / "fig1_skeleton_curve.png"
    fig.savefig(target)
    return target


def _polar(ax, ranges: np.ndarray, max_range: float, colour: str) -> None:  # type: ignore[no-untyped-def]
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
    pts = caps.landmarks.points
    n = len(pts)
    cols = min(10, n)
    rows = math.ceil(n / cols)
    fig = _figure(1.5 * cols, 1.6 * rows + 0.4)
    red = caps.reduction
    templates = set(red.templates.tolist())
    for j in range(n):
        ax = fig.add_subplot(rows, cols, j + 1)
        t = int(red.template_of[j])
        _polar(ax, pts[j], max_range, _colour(t))
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
    fig.tight_layout()
    target = out / "fig1_landmarks.png"
    fig.savefig(target)
    return target


def save_policies(caps: Capabilities, out: Path) -> Path:
    """Fig. 1(f): each template's local world with its policies, one path per passable
    direction, in the template's frame."""
    max_range = float(caps.params.get("max_range", caps.nodes.max()))
    red, pol = caps.reduction, caps.policies
    templates = caps.landmarks.points[red.templates]
    n = len(templates)
    cols = min(8, n)
    rows = math.ceil(n / cols)
    fig = _figure(1.9 * cols, 2.0 * rows + 0.4)
    for t in range(n):
        ax = fig.add_subplot(rows, cols, t + 1)
        world = local_world(templates[t], max_range)
        b = np.vstack([world.boundary, world.boundary[:1]])
        ax.fill(b[:, 0], b[:, 1], color="#f2f2f2")
        ax.plot(b[:, 0], b[:, 1], color="#444444", lw=0.8)
        for d in range(len(pol.names)):
            path = pol.path(t, d)
            if len(path):
                ax.plot(path[:, 0], path[:, 1], color=_colour(d), lw=1.1)
                ax.annotate(
                    "",
                    xy=tuple(path[-1]),
                    xytext=tuple(path[-2]),
                    arrowprops={"arrowstyle": "->", "color": _colour(d), "lw": 1.1},
                )
        ax.plot([0], [0], "ko", ms=3)
        ax.set_xlim(-max_range, max_range)
        ax.set_ylim(-max_range, max_range)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        names = [pol.names[d] for d in range(len(pol.names)) if pol.passable[t, d]]
        ax.set_title(f"T{t}: {' '.join(names) or 'none'}", fontsize=6)
    fig.suptitle(f"{pol.n_policies} local policies ({pol.learner}) on {n} templates", fontsize=8)
    fig.tight_layout()
    target = out / "fig1_policies.png"
    fig.savefig(target)
    return target


def save_automaton(out: Path) -> Path:
    """Fig. 2: the automaton built from the toy operators, transitions labelled with
    the exponents (a, b) of the permutations o^a p^b that use them."""
    from matplotlib.patches import Circle

    fa = PermutationAutomaton.from_operators(fig2_operators())
    fig = _figure(6.5, 5.0)
    ax = fig.add_subplot()
    ring = {
        i: (math.cos(math.pi / 2 - math.pi * i / 2), math.sin(math.pi / 2 - math.pi * i / 2))
        for i in range(4)
    }
    pos = {**ring, 4: (2.4, 0.0), 5: (3.6, 0.8), 6: (3.6, -0.8)}
    for i, (x, y) in pos.items():
        ax.add_patch(Circle((x, y), 0.22, fc="white", ec="black", zorder=3))
        ax.text(x, y, str(i + 1), ha="center", va="center", zorder=4, fontsize=10)
    for (u, v), labels in sorted(fa.transitions.items()):
        (x0, y0), (x1, y1) = pos[u], pos[v]
        rad = 0.25 if (v, u) in fa.transitions else 0.0
        ax.annotate(
            "",
            xy=(x1, y1),
            xytext=(x0, y0),
            arrowprops={
                "arrowstyle": "-|>",
                "shrinkA": 12,
                "shrinkB": 12,
                "connectionstyle": f"arc3,rad={rad}",
                "color": "#444444",
                "lw": 0.8,
            },
            zorder=2,
        )
        text = ",".join(f"{a}{b}" for a, b in sorted(labels))
        mx, my = (x0 + x1) / 2, (y0 + y1) / 2
        ax.text(mx + 0.12 * (y1 - y0), my - 0.12 * (x1 - x0), text, fontsize=5.5, color="#1f4e99")
    ax.set_xlim(-1.5, 4.3)
    ax.set_ylim(-1.6, 1.6)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(
        "Fig. 2: automaton of o (rotate elements 1-4) and p (swap 6-7);\n"
        "labels ab: the transition belongs to o^a p^b",
        fontsize=8,
    )
    fig.tight_layout()
    target = out / "fig2_automaton.png"
    fig.savefig(target)
    return target


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

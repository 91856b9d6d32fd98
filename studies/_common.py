"""What the studies share."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

__all__ = ["FRESH_SEED", "drawn_episodes", "finish_cost_figure", "kept_times",
           "predictive_capabilities", "splice_section", "timed_acts", "won_by_arm",
           "write_page"]

FRESH_SEED = 2
"""Episodes of a seed no method was tuned on and no benchmark table reports (the
predictive studies' yardstick)."""


def kept_times(path: Path, measured: dict[str, tuple[float, Any]]) -> dict[str, Any]:
    """The wall times of the runs that did the work, in the JSON file ``path``:
    ``measured`` maps a part to (seconds it just took, what to keep); a part is kept
    anew when it is missing or took more than 30 s (a rerun that only resumes keeps the
    first run's times)."""
    times = json.loads(path.read_text()) if path.is_file() else {}
    for key, (took, value) in measured.items():
        if key not in times or took > 30:
            times[key] = value
    path.write_text(json.dumps(times))
    return times


def splice_section(page: Path, heading: str, lines: list[str], *, after: str = "",
                   before: str = "") -> None:  # fmt: skip
    """``lines`` (a section starting with ``heading``) into ``page`` in place of its last
    version; where there is none, before the line starting with ``before``, or before the
    next section after the one whose heading starts with ``after``."""
    text = page.read_text().split("\n")

    def next_section(i: int) -> int:
        return next(k for k in range(i + 1, len(text)) if text[k].startswith("## "))

    if heading in text:
        start = text.index(heading)
        end = next_section(start)
    elif before:
        start = end = next(i for i, ln in enumerate(text) if ln.startswith(before))
    else:
        start = end = next_section(next(i for i, ln in enumerate(text) if ln.startswith(after)))
    page.write_text("\n".join([*text[:start], *lines, *text[end:]]))


def finish_cost_figure(fig: Any, ax: Any, out: Path, *, xlabel: str, title: str) -> None:
    """A learning-cost figure's axes (samples on a log scale against validation success),
    its legend beside them, written to ``out``."""
    import matplotlib.pyplot as plt

    ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("success on validation episodes (%)")
    ax.set_title(title)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120, bbox_inches="tight")
    plt.close(fig)


def interval(d: Any) -> str:
    """A paired difference (:func:`copi.results.paired_difference`) in points with its
    95 % interval, as the studies' tables print it: ``+1.5 [-1.2, +4.2]``."""
    return f"{100 * d.estimate:+.1f} [{100 * d.low:+.1f}, {100 * d.high:+.1f}]"


def predictive_capabilities(path: str | Path) -> Path:
    """The predictive preset's capabilities at ``path``, learnt there first when absent
    (``copi learn --preset predictive``)."""
    from copi.learning import learn
    from copi.methods import PRESETS

    out = Path(path)
    if not out.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        learn(PRESETS["predictive"].learn).save(out)
    return out


def drawn_episodes(family: str, n: int, seed: int) -> list[Any]:
    """Episodes 0 .. n - 1 of ``family`` at ``seed``, those of a world with no valid task
    left out (the family's others count)."""
    from copi.errors import InvalidWorldError
    from copi.runs import Episode

    out = []
    for k in range(n):
        try:
            out.append(Episode.draw(family, k, seed))
        except InvalidWorldError:
            continue
    return out


def timed_acts(agent: Any) -> list[float]:
    """The seconds of each call of ``agent.act`` from now on, appended as it is called
    (``act`` wrapped in a timer, in this process)."""
    import time

    plain = agent.act
    took: list[float] = []

    def act(obs: Any) -> Any:
        t0 = time.perf_counter()
        move = plain(obs)
        took.append(time.perf_counter() - t0)
        return move

    agent.act = act
    return took


def won_by_arm(arm: Any, arms: int, draws: int, *args: Any) -> list[Any]:
    """Each arm's success per episode, the share of ``draws`` seeds of its futures it
    won: ``arm(k, *args, draw)`` (a list of booleans, one per episode) for every arm k
    < ``arms`` and draw, on two processes."""
    from concurrent.futures import ProcessPoolExecutor

    import numpy as np

    with ProcessPoolExecutor(2) as pool:
        runs = [[pool.submit(arm, k, *args, d) for d in range(draws)] for k in range(arms)]
        return [np.mean([r.result() for r in rs], axis=0) for rs in runs]


def write_page(path: str | Path, lines: list[str]) -> None:
    """Write a study's page (its lines, and a last empty one) and show it."""
    Path(path).write_text("\n".join([*lines, ""]))
    print("\n".join(lines))
    print(f"wrote {path}")

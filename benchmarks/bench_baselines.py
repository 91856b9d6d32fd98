"""Decision cost of every method, as a ratio to copi's decision in the same run.

Each method drives the same 20 episodes of the ``polygon`` family (seed 3, not a
reported seed) at its first benchmark level; a method's cost is the median over episodes
of its mean wall time per decision (global direction included, the scan excluded). The
"×" column is the method's cost over copi-extended's. No goal: the table says what each
method costs next to copi.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from benchmarks._timing import Timing, fmt, show
from copi.experiments import ensure_capabilities
from copi.learning import Capabilities
from copi.methods import make_agent, method_names, method_spec
from copi.runs import Episode


def main() -> bool:
    names = [n for n in method_names() if method_spec(n).available()
             and not method_spec(n).ablation and n != "copi-learnt-continual"]  # fmt: skip
    # every preset a timed method needs (learnt once, at the preset's own scale)
    presets = {p for n in names if (p := method_spec(n).capabilities) is not None}
    caps_paths = ensure_capabilities(Path(tempfile.mkdtemp()), presets)
    caps = {k: Capabilities.load(v) for k, v in caps_paths.items()}
    episodes = [Episode.draw("polygon", k, 3) for k in range(20)]
    rows = []
    for name in names:
        spec = method_spec(name)
        level = spec.levels[-1]
        costs = []
        for episode in episodes:
            agent = make_agent(name, caps.get(spec.capabilities or ""))
            costs.append(episode.run(agent, sensing=level).decision_us)
        rows.append(Timing(f"{name} ({level})", float(np.median(costs)) * 1e-6))
    ref = next(r for r in rows if r.name == "copi-extended (map)")
    show("decision cost per method (polygon, 20 episodes)",
         ["method (level)", "per decision", "× copi-extended's cost"],
         [[r.name, fmt(r.per_item), f"{r.per_item / ref.per_item:,.1f}"] for r in rows])
    return True


if __name__ == "__main__":
    main()

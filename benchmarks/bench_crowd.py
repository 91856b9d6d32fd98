"""Speed of many agents among each other (``copi crowd``), beside navground's ORCA.

N agents in a square room at 0.1 agents per square agent step (the default of ``copi
crowd``), each with copi's 32-ray scan against the walls and every other agent and
copi-learnt's decision, timed through :func:`copi.experiments.crowd.run_crowd` (what
``copi crowd`` runs for one run) in a steady crowd (a new goal on arrival, contacts only
counted, so that all N agents stay in every timed step). navground's ORCA moves the same
N agents from the same starts, driven by navground itself (``World.run``, its own
neighbour search within the same 10-step range, the same walls, new waypoints on
arrival), timed in the same run, alternating with copi's, so that both meet the same
load on a shared machine.

Goals (issue: many agents among each other):
- 1,000 agents: >= 200 world steps a second on 2 cores, and >= 2x navground's ORCA;
- 10,000 agents: >= 20 world steps a second;
- memory linear in N (the bytes per agent are printed for both sizes).

Alone: ``python benchmarks/bench_crowd.py --agents N [--json]`` times one size and prints
world steps a second for each (JSON: ``copi_steps_per_s``, ``navground_steps_per_s``,
``agents``, and more).
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import hashlib
import json
import math
import os
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._timing import Timing, note, report, show  # noqa: E402
from copi.experiments.crowd import CrowdConfig, draw_crowd, run_crowd  # noqa: E402
from copi.learning import learn  # noqa: E402
from copi.methods import PRESETS  # noqa: E402

DENSITY = 0.1
"""Agents per square agent step (``copi crowd``'s default)."""
GOALS = {1000: 1 / 200, 10_000: 1 / 20}
"""Most seconds a world step may take, by N."""
RATIO = 2.0
"""copi's world steps a second over navground's ORCA's, at least (1,000 agents)."""


def capabilities(path: str | None) -> str:
    """The learnt preset's capabilities (``copi learn``'s default), learnt once and kept in
    the temporary directory by copi's version and parameters (about a minute)."""
    if path is not None:
        return path
    from copi import __version__

    params = PRESETS["learnt"].learn
    key = hashlib.sha256(json.dumps(dataclasses.asdict(params), sort_keys=True,
                                    default=str).encode()).hexdigest()[:12]  # fmt: skip
    target = Path(tempfile.gettempdir()) / f"copi-bench-learnt-{__version__}-{key}.npz"
    if not target.exists():
        print(f"learning the learnt preset's capabilities into {target} (about a minute)")
        learn(params).save(target)
    return str(target)


def copi_rate(config: CrowdConfig, processes: int) -> float:
    """World steps a second of one steady run (its set-up aside)."""
    return run_crowd(config, "copi-learnt", DENSITY, 0, processes=processes).steps_per_s


def navground_world(config: CrowdConfig) -> Any:
    """navground's world of the same crowd: ORCA agents (copi's registered margin and
    horizon), speed 1, a 10-step neighbourhood, the room's walls, waypoints looping
    between each agent's goal and start (a new goal on each arrival)."""
    from navground import core, sim

    crowd = draw_crowd(config, DENSITY, 0)
    world = sim.World()
    for i in range(crowd.n_agents):
        b = core.behaviors.ORCABehavior()
        b.optimal_speed = 1.0
        b.horizon = 5.0
        b.safety_margin = 0.3
        task = sim.tasks.WaypointsTask(waypoints=[crowd.goals[i], crowd.starts[i]], loop=True,
                                       tolerance=crowd.goal_tolerance)  # fmt: skip
        agent = sim.Agent(
            radius=crowd.radius, behavior=b,
            kinematics=core.kinematics.OmnidirectionalKinematics(max_speed=1.0), task=task,
            state_estimations=[sim.state_estimations.BoundedStateEstimation(
                range=crowd.sensor.max_range)],
        )  # fmt: skip
        agent.position = crowd.starts[i]
        world.add_agent(agent)
    for s in crowd.world.segments:
        world.add_wall(sim.Wall(np.array(s[:2]), np.array(s[2:])))
    return world


def navground_rate(config: CrowdConfig, steps: int) -> float:
    world = navground_world(config)
    world.run(steps=2, time_step=1.0)  # its set-up (spatial index, first neighbours)
    t0 = time.perf_counter()
    world.run(steps=steps, time_step=1.0)
    return steps / (time.perf_counter() - t0)


def env_rate(agents: int, steps: int = 10) -> float:
    """World steps a second of the PettingZoo environment (``CrowdEnv.step``, every agent
    heading straight for its goal; the scan is the crowd's, the actions a learner's)."""
    from copi.envs import CrowdEnv

    env = CrowdEnv(agents=agents, density=DENSITY, max_steps=10**6)
    env.reset(seed=0)
    crowd = env.crowd
    assert crowd is not None
    names = env.possible_agents
    t0 = time.perf_counter()
    for _ in range(steps):
        v = crowd.goals - crowd.positions
        v /= np.maximum(1.0, np.hypot(v[:, 0], v[:, 1]))[:, None]
        live = set(env.agents)
        env.step({a: v[i] for i, a in enumerate(names) if a in live})
    return steps / (time.perf_counter() - t0)


@njit(cache=False)
def _work(n: int) -> float:
    acc = 0.0
    for k in range(n):
        acc += math.sin(k * 1e-3)
    return acc


def _spin(n: int) -> float:
    """A second or so of pure arithmetic (numba, no memory traffic)."""
    return float(_work(n))


def core_scaling(processes: int, n: int = 30_000_000) -> float:
    """How much more arithmetic ``processes`` processes do in the same time than one
    (``processes`` on ideal cores; less where the cores share a physical one, or the
    machine is shared): the ceiling of any speed-up copi's processes can give here."""
    import multiprocessing

    _spin(1000)  # compiled in this process, before the fork: the workers inherit it
    t0 = time.perf_counter()
    _spin(n)
    one = time.perf_counter() - t0
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(processes) as pool:
        t0 = time.perf_counter()
        pool.map(_spin, [n] * processes)
        many = time.perf_counter() - t0
    return processes * one / many


def bytes_per_agent(config: CrowdConfig) -> float:
    """Peak memory (numpy and Python allocations, tracemalloc) of drawing a crowd and
    running 3 steps in this process, over N."""
    gc.collect()
    tracemalloc.start()
    try:
        run_crowd(dataclasses.replace(config, steps=3), "copi-learnt", DENSITY, 0)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return peak / config.agents


def measure(
    agents: int, caps: str, *, repeat: int = 3, processes: int | None = None
) -> dict[str, Any]:
    """copi's and navground's world steps a second at N = ``agents``, alternating, medians
    of ``repeat``; copi on one process per core and on one."""
    cores = processes or os.cpu_count() or 1
    steps = 30 if agents <= 2000 else 10
    config = CrowdConfig(agents=agents, densities=(DENSITY,), steps=steps, steady=True,
                         capabilities={"learnt": caps}).resolved()  # fmt: skip
    run_crowd(dataclasses.replace(config, steps=2), "copi-learnt", DENSITY, 0)  # warm up
    many, one, ng = [], [], []
    for _ in range(repeat):
        many.append(copi_rate(config, cores))
        ng.append(navground_rate(config, max(3, steps // 3)))
        if cores > 1:
            one.append(copi_rate(config, 1))
    med = float(np.median(many))
    out = {
        "agents": agents, "density": DENSITY, "processes": cores,
        "copi_steps_per_s": med,
        "copi_one_process_steps_per_s": float(np.median(one)) if one else med,
        "navground_steps_per_s": float(np.median(ng)),
        "bytes_per_agent": bytes_per_agent(config),
        "env_steps_per_s": env_rate(agents),
        "core_scaling": core_scaling(cores) if cores > 1 else 1.0,
    }  # fmt: skip
    out["ratio"] = out["copi_steps_per_s"] / out["navground_steps_per_s"]
    return out


def main(sizes: tuple[int, ...] = (1000, 10_000), caps: str | None = None) -> bool:
    path = capabilities(caps)
    found = [measure(n, path) for n in sizes]
    rows, goals = [], {}
    for r in found:
        n = r["agents"]
        name = f"copi crowd, {n:,} agents, {r['processes']} processes"
        rows.append(Timing(name, 1 / r["copi_steps_per_s"]))
        rows.append(Timing(f"copi crowd, {n:,} agents, 1 process",
                           1 / r["copi_one_process_steps_per_s"]))  # fmt: skip
        rows.append(Timing(f"navground ORCA, {n:,} agents", 1 / r["navground_steps_per_s"]))
        rows.append(Timing(f"CrowdEnv.step (PettingZoo), {n:,} agents",
                           1 / r["env_steps_per_s"]))  # fmt: skip
        if n in GOALS:
            goals[name] = GOALS[n]
    ok = report("crowd: seconds per world step (copi-learnt, 32 rays each)", rows, None, goals)
    cells = []
    for r in found:
        verdict = ""
        if r["agents"] == 1000:
            met = r["ratio"] >= RATIO
            ok &= met
            verdict = f"{'met' if met else 'MISSED'} (≥ {RATIO:g}x)"
        cells.append([f"{r['agents']:,}", f"{r['copi_steps_per_s']:,.1f}",
                      f"{r['navground_steps_per_s']:,.1f}", f"{r['ratio']:.1f}", verdict,
                      f"{r['bytes_per_agent']:,.0f}"])  # fmt: skip
    show("crowd: world steps a second, copi against navground's ORCA (same run)",
         ["agents", "copi", "navground ORCA", "× navground", "goal", "bytes per agent"], cells)
    scale = found[0]["core_scaling"]
    note(f"Density {DENSITY:g} agents per square agent step, steady crowds; medians of 3 "
         "alternating runs; memory is the peak tracemalloc sees over drawing a crowd and "
         "running 3 steps, per agent. This machine's cores: "
         f"{found[0]['processes']} processes do {scale:.2f}x the arithmetic of one in the "
         "same time (pure compute, no memory traffic): the ceiling of any speed-up from "
         "processes here.")  # fmt: skip
    return ok


def _cli() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--agents", type=int, default=None,
                        help="one crowd size (default: 1,000 and 10,000)")
    parser.add_argument("--json", action="store_true", help="print the numbers as JSON")
    parser.add_argument("--processes", type=int, default=None,
                        help="copi's processes (default: the cores)")
    parser.add_argument("--capabilities", default=None,
                        help="the learnt preset's capabilities (default: learnt once, kept)")
    args = parser.parse_args()
    if args.agents is None and not args.json:
        return 0 if main(caps=args.capabilities) else 1
    if args.agents is not None and not 1 <= args.agents <= 100_000:
        parser.error(f"--agents must be in 1 .. 100,000; got {args.agents}")
    sizes = (args.agents,) if args.agents is not None else (1000, 10_000)
    path = capabilities(args.capabilities)
    found = [measure(n, path, processes=args.processes) for n in sizes]
    if args.json:
        print(json.dumps(found[0] if len(found) == 1 else found, indent=2))
    else:
        for r in found:
            print(f"{r['agents']:,} agents: copi {r['copi_steps_per_s']:,.1f} world steps/s "
                  f"({r['processes']} processes; {r['copi_one_process_steps_per_s']:,.1f} on one), "
                  f"navground ORCA {r['navground_steps_per_s']:,.1f} ({r['ratio']:.1f}x); "
                  f"{r['bytes_per_agent']:,.0f} bytes per agent; the PettingZoo env "
                  f"{r['env_steps_per_s']:,.1f}; {r['processes']} processes do "
                  f"{r['core_scaling']:.2f}x one's arithmetic here")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(_cli())

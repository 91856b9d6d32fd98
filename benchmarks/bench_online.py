"""Speed of online policy instantiation and of Experiment 1.

Goals (issue: online policy instantiation and Experiment 1):
- one decision (scan excluded) <= 10 µs for one agent, <= 3 µs per agent batched;
- the learnt preset's decision as a user calls it (``make_agent("copi-learnt",
  caps).act(obs)``: its global direction, recognition and choice; the scan aside) <= 10
  µs for one agent at each level, its batched path with its defaults <= 3 µs per agent;
- copi-predictive's decision (planning over its learnt futures) <= 1 ms;
- 2 workers >= 1.8x one worker on the same episodes (the full `copi reproduce` at
  paper scale, <= 120 s on 2 cores, is timed by `make run`).
"""

from __future__ import annotations

import tempfile
import time
import timeit
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._timing import Timing, median_time, note, report
from copi.core import Agent, Observation, Task
from copi.experiments import NavigationConfig, evaluate
from copi.learning import LearnParams, explore, learn
from copi.methods import make_agent
from copi.online import ContextController
from copi.runs import draw_episode, run_episode


def _observations(level: str, family: str = "indoor") -> tuple[Any, list[Observation]]:
    """The task and every observation of an episode as the runner hands them to a method
    at ``level`` (compass-guard walking it), to replay to the method timed."""
    seen: list[Observation] = []

    class Recording(Agent):
        steers_itself = True

        def reset(self, task: Task) -> None:
            self.inner = make_agent("compass-guard")
            self.inner.reset(task)
            self.task = task

        def act(self, obs: Observation) -> np.ndarray:
            seen.append(obs)
            return self.inner.act(obs)

    rec = Recording()
    for k in range(20):
        seen.clear()
        run_episode(rec, draw_episode(family, k, 7), sensing=level, max_steps=200)  # type: ignore[arg-type]
        if len(seen) >= 40:
            break
    return rec.task, list(seen)


def _act_time(agent: Agent, task: Any, observations: list[Observation], *,
              repeat: int = 7) -> float:  # fmt: skip
    """Median over ``repeat`` replays of one method's ``act`` per observation, as a user
    calls it (its global direction, the recognition and the choice; the scan aside)."""
    times = []
    for _ in range(repeat + 1):  # the first replay compiles and warms
        agent.reset(task)
        t0 = time.perf_counter()
        for obs in observations:
            agent.act(obs)
        times.append((time.perf_counter() - t0) / len(observations))
    return float(np.median(times[1:]))


def main() -> bool:
    tmp = Path(tempfile.mkdtemp())
    caps = learn(LearnParams(directions=16))
    caps_path = caps.save(tmp / "caps.npz")
    readings = explore(4, 500, seed=9).readings
    rng = np.random.default_rng(0)
    want = rng.normal(size=(len(readings), 2))
    plain = ContextController(caps)
    guarded = ContextController(caps, guard=1.2)
    plain.decide(readings[0], want[0])
    guarded.decide(readings[0], want[0])
    batch = readings[:1000]
    plain.decide_batch(batch, want[:1000])

    def single(ctl: ContextController) -> float:
        i = iter(range(10**9))
        return (
            min(
                timeit.repeat(
                    lambda: ctl.decide(readings[(k := next(i) % 2000)], want[k]),
                    number=20000,
                    repeat=5,
                )
            )
            / 20000
        )

    rows = [
        Timing("decide, one agent", single(plain)),
        Timing("decide, one agent, guard 1.2", single(guarded)),
        Timing(
            "decide_batch, 1000 agents",
            min(timeit.repeat(lambda: plain.decide_batch(batch, want[:1000]), number=20, repeat=5))
            / 20,
            per=1000,
        ),
    ]
    learnt = learn(LearnParams(directions=16, safety=True))
    agent = make_agent("copi-learnt", learnt)  # the registered preset, its defaults
    recorded = {level: _observations(level) for level in ("sensor", "map")}
    for level, (task, observations) in recorded.items():
        rows.append(Timing(f"copi-learnt: make_agent(...).act, level {level}",
                           _act_time(agent, task, observations)))  # fmt: skip
    # contexts that see motion (copi-learnt-motion, an ablation: no goal of its own)
    moving = make_agent("copi-learnt-motion", learn(LearnParams(directions=16, safety=True,
                                                                motion=True)))  # fmt: skip
    task, observations = recorded["map"]
    rows.append(Timing("copi-learnt-motion: act, level map", _act_time(moving, task, observations)))
    prev_batch = readings[999:1999]
    static_batch = np.asarray([o.static for o in observations[:1]] * 1000)
    agent.decide_batch(batch, prev_batch, want[:1000], 5.0, static_batch)
    rows.append(
        Timing(
            "copi-learnt: decide_batch, 1000 agents (defaults)",
            median_time(
                lambda: agent.decide_batch(batch, prev_batch, want[:1000], 5.0, static_batch),
                number=20,
            ),
            per=1000,
        )
    )
    # the registered preset's choice uses no context (beta 0): the same actions without
    # recognising any, when asked
    rows.append(
        Timing(
            "copi-learnt: decide_batch, 1000 agents, recognise=False",
            median_time(
                lambda: agent.decide_batch(batch, prev_batch, want[:1000], 5.0, static_batch,
                                           recognise=False),  # fmt: skip
                number=20,
            ),
            per=1000,
        )
    )
    predictive = make_agent("copi-predictive", learn(LearnParams(
        directions=16, safety=True, safety_static=True, predict=True)))  # fmt: skip
    crowd_task, crowd_obs = _observations("map", family="crowd")
    rows.append(Timing("copi-predictive: act, level map (crowd)",
                       _act_time(predictive, crowd_task, crowd_obs, repeat=3)))  # fmt: skip
    # many agents at once: each plans in its own thread (the kernels release the GIL)
    many = [make_agent("copi-predictive", predictive.capabilities) for _ in range(8)]
    for workers in (1, 2):
        runs = []
        for _ in range(4):  # the first run warms; each starts from reset, which is not timed
            for a in many:
                a.reset(crowd_task)
            t0 = time.perf_counter()
            for obs in crowd_obs[:10]:
                type(predictive).act_many(many, [obs] * len(many), workers=workers)
            runs.append(time.perf_counter() - t0)
        rows.append(Timing(f"copi-predictive: act_many, 8 agents, {workers} worker(s)",
                           float(np.median(runs[1:])), per=80))  # fmt: skip
    ok = report(
        "online decision (scan excluded)",
        rows,
        None,
        {rows[0].name: 10e-6, rows[1].name: 10e-6, rows[2].name: 3e-6, rows[3].name: 10e-6,
         rows[4].name: 10e-6, rows[6].name: 3e-6, rows[7].name: 3e-6,
         rows[8].name: 1e-3},
    )
    cfg = NavigationConfig(str(caps_path), worlds=400, method="copi-extended", guard=1.2)
    walls = {}
    for workers in (1, 2):
        t0 = time.perf_counter()
        evaluate(cfg, tmp / f"w{workers}.sqlite", workers=workers)
        walls[workers] = time.perf_counter() - t0
    speedup = walls[1] / walls[2]
    note(
        f"Experiment 1, 400 episodes: 1 worker {walls[1]:.1f} s, 2 workers {walls[2]:.1f} s, "
        f"speed-up {speedup:.2f}x (goal >= 1.8x)"
    )
    return ok and speedup >= 1.8


if __name__ == "__main__":
    raise SystemExit(0 if main() else 1)

"""How a registered method drives every agent of a crowd (:class:`copi.world.crowd.Crowd`),
and how the agents are shared out among processes, one per core.

Two drivers answer one call, ``decide(crowd, out)``, for the agents of one slice:

- :class:`BatchDriver`: copi's learnt agent (:class:`copi.online.LearntAgent`) deciding
  for all of them in one compiled call (:meth:`~copi.online.LearntAgent.decide_rows`, on
  the crowd's own arrays; :meth:`~copi.online.LearntAgent.decide_batch` when the choice
  uses the context);
- :class:`AgentsDriver`: any registered method, one :class:`~copi.core.Agent` per crowd
  agent, each asked through its own ``act`` (slower, the same contract as an episode).

Both see the same thing, at the level asked: the ranges and the goal (``sensor``), plus
the position, the world and the walls' reading (``map``), plus the other agents within
sensor range with their last step's velocity (``oracle``). The global direction is the
straight line to the goal, which is the route in the crowd's convex room.

A :class:`Team` shares each step's sensing and deciding among processes, this one and
forked workers, all on the crowd's arrays in shared memory: the batched driver's agents
in chunks each process takes as it comes free, another driver's in one slice a process
(each with its own agents); this process then moves every agent. Every agent's reading
and decision depend on the crowd's state only, never on the process that made them, so
the trajectories are the same for any number of processes (tested).
"""

from __future__ import annotations

import math
import mmap
import multiprocessing
import signal
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.core import Agent, Observation, Task
from copi.errors import CopiError, MethodError
from copi.learning import Capabilities
from copi.methods import make_agent, method_spec
from copi.online import LearntAgent
from copi.runs import checked_act
from copi.world.crowd import Crowd

__all__ = ["AgentsDriver", "BatchDriver", "Driver", "Team", "batched", "chunks", "make_driver",
           "slices"]

_MIN_SLICE = 250
"""Fewest agents worth a process of their own (below, the round trip to a worker each
step costs more than the work it takes over)."""


class Driver:
    """Decides the moves of the crowd's agents ``lo .. hi - 1`` (those still in the
    world); keeps its decision time."""

    def __init__(self, lo: int, hi: int) -> None:
        self.lo = lo
        self.hi = hi
        self.seconds = 0.0
        """Wall time of the decisions so far."""
        self.decisions = 0
        """Decisions so far (one per agent in the world per step)."""

    shared = False
    """Its state lives in arrays that :meth:`share` can put in shared memory, so that any
    process may decide for any of its agents (else each process decides for its own)."""

    def share(self, keep: list[mmap.mmap]) -> None:
        """Move the per-agent state to shared memory (see :attr:`shared`)."""
        raise NotImplementedError

    def decide(self, crowd: Crowd, out: NDArray[np.float64], lo: int | None = None,
               hi: int | None = None) -> None:  # fmt: skip
        """Fill ``out[i]`` (the velocity of agent i) for every agent still in the world of
        the slice, or of ``lo .. hi - 1`` within it."""
        lo = self.lo if lo is None else lo
        rows = lo + np.flatnonzero(crowd.active[lo : self.hi if hi is None else hi])
        if len(rows) == 0:
            return
        t0 = time.perf_counter()
        out[rows] = self._decide(crowd, rows)
        self.seconds += time.perf_counter() - t0
        self.decisions += len(rows)

    def _decide(self, crowd: Crowd, rows: NDArray[np.intp]) -> NDArray[np.float64]:
        raise NotImplementedError


def _aim(crowd: Crowd, rows: NDArray[np.intp]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The straight line to each goal (the route in a convex room) and its length."""
    want = crowd.goals[rows] - crowd.positions[rows]
    return want, np.hypot(want[:, 0], want[:, 1])


class BatchDriver(Driver):
    """copi's learnt agent deciding for every agent of the slice in one call: the decision
    :meth:`LearntAgent.act` makes for each (its reading, its previous one, the straight
    line to its goal), without the context search when the choice does not use it
    (``beta`` 0, as copi-learnt is registered: :meth:`LearntAgent.decide_rows`, in place
    on the crowd's arrays; measured, the dozen array operations a batch it spares cost
    about a tenth of the decision time at 250 agents a batch)."""

    def __init__(self, agent: LearntAgent, crowd: Crowd, lo: int, hi: int) -> None:
        super().__init__(lo, hi)
        self.agent = agent
        self.prev = np.empty((hi - lo, crowd.ranges.shape[1]))
        self.goal = np.full((hi - lo, 2), np.nan)
        """The goal each agent's previous reading was taken for: a new goal is a new task,
        whose first decision has no previous reading (as after :meth:`LearntAgent.reset`)."""

    shared = True

    def share(self, keep: list[mmap.mmap]) -> None:
        self.prev = _shared(self.prev, keep)
        self.goal = _shared(self.goal, keep)

    def decide(self, crowd: Crowd, out: NDArray[np.float64], lo: int | None = None,
               hi: int | None = None) -> None:  # fmt: skip
        if self.agent.beta > 0.0:  # the context is recognised: decide_batch
            super().decide(crowd, out, lo, hi)
            return
        lo = self.lo if lo is None else lo
        hi = self.hi if hi is None else hi
        t0 = time.perf_counter()
        self.agent.decide_rows(crowd.ranges, crowd.positions, crowd.goals, crowd.active, lo,
                               hi, self.prev, self.goal, self.lo, out)  # fmt: skip
        self.seconds += time.perf_counter() - t0
        self.decisions += int(np.count_nonzero(crowd.active[lo:hi]))

    def _decide(self, crowd: Crowd, rows: NDArray[np.intp]) -> NDArray[np.float64]:
        k = rows - self.lo
        s = crowd.ranges[rows]
        fresh = (self.goal[k] != crowd.goals[rows]).any(axis=1)
        self.prev[k[fresh]] = s[fresh]
        want, reach = _aim(crowd, rows)
        acts, _ = self.agent.decide_batch(s, self.prev[k], want, reach,
                                          recognise=self.agent.beta > 0.0)  # fmt: skip
        self.prev[k] = s
        self.goal[k] = crowd.goals[rows]
        return acts


class AgentsDriver(Driver):
    """One agent of ``method`` per crowd agent of the slice, each asked through ``act``
    at level ``sensing``; a new goal (a steady crowd) is a new task (``finish`` then
    ``reset``)."""

    def __init__(self, make: Callable[[], Agent], crowd: Crowd, sensing: str, lo: int,
                 hi: int) -> None:  # fmt: skip
        super().__init__(lo, hi)
        self.sensing = sensing
        self.rank = ("sensor", "map", "oracle").index(sensing)
        self.agents = [make() for _ in range(lo, hi)]
        self.goal = np.full((hi - lo, 2), np.nan)
        self.crowd = crowd

    def _task(self, crowd: Crowd, i: int) -> Task:
        knows = self.rank >= 1
        return Task(
            sensing=self.sensing,  # type: ignore[arg-type]  # checked by the runner
            agent_radius=crowd.radius, goal_tolerance=crowd.goal_tolerance,
            n_rays=crowd.sensor.n_rays, max_range=crowd.sensor.max_range,
            world=crowd.world if knows else None,
            start=crowd.positions[i].copy() if knows else None,
            goal=crowd.goals[i].copy() if knows else None, strategy="greedy",
        )  # fmt: skip

    def _decide(self, crowd: Crowd, rows: NDArray[np.intp]) -> NDArray[np.float64]:
        want, reach = _aim(crowd, rows)
        static = crowd.static_ranges(rows) if self.rank >= 1 else None
        out = np.empty((len(rows), 2))
        for n, i in enumerate(rows.tolist()):
            k = i - self.lo
            agent = self.agents[k]
            if (self.goal[k] != crowd.goals[i]).any():
                if not np.isnan(self.goal[k, 0]):
                    agent.finish("success")
                try:
                    agent.reset(self._task(crowd, i))
                except CopiError:
                    raise
                except Exception as exc:
                    raise MethodError(f"method {agent.name!r}: reset raised "
                                      f"{type(exc).__name__}: {exc}") from None  # fmt: skip
                self.goal[k] = crowd.goals[i]
            d = want[n] / reach[n] if reach[n] > 0 else np.zeros(2)
            obs = Observation(
                ranges=crowd.ranges[i].copy(), goal=want[n].copy(),
                position=crowd.positions[i].copy() if self.rank >= 1 else None,
                static=None if static is None else static[n],
                obstacles=self._others(crowd, i) if self.rank >= 2 else None,
                direction=None if agent.steers_itself else d, reach=float(reach[n]),
            )  # fmt: skip
            out[n] = checked_act(agent, obs, crowd.t + 1)
        return out

    @staticmethod
    def _others(crowd: Crowd, i: int) -> NDArray[np.float64]:
        """The agents within sensor range as rows (x, y, vx, vy, radius)."""
        near = crowd.neighbours(i)
        return np.column_stack([crowd.positions[near], crowd.velocities[near],
                                np.full(len(near), crowd.radius)])  # fmt: skip


def batched(agent: Agent) -> bool:
    """Whether ``agent``'s decisions for a crowd can be made in one batch: copi's learnt
    agent without what a batch cannot carry (persistence, contexts grown online)."""
    return (type(agent) is LearntAgent and agent.persist == 0.0 and not agent.continual
            and not agent.wait)  # fmt: skip


def make_driver(
    method: str,
    caps: Capabilities | None,
    params: dict[str, Any],
    crowd: Crowd,
    sensing: str,
    lo: int,
    hi: int,
) -> Driver:
    """The driver of ``method`` (with ``params`` over its registered ones) for agents
    ``lo .. hi - 1``: batched where it can be (:func:`batched`, at level ``sensor``), else
    one agent each."""
    probe = make_agent(method, caps, **params)
    if batched(probe) and sensing == "sensor":
        assert isinstance(probe, LearntAgent)
        return BatchDriver(probe, crowd, lo, hi)
    del probe
    spec = method_spec(method)
    return AgentsDriver(lambda: spec.make(caps, **params), crowd, sensing, lo, hi)


# -- one process per core -------------------------------------------------------------


def _shared(a: NDArray[Any], keep: list[mmap.mmap]) -> NDArray[Any]:
    """A copy of ``a`` in anonymous shared memory (inherited by forked workers)."""
    buf = mmap.mmap(-1, max(a.nbytes, 1))
    keep.append(buf)
    out: NDArray[Any] = np.frombuffer(buf, dtype=a.dtype, count=a.size).reshape(a.shape)
    out[...] = a
    return out


def slices(n: int, processes: int) -> list[tuple[int, int]]:
    """Agents 0 .. n - 1 cut into ``processes`` contiguous slices (fewer when a slice
    would hold under 250 agents)."""
    p = max(1, min(int(processes), n // _MIN_SLICE))
    cuts = [round(n * k / p) for k in range(p + 1)]
    return list(zip(cuts[:-1], cuts[1:], strict=True))


def chunks(n: int, processes: int) -> list[tuple[int, int]]:
    """Agents 0 .. n - 1 cut into pieces of work for ``processes`` processes sharing
    them out as they go: four a process, of 250 agents at least (measured: batches of
    250 decide 6 % slower than one of 1,000, of 125 10 %)."""
    k = max(1, min(4 * int(processes), n // 250))
    cuts = [round(n * j / k) for j in range(k + 1)]
    return list(zip(cuts[:-1], cuts[1:], strict=True))


class Team:
    """Sense and decide for a crowd with ``processes`` processes (see the module); use as
    a context manager, which stops the workers.

    ``make(lo, hi)`` builds the driver of agents ``lo .. hi - 1``. A driver whose state
    can be shared (``shared``: the batched one) is built once, here, and the agents are
    cut in :func:`chunks` that every process takes in turn as it comes free, so that a
    process the machine leaves waiting holds up no more than the chunk in its hands.
    Otherwise each worker builds the driver of its own :func:`slices` after the fork (each
    process then holds the per-agent state of its slice only).
    """

    def __init__(self, crowd: Crowd, make: Callable[[int, int], Driver], processes: int = 1,
                 *, shared: bool = False):  # fmt: skip
        self.crowd = crowd
        n = crowd.n_agents
        cuts = slices(n, processes)
        if len(cuts) > 1 and "fork" not in multiprocessing.get_all_start_methods():
            cuts = slices(n, 1)  # pragma: no cover - no fork: one process
        self._keep: list[mmap.mmap] = []
        self.actions = np.zeros((n, 2))
        self.workers: list[tuple[Any, Any]] = []
        self.processes = len(cuts)
        self.chunks: list[tuple[int, int]] = []
        if len(cuts) == 1:
            self.driver = make(0, n)
            return
        for name in ("positions", "goals", "active", "ranges", "velocities"):
            setattr(crowd, name, _shared(getattr(crowd, name), self._keep))
        self.actions = _shared(self.actions, self._keep)
        ctx = multiprocessing.get_context("fork")
        if shared:
            self.driver = make(0, n)
            self.driver.share(self._keep)
            self.chunks = chunks(n, len(cuts))
            self.lock = ctx.Lock()
            # the step being decided, the next chunk to take, the chunks done
            self.ctl = _shared(np.array([-1, 0, 0], dtype=np.int64), self._keep)
            for k in range(1, len(cuts)):
                self._fork(ctx, f"copi-crowd-{k}", _serve_chunks, (self,))
        else:
            for lo, hi in cuts[1:]:
                self._fork(ctx, f"copi-crowd-{lo}", _serve, (crowd, make, lo, hi, self.actions))
            self.driver = make(*cuts[0])

    def _fork(
        self, ctx: Any, name: str, target: Callable[..., None], args: tuple[Any, ...]
    ) -> None:
        here, there = ctx.Pipe()
        proc = ctx.Process(target=target, args=(there, *args), daemon=True, name=name)
        proc.start()
        there.close()
        self.workers.append((proc, here))

    def decide(self) -> NDArray[np.float64]:
        """Every agent's reading (into ``crowd.ranges``) and move (returned, (N, 2)) at the
        crowd's present positions."""
        crowd = self.crowd
        if self.chunks:
            self.start()
        else:
            for _, conn in self.workers:
                conn.send(crowd.t)
        crowd.index()
        if self.chunks:
            self.take_chunks(crowd.t)
            self._wait_chunks()
            return self.actions
        crowd.scan(self.driver.lo, self.driver.hi)
        self.driver.decide(crowd, self.actions)
        for proc, conn in self.workers:
            try:
                answer = conn.recv()
            except (EOFError, OSError):
                raise _died(proc) from None
            _raise_reported(answer)
        return self.actions

    _started = -1
    """The last step whose chunks were handed out."""

    def start(self) -> None:
        """Hand out the chunks of the crowd's present step (:attr:`Crowd.t`) to the other
        processes, once (:meth:`decide` then joins them): called as soon as the step's
        positions, goals and agents in the world are settled (:attr:`moved`), the other
        processes sense and decide while this one still keeps the last step's books."""
        t = self.crowd.t
        if not self.chunks or self._started == t:
            return
        self._started = t
        with self.lock:
            self.ctl[:] = (t, 0, 0)
        for _, conn in self.workers:
            conn.send(t)

    @property
    def moved(self) -> Callable[[], None] | None:
        """What to hand :meth:`Crowd.step` as ``moved``: :meth:`start` where the agents are
        shared out in chunks (the batched driver, which reads the positions, the goals and
        the readings only); else None (a driver of its own slice may read the velocities,
        which the step's books settle last)."""
        return self.start if self.chunks else None

    def take_chunks(self, t: int, *, index: bool = False, notify: Any = None) -> None:
        """Take the chunks of step t still free, one at a time, and scan and decide for
        them (first indexing the crowd, with ``index``: the positions cannot move while a
        chunk of the step is out); a worker finishing the step's last chunk says so on
        its pipe ``notify``, which wakes this process at once."""
        crowd = self.crowd
        n = len(self.chunks)
        while True:
            with self.lock:
                if self.ctl[0] != t or self.ctl[1] >= n:
                    return
                c = int(self.ctl[1])
                self.ctl[1] += 1
            if index:
                crowd.t = t
                crowd.index()
                index = False
            lo, hi = self.chunks[c]
            crowd.scan(lo, hi)
            self.driver.decide(crowd, self.actions, lo, hi)
            with self.lock:
                self.ctl[2] += 1
                last = self.ctl[2] == n
            if last and notify is not None:
                notify.send(("done", t))

    def _wait_chunks(self) -> None:
        """Until every chunk of the step is done (a worker's error or death is raised)."""
        from multiprocessing.connection import wait

        while self.ctl[2] < len(self.chunks):
            ready = wait([conn for _, conn in self.workers], timeout=0.01)
            for proc, conn in self.workers:
                if conn in ready:  # the last chunk done, an error, or the pipe of one that died
                    try:
                        answer = conn.recv()
                    except (EOFError, OSError):
                        raise _died(proc) from None
                    _raise_reported(answer)

    @property
    def seconds(self) -> float:
        """Decision time of this process's slice (each worker's is summed at :meth:`close`)."""
        return self.driver.seconds + self._worker_seconds

    @property
    def decisions(self) -> int:
        return self.driver.decisions + self._worker_decisions

    _worker_seconds = 0.0
    _worker_decisions = 0

    def close(self) -> None:
        """Stop the workers (collecting their decision times)."""
        for proc, conn in self.workers:
            try:
                conn.send(None)
                while True:  # answers to earlier steps may come first
                    answer = conn.recv()
                    if isinstance(answer, tuple) and len(answer) == 2 and answer[0] == "time":
                        self._worker_seconds += answer[1][0]
                        self._worker_decisions += answer[1][1]
                        break
            except (EOFError, OSError):
                pass
            conn.close()
            proc.join(5.0)
            if proc.is_alive():
                proc.kill()
                proc.join(1.0)
        self.workers = []

    def __enter__(self) -> Team:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _died(proc: Any) -> CopiError:
    return CopiError(f"a crowd worker process ({proc.name}) died: killed, or out of memory")


def _raise_reported(answer: Any) -> None:
    """Raise the error a worker reported, if ``answer`` is one."""
    if isinstance(answer, tuple) and len(answer) == 2 and answer[0] in ("method", "copi"):
        raise (MethodError if answer[0] == "method" else CopiError)(answer[1])


def _report(conn: Any, exc: BaseException) -> None:
    kind = "method" if isinstance(exc, MethodError) else "copi"
    text = str(exc) if isinstance(exc, CopiError) else f"{type(exc).__name__}: {exc}"
    conn.send((kind, text or type(exc).__name__))


def _work_loop(conn: Any, step: Callable[[int], None], driver: Callable[[], Driver | None]) -> None:
    """A worker's life: ``step(t)`` for each step t the parent sends; None ends it,
    answering the decision time of ``driver()``; an error is sent as one line and ends
    it. Ctrl-C is the parent's; a parent gone closes the pipe, which ends the worker."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    while True:
        try:
            t = conn.recv()
        except (EOFError, OSError):
            return
        if t is None:
            d = driver()
            conn.send(("time", (0.0, 0) if d is None else (d.seconds, d.decisions)))
            return
        try:
            step(t)
        except BaseException as exc:
            _report(conn, exc)
            return


def _serve_chunks(conn: Any, team: Team) -> None:
    """A worker of a shared driver: each step, chunks until none is left (a step already
    over has none)."""
    _work_loop(conn, lambda t: team.take_chunks(t, index=True, notify=conn),
               lambda: team.driver)  # fmt: skip


def _serve(conn: Any, crowd: Crowd, make: Callable[[int, int], Driver], lo: int, hi: int,
           actions: NDArray[np.float64]) -> None:  # fmt: skip
    """A worker of its own slice: each step, scan and decide for agents lo .. hi - 1 into
    the shared arrays, and answer."""
    box: dict[str, Any] = {}
    try:
        box["driver"] = make(lo, hi)
    except BaseException as exc:  # reported at the first step
        box["failed"] = exc

    def step(t: int) -> None:
        if "driver" not in box:
            raise box["failed"]
        crowd.t = t
        crowd.index()
        crowd.scan(lo, hi)
        box["driver"].decide(crowd, actions)
        conn.send(t)

    _work_loop(conn, step, lambda: box.get("driver"))


def decision_us(team: Team) -> float:
    """Mean wall time of one agent's decision, microseconds (NaN before any)."""
    return 1e6 * team.seconds / team.decisions if team.decisions else math.nan

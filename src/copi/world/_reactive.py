"""Crowds that react: moving discs walking toward goals of their own, each step chosen by
one of navground's behaviours (ORCA, HL, HRVO, social force), no home-made crowd model.

navground is the optional extra ``peers``; a world whose discs follow a crowd behaviour
needs it (one clear error otherwise), every other world does not.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.world._world import ObstacleSpec, World

__all__ = ["ReactiveCrowd", "navground_available"]

_NAMES = {"orca": "ORCA", "hl": "HL", "hrvo": "HRVO", "social-force": "SocialForce"}
_AGENT_ID = 1_000_000  # the copi agent's id among the crowd's (when the crowd sees it)


def navground_available() -> bool:
    """Whether navground (the extra ``peers``) can be imported."""
    try:
        import navground.sim  # noqa: F401
    except ImportError:
        return False
    return True


class ReactiveCrowd:
    """The moving discs of one episode as a navground world: each disc an agent with the
    behaviour of ``spec`` (its preferred speed ``spec.speed``, its time horizon, safety
    margin, neighbours and how far it sees them), its radius, a goal, and the world's
    walls. One :meth:`step` is one time step of copi's (navground's time unit is copi's
    step, its lengths agent steps). A disc within its radius of its goal is given a new
    one (drawn by the episode's generator, in the free space) when ``spec.new_goals``;
    else it stays there.

    With ``spec.sees_agent`` the copi agent is in the crowd's world as a disc with no
    behaviour, put where the agent is (and moving as it moves) before each step, so that
    the discs give way to it; otherwise it is invisible to them (CrowdNav's setting) and
    their future does not depend on anything the agent does.

    Examples
    --------
    >>> room = World([[0, 0], [20, 0], [20, 20], [0, 20]])
    >>> spec = ObstacleSpec(behaviour="orca", speed=1.0, radius=0.5,
    ...                     positions=[[5, 10]], goals=[[15, 10]], new_goals=False)
    >>> crowd = ReactiveCrowd(room, spec, np.array([[5.0, 10.0]]), np.array([0.5]),
    ...                       np.array([[15.0, 10.0]]), 0.3)
    >>> for _ in range(12):
    ...     c = crowd.step(np.array([1.0, 1.0]), np.zeros(2), np.random.default_rng(0))
    >>> round(float(np.hypot(*(c[0] - [15, 10]))), 1) <= 0.5  # at its goal, and there it stays
    True
    """

    def __init__(
        self,
        world: World,
        spec: ObstacleSpec,
        centers: NDArray[np.float64],
        radii: NDArray[np.float64],
        goals: NDArray[np.float64],
        agent_radius: float,
        *,
        velocities: NDArray[np.float64] | None = None,
    ) -> None:
        if not navground_available():
            raise InvalidArgumentError(
                f"moving obstacles of behaviour {spec.behaviour!r} need navground (the extra "
                "peers): pip install 'copi[peers]' (make install does)"
            )
        self.world = world
        self.spec = spec
        self.agent_radius = float(agent_radius)
        self.goals = np.array(goals, dtype=np.float64).reshape(-1, 2)
        self._build(np.asarray(centers, dtype=np.float64), np.asarray(radii, dtype=np.float64),
                    velocities)  # fmt: skip

    def _build(self, centers: NDArray[np.float64], radii: NDArray[np.float64],
               velocities: NDArray[np.float64] | None) -> None:  # fmt: skip
        from navground import core, sim

        spec = self.spec
        w = sim.World()
        # the walls as navground sees them: the world's segments
        for px, py, qx, qy in self.world.segments:
            w.add_wall(core.LineSegment(np.array([px, py]), np.array([qx, qy])))
        self.agents = []
        for k, (c, r) in enumerate(zip(centers, radii, strict=True)):
            b: Any = core.Behavior.make_type(_NAMES[spec.behaviour])
            b.optimal_speed = spec.speed
            b.safety_margin = spec.safety_margin
            if hasattr(b, "time_horizon"):
                b.time_horizon = spec.time_horizon
            if spec.behaviour in ("orca", "hrvo"):
                b.set("max_neighbors", int(spec.neighbours))
            if spec.behaviour == "orca":  # its neighbour distance is twice its horizon
                b.horizon = spec.sight / 2
            a = sim.Agent(
                radius=float(r), behavior=b,
                kinematics=core.kinematics.OmnidirectionalKinematics(max_speed=spec.speed),
                task=self._task(self.goals[k], float(r)),
                state_estimations=[sim.state_estimations.BoundedStateEstimation(
                    range=spec.sight)],
                id=k,
            )  # fmt: skip
            a.position = np.asarray(c, dtype=np.float64)
            if velocities is not None:
                a.velocity = np.asarray(velocities[k], dtype=np.float64)
            w.add_agent(a)
            self.agents.append(a)
        # navground stops agents that touch; copi's discs pass through each other as the
        # random walk's do, and a contact with the copi agent is the agent's, reported
        w.ignore_collisions = True
        self.radii = np.asarray(radii, dtype=np.float64).copy()
        self.ghost = None
        if spec.sees_agent:
            g = sim.Agent(radius=self.agent_radius, behavior=None,
                          kinematics=core.kinematics.OmnidirectionalKinematics(max_speed=1.0),
                          id=_AGENT_ID)  # fmt: skip
            g.ignore_collisions = True
            w.add_agent(g)
            self.ghost = g
        self.nav = w

    @staticmethod
    def _task(goal: NDArray[np.float64], radius: float) -> Any:
        from navground import sim

        return sim.tasks.WaypointsTask(waypoints=[np.asarray(goal, dtype=np.float64)],
                                       loop=False, tolerance=radius)  # fmt: skip

    def centers(self) -> NDArray[np.float64]:
        """The discs' centres now (d, 2)."""
        return np.array([a.position for a in self.agents], dtype=np.float64).reshape(-1, 2)

    def velocities(self) -> NDArray[np.float64]:
        return np.array([a.velocity for a in self.agents], dtype=np.float64).reshape(-1, 2)

    def step(
        self, agent: NDArray[np.float64], velocity: NDArray[np.float64], rng: np.random.Generator
    ) -> NDArray[np.float64]:
        """One time step of the crowd, the copi agent at ``agent`` moving at ``velocity``
        (seen only by a crowd that sees it); new goals drawn from ``rng``. Returns the
        discs' new centres (d, 2)."""
        if self.ghost is not None:
            self.ghost.position = np.asarray(agent, dtype=np.float64)
            self.ghost.velocity = np.asarray(velocity, dtype=np.float64)
        self.nav.update(1.0)
        out = self.centers()
        if self.spec.new_goals:
            from copi.world._generate import sample_free

            there = np.hypot(*(out - self.goals).T) <= self.radii
            for k in np.flatnonzero(there):
                self.goals[k] = sample_free(self.world, rng, float(self.radii[k]))
                self.agents[k].task = self._task(self.goals[k], float(self.radii[k]))
        return out

    def __deepcopy__(self, memo: dict[int, Any]) -> ReactiveCrowd:
        """A crowd in the same state (positions, velocities, goals), stepped alike: the
        navground world is built anew from it (its C++ objects cannot be copied)."""
        twin = ReactiveCrowd.__new__(ReactiveCrowd)
        twin.world, twin.spec, twin.agent_radius = self.world, self.spec, self.agent_radius
        twin.goals = self.goals.copy()
        twin._build(self.centers(), self.radii, self.velocities())
        return twin

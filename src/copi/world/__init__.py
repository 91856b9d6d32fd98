"""The navigation domain of the paper's experiments (§IV).

A static :class:`World` (a polygon with holes), the paper's random worlds, moving disc
obstacles, a holonomic disc agent, the ring :class:`RangeSensor`, world files, and the
Gymnasium environment ``copi/Navigation-v0``. All randomness comes from a passed seed or
``numpy.random.Generator``.
"""

from __future__ import annotations

from copi.world._agents import RandomWalk
from copi.world._env import NavigationEnv
from copi.world._generate import WorldParams, place_obstacles, random_world, sample_start_goal
from copi.world._io import load_worlds, save_worlds
from copi.world._render import draw_simulator, draw_world, render_rgb
from copi.world._sensor import RangeSensor
from copi.world._simulator import Simulator, StepResult
from copi.world._world import ObstacleSpec, World

__all__ = [
    "NavigationEnv",
    "ObstacleSpec",
    "RandomWalk",
    "RangeSensor",
    "Simulator",
    "StepResult",
    "World",
    "WorldParams",
    "draw_simulator",
    "draw_world",
    "load_worlds",
    "place_obstacles",
    "random_world",
    "render_rgb",
    "sample_start_goal",
    "save_worlds",
]

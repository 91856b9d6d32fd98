"""The navigation domain of the paper's experiments (§IV).

A static :class:`World` (a polygon with holes), the paper's random worlds and the
benchmark's world families (:func:`sample_world`), moving disc
obstacles, a holonomic disc agent, the ring :class:`RangeSensor` and world files (the
Gymnasium environment over them is :mod:`copi.envs`'). All randomness comes from a
passed seed or ``numpy.random.Generator``.
"""

from __future__ import annotations

from copi._moved import moved_names
from copi.world._agents import RandomWalk, random_walk_episodes
from copi.world._families import (
    BENCHMARK_FAMILIES,
    CROWD_OBSTACLES,
    FAMILIES,
    EpisodeSettings,
    FamilySpec,
    check_family,
    family_inputs,
    family_names,
    family_replaced,
    family_spec,
    in_sight,
    register_family,
    sample_world,
    unregister_family,
)
from copi.world._family_crowdnav import CROWDNAV, STEPS_PER_METRE, CrowdNavSettings
from copi.world._family_indoor import IndoorParams, indoor_world
from copi.world._family_maps import (
    MOVINGAI_ENV,
    PACKAGED_MAPS,
    MapsParams,
    map_window_world,
    maps_identity,
    movingai_dir,
    scaled_map_world,
    shipped_map,
    shipped_maps,
)
from copi.world._family_polygon import PolygonParams, is_star_shaped, polygon_world
from copi.world._generate import (
    WorldParams,
    check_task,
    place_obstacles,
    random_world,
    sample_free,
    sample_start_goal,
)
from copi.world._io import MAX_WORLDS, load_worlds, save_worlds
from copi.world._reactive import ReactiveCrowd, navground_available
from copi.world._render import draw_simulator, draw_world, rasterize, render_rgb
from copi.world._sensor import RangeSensor
from copi.world._simulator import Simulator, StepResult
from copi.world._world import BEHAVIOURS, ObstacleSpec, World

__all__ = [
    "BEHAVIOURS",
    "BENCHMARK_FAMILIES",
    "CROWDNAV",
    "CROWD_OBSTACLES",
    "CrowdNavSettings",
    "EpisodeSettings",
    "FAMILIES",
    "FamilySpec",
    "IndoorParams",
    "MAX_WORLDS",
    "MOVINGAI_ENV",
    "MapsParams",
    "ObstacleSpec",
    "PACKAGED_MAPS",
    "PolygonParams",
    "RandomWalk",
    "RangeSensor",
    "ReactiveCrowd",
    "STEPS_PER_METRE",
    "Simulator",
    "StepResult",
    "World",
    "WorldParams",
    "check_family",
    "check_task",
    "draw_simulator",
    "draw_world",
    "family_inputs",
    "family_names",
    "family_replaced",
    "family_spec",
    "in_sight",
    "indoor_world",
    "is_star_shaped",
    "load_worlds",
    "map_window_world",
    "maps_identity",
    "movingai_dir",
    "navground_available",
    "place_obstacles",
    "polygon_world",
    "random_walk_episodes",
    "random_world",
    "rasterize",
    "register_family",
    "render_rgb",
    "sample_free",
    "sample_start_goal",
    "sample_world",
    "save_worlds",
    "scaled_map_world",
    "shipped_map",
    "shipped_maps",
    "unregister_family",
]

__getattr__ = moved_names(__name__, {"NavigationEnv": "copi.envs.navigation"})

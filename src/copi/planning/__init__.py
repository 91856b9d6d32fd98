"""Optimal reference paths on static snapshots, and grid search.

The paper judges its online agent against "an optimal A* shortest path, run on stationary
snapshots of the environment" (§IV). :func:`shortest_path` gives it in the continuous
plane for a disc agent (visibility graph of the configuration space); :func:`grid_astar`
searches occupancy grids with the Moving AI conventions, and :mod:`movingai` readers turn
their benchmark maps into worlds. :func:`family_stats` measures the world families
(:func:`copi.world.sample_world`) with these paths.
"""

from __future__ import annotations

from copi.planning._cspace import (
    MAX_PLANNED_VERTICES,
    check_plannable,
    check_size,
    configuration_space,
    length_error_bound,
    shortest_path,
)
from copi.planning._family_stats import FamilyStats, family_stats, mean_free_width
from copi.planning._field import GoalField
from copi.planning._grid import GridPlanner
from copi.planning._visibility import Plan, VisibilityGraph

__all__ = [
    "FamilyStats",
    "GoalField",
    "GridPlanner",
    "MAX_PLANNED_VERTICES",
    "Plan",
    "VisibilityGraph",
    "check_plannable",
    "check_size",
    "configuration_space",
    "family_stats",
    "length_error_bound",
    "mean_free_width",
    "shortest_path",
]

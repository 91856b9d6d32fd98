"""Running methods: one episode of any method at any sensing level, episodes drawn the
same for every method, a run's inputs checked and hashed, and the one loop that runs
independent seeded items into a results store, here, on a local pool or on Dask.

The episode API is what every experiment, study and training loop runs::

    ep = Episode.draw("indoor", 3, seed=0)          # the world, task and obstacles
    row = ep.row(make_agent("dwa"), sensing="map")  # on a fresh copy, within its limit

and :func:`run_episode` runs any agent on any simulator.
"""

from __future__ import annotations

from copi.runs._draw import (
    Episode,
    check_world_file,
    draw_episode,
    episode_world_name,
    load_capabilities,
    mapping_closes,
    result_row,
    skipped_row,
    step_limit,
    world_file_label,
)
from copi.runs._episode import (
    EnvEpisode,
    EpisodeOutcome,
    checked_act,
    make_task,
    obstacle_future,
    optimal_to_goal,
    run_episode,
    run_in_env,
    velocity_of,
)
from copi.runs._executor import ExecutorError, InlineExecutor, make_executor
from copi.runs._inputs import Inputs, check_family_inputs, code_version, resolve_inputs, run_id
from copi.runs._series import (
    MAX_EPISODES,
    MAX_LIFE_TASKS,
    MAX_LIVES,
    MAX_TASKS,
    Series,
    run_one,
    run_series,
)

__all__ = [
    "EnvEpisode",
    "Episode",
    "EpisodeOutcome",
    "ExecutorError",
    "InlineExecutor",
    "Inputs",
    "MAX_EPISODES",
    "MAX_LIFE_TASKS",
    "MAX_LIVES",
    "MAX_TASKS",
    "Series",
    "check_family_inputs",
    "check_world_file",
    "checked_act",
    "code_version",
    "draw_episode",
    "episode_world_name",
    "load_capabilities",
    "make_executor",
    "make_task",
    "mapping_closes",
    "obstacle_future",
    "optimal_to_goal",
    "resolve_inputs",
    "result_row",
    "run_episode",
    "run_id",
    "run_in_env",
    "run_one",
    "run_series",
    "skipped_row",
    "step_limit",
    "velocity_of",
    "world_file_label",
]

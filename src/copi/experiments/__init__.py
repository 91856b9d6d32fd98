"""The paper's experiments and the benchmark: their configurations and runners.

Experiment 1 (:mod:`~copi.experiments.navigation`, paper §IV Fig. 3-4), Experiment 2
(:mod:`~copi.experiments.pursuit`, the homicidal chauffeur, Fig. 5), Experiment 3
(:mod:`~copi.experiments.lifelong`, one world task after task), the benchmark (every
method on the same episodes of every family) and :func:`reproduce` (all of them end to
end). Each is a configuration (a frozen dataclass: everything that decides its results)
and a runner into a results store, built on :mod:`copi.runs`; their reports are
:mod:`copi.reports`'.

Names that lived here before the platform had rooms of its own (``make_agent``,
``run_episode``, ``ResultsStore``, ...) still work, with a ``DeprecationWarning`` saying
where they are now.
"""

from __future__ import annotations

from copi._moved import moved_names
from copi.experiments._reproduce import Reproduced, reproduce
from copi.experiments.benchmark import BenchmarkConfig, ensure_capabilities, run_benchmark
from copi.experiments.lifelong import LifelongConfig, draw_life, run_lifelong
from copi.experiments.navigation import (
    NavigationConfig,
    evaluate,
    evaluate_episode,
    evaluate_episodes,
)
from copi.experiments.pursuit import PursuitConfig, pursue, run_game, run_games

__all__ = [
    "BenchmarkConfig",
    "LifelongConfig",
    "NavigationConfig",
    "PursuitConfig",
    "Reproduced",
    "draw_life",
    "ensure_capabilities",
    "evaluate",
    "evaluate_episode",
    "evaluate_episodes",
    "pursue",
    "reproduce",
    "run_benchmark",
    "run_game",
    "run_games",
    "run_lifelong",
]

__getattr__ = moved_names(__name__, {
    "DEFAULT_PRESET": "copi.methods",
    "EnvEpisode": "copi.runs",
    "EpisodeOutcome": "copi.runs",
    "EpisodeResult": "copi.results:EpisodeRow",
    "EpisodeRow": "copi.results",
    "ExecutorError": "copi.runs",
    "GameRecord": "copi.results:GameRow",
    "GameRow": "copi.results",
    "InlineExecutor": "copi.runs",
    "LifeRow": "copi.results",
    "MethodRun": "copi.methods",
    "MethodSpec": "copi.methods",
    "PRESETS": "copi.methods",
    "Preset": "copi.methods",
    "ResultsError": "copi.results",
    "ResultsStore": "copi.results",
    "RunRow": "copi.results",
    "make_agent": "copi.methods",
    "make_executor": "copi.runs",
    "make_task": "copi.runs",
    "method_names": "copi.methods",
    "method_spec": "copi.methods",
    "optimal_to_goal": "copi.runs",
    "parse_methods": "copi.methods",
    "preset": "copi.methods",
    "random_walk_episodes": "copi.world",
    "register_method": "copi.methods",
    "run_episode": "copi.runs",
    "run_in_env": "copi.runs",
    "save_episode_gif": "copi.reports",
    "save_episode_png": "copi.reports",
    "save_overview_png": "copi.reports",
    "save_plan_png": "copi.reports",
    "summarize": "copi.reports",
    "summarize_games": "copi.reports",
    "unregister_method": "copi.methods",
    "write_report": "copi.reports",
})  # fmt: skip

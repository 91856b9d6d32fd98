"""Experiment runners, the method registry, figures and reports: the only part of copi
that writes files (besides saving capabilities).

The entry points a user needs to build on copi: :func:`register_method` (a method of
their own, then run by ``copi benchmark --methods NAME``), :func:`run_episode` (any agent
in any episode) and :func:`run_in_env` (an agent in the Gymnasium environment), the
experiments' configurations and runners, and :class:`ResultsStore`, whose rows read back
typed.
"""

from __future__ import annotations

from copi.experiments._episode import (
    EnvEpisode,
    EpisodeOutcome,
    make_task,
    optimal_to_goal,
    run_episode,
    run_in_env,
)
from copi.experiments._reproduce import reproduce
from copi.experiments.benchmark import BenchmarkConfig, run_benchmark
from copi.experiments.demo import random_walk_episodes
from copi.experiments.executor import ExecutorError, InlineExecutor, make_executor
from copi.experiments.figures import (
    save_episode_gif,
    save_episode_png,
    save_overview_png,
    save_plan_png,
)
from copi.experiments.lifelong import LifelongConfig, run_lifelong
from copi.experiments.methods import (
    MethodRun,
    MethodSpec,
    make_agent,
    method_names,
    method_spec,
    parse_methods,
    register_method,
    unregister_method,
)
from copi.experiments.navigation import (
    EpisodeResult,
    NavigationConfig,
    evaluate,
    evaluate_episode,
    evaluate_episodes,
)
from copi.experiments.presets import DEFAULT_PRESET, PRESETS, Preset, preset
from copi.experiments.pursuit import GameRow, PursuitConfig, pursue, run_game, run_games
from copi.experiments.report import summarize, summarize_games, write_report
from copi.experiments.rows import EpisodeRow, GameRecord, LifeRow, RunRow
from copi.experiments.store import ResultsError, ResultsStore

__all__ = [
    "BenchmarkConfig",
    "DEFAULT_PRESET",
    "EnvEpisode",
    "EpisodeOutcome",
    "EpisodeResult",
    "EpisodeRow",
    "ExecutorError",
    "GameRecord",
    "GameRow",
    "InlineExecutor",
    "LifeRow",
    "LifelongConfig",
    "MethodRun",
    "MethodSpec",
    "NavigationConfig",
    "PRESETS",
    "Preset",
    "PursuitConfig",
    "ResultsError",
    "ResultsStore",
    "RunRow",
    "evaluate",
    "evaluate_episode",
    "evaluate_episodes",
    "make_agent",
    "make_executor",
    "make_task",
    "method_names",
    "method_spec",
    "optimal_to_goal",
    "parse_methods",
    "preset",
    "pursue",
    "random_walk_episodes",
    "register_method",
    "reproduce",
    "run_benchmark",
    "run_episode",
    "run_game",
    "run_games",
    "run_in_env",
    "run_lifelong",
    "save_episode_gif",
    "save_episode_png",
    "save_overview_png",
    "save_plan_png",
    "summarize",
    "summarize_games",
    "unregister_method",
    "write_report",
]

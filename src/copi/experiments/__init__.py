"""Experiment runners, figures and reports: the only part of copi that writes files
(besides saving capabilities)."""

from __future__ import annotations

from copi.experiments.demo import random_walk_episodes
from copi.experiments.executor import ExecutorError, InlineExecutor, make_executor
from copi.experiments.figures import (
    save_episode_gif,
    save_episode_png,
    save_overview_png,
    save_plan_png,
)
from copi.experiments.navigation import (
    EpisodeResult,
    NavigationConfig,
    evaluate,
    run_episode,
    run_episodes,
)
from copi.experiments.pursuit import GameRow, PursuitConfig, pursue, run_game, run_games
from copi.experiments.report import summarize, summarize_games, write_report
from copi.experiments.store import ResultsError, ResultsStore

__all__ = [
    "EpisodeResult",
    "ExecutorError",
    "GameRow",
    "InlineExecutor",
    "NavigationConfig",
    "PursuitConfig",
    "ResultsError",
    "ResultsStore",
    "evaluate",
    "make_executor",
    "pursue",
    "random_walk_episodes",
    "run_episode",
    "run_episodes",
    "run_game",
    "run_games",
    "save_episode_gif",
    "save_episode_png",
    "save_overview_png",
    "save_plan_png",
    "summarize",
    "summarize_games",
    "write_report",
]

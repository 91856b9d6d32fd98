"""Experiment runners, figures and reports: the only part of copi that writes files
(besides saving capabilities)."""

from __future__ import annotations

from copi.experiments._episode import EpisodeOutcome, make_task, optimal_to_goal, run_episode
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
    evaluate_episode,
    evaluate_episodes,
)
from copi.experiments.pursuit import GameRow, PursuitConfig, pursue, run_game, run_games
from copi.experiments.report import summarize, summarize_games, write_report
from copi.experiments.store import ResultsError, ResultsStore

__all__ = [
    "EpisodeOutcome",
    "EpisodeResult",
    "ExecutorError",
    "GameRow",
    "InlineExecutor",
    "NavigationConfig",
    "PursuitConfig",
    "ResultsError",
    "ResultsStore",
    "evaluate",
    "evaluate_episode",
    "evaluate_episodes",
    "make_executor",
    "make_task",
    "optimal_to_goal",
    "pursue",
    "random_walk_episodes",
    "run_episode",
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

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
from copi.experiments.report import summarize, write_report
from copi.experiments.store import ResultsError, ResultsStore

__all__ = [
    "EpisodeResult",
    "ExecutorError",
    "InlineExecutor",
    "NavigationConfig",
    "ResultsError",
    "ResultsStore",
    "evaluate",
    "make_executor",
    "random_walk_episodes",
    "run_episode",
    "run_episodes",
    "save_episode_gif",
    "save_episode_png",
    "save_overview_png",
    "save_plan_png",
    "summarize",
    "write_report",
]

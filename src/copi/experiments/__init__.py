"""Experiment runners, figures and reports: the only part of copi that writes files
(besides saving capabilities)."""

from __future__ import annotations

from copi.experiments.demo import random_walk_episodes
from copi.experiments.figures import save_episode_gif, save_episode_png, save_overview_png

__all__ = [
    "random_walk_episodes",
    "save_episode_gif",
    "save_episode_png",
    "save_overview_png",
]

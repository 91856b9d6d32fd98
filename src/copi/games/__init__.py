"""The homicidal chauffeur (paper §IV, second experiment): a differential game played
through the learnt capabilities."""

from __future__ import annotations

from copi._moved import moved_names
from copi.games._chauffeur import (
    ChauffeurParams,
    Pursuer,
    critical_beta,
    evader_direction,
    isaacs_control,
)
from copi.games._play import GameResult, first_contact, play_open, pursuer_step
from copi.games._world_game import ChauffeurGame

__all__ = [
    "ChauffeurGame",
    "ChauffeurParams",
    "GameResult",
    "Pursuer",
    "critical_beta",
    "evader_direction",
    "first_contact",
    "isaacs_control",
    "play_open",
    "pursuer_step",
]

__getattr__ = moved_names(__name__, {
    "ChauffeurEnv": "copi.envs.chauffeur",
    "parallel_env": "copi.envs.chauffeur",
})  # fmt: skip

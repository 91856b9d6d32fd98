"""Gymnasium registration of copi's environments (done once, on ``import copi``).

Only names are registered here: an environment's module is imported when it is made
(``gymnasium.make``), so that ``import copi`` stays light."""

from __future__ import annotations

__all__ = ["ENV_IDS", "register_envs"]

ENV_IDS = ("copi/Navigation-v0", "copi/NavigationStatic-v0")


def register_envs() -> None:
    """Register copi's environment ids with Gymnasium (idempotent)."""
    import gymnasium

    if ENV_IDS[0] in gymnasium.registry:
        return
    # max_episode_steps: the environment's own default max_steps, so that the spec says it
    gymnasium.register(
        id=ENV_IDS[0], entry_point="copi.envs.navigation:NavigationEnv", max_episode_steps=500
    )
    gymnasium.register(
        id=ENV_IDS[1],
        entry_point="copi.envs.navigation:NavigationEnv",
        kwargs={"obstacles": 0},
        max_episode_steps=500,
    )

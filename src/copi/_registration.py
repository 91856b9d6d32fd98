"""Gymnasium registration of copi's environments (done once, on ``import copi``)."""

from __future__ import annotations

ENV_IDS = ("copi/Navigation-v0", "copi/NavigationStatic-v0")


def register_envs() -> None:
    """Register copi's environment ids with Gymnasium (idempotent)."""
    import gymnasium

    if ENV_IDS[0] in gymnasium.registry:
        return
    # max_episode_steps: the environment's own default max_steps, so that the spec says it
    gymnasium.register(
        id=ENV_IDS[0], entry_point="copi.world._env:NavigationEnv", max_episode_steps=500
    )
    gymnasium.register(
        id=ENV_IDS[1],
        entry_point="copi.world._env:NavigationEnv",
        kwargs={"obstacles": 0},
        max_episode_steps=500,
    )

"""Deep RL as copi's learning peer: PPO or SAC (Stable-Baselines3) trained for a local
policy in copi's own factorisation, exported to numpy weights that copi runs without torch
(:class:`copi.baselines.PPOAgent`); and CrowdNav's SARL, trained as CrowdNav trains it
(:func:`train_sarl`; run by :class:`copi.baselines.SARLAgent`). Training needs the
optional extra ``rl``; running a trained policy does not."""

from __future__ import annotations

from copi.envs.local_policy import TRAINING_SEED, LocalPolicyEnv, Reward
from copi.rl._imitate import check_demonstrator
from copi.rl._sarl import SARLConfig, train_sarl, write_sarl
from copi.rl._train import (
    VALIDATION_SEED,
    RLMissingError,
    TrainConfig,
    check_apart,
    rl_available,
    train,
    validation_success,
)

__all__ = [
    "LocalPolicyEnv",
    "RLMissingError",
    "Reward",
    "SARLConfig",
    "TRAINING_SEED",
    "TrainConfig",
    "VALIDATION_SEED",
    "check_apart",
    "check_demonstrator",
    "rl_available",
    "train",
    "train_sarl",
    "validation_success",
    "write_sarl",
]

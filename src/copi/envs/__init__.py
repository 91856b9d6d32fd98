"""copi's environments for other people's learners: the Gymnasium navigation
environment (``copi/Navigation-v0``, :mod:`copi.envs.navigation`), the environment a
local policy learns in (:mod:`copi.envs.local_policy`), the homicidal chauffeur
(:mod:`copi.envs.chauffeur`) and many agents among each other (:mod:`copi.envs.crowd`)
as PettingZoo ``ParallelEnv`` environments, and their registration.

The environments are reached through their modules (or as this package's attributes,
imported when first used), so that ``import copi``, which registers the ids, stays
light.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from copi.envs.registration import ENV_IDS, register_envs

if TYPE_CHECKING:
    from copi.envs.chauffeur import ChauffeurEnv, parallel_env
    from copi.envs.crowd import CrowdEnv
    from copi.envs.local_policy import LocalPolicyEnv, Reward
    from copi.envs.navigation import NavigationEnv

__all__ = [
    "ChauffeurEnv",
    "CrowdEnv",
    "ENV_IDS",
    "LocalPolicyEnv",
    "NavigationEnv",
    "Reward",
    "parallel_env",
    "register_envs",
]

_LAZY = {
    "ChauffeurEnv": "copi.envs.chauffeur",
    "parallel_env": "copi.envs.chauffeur",
    "CrowdEnv": "copi.envs.crowd",
    "LocalPolicyEnv": "copi.envs.local_policy",
    "Reward": "copi.envs.local_policy",
    "NavigationEnv": "copi.envs.navigation",
}


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_LAZY[name]), name)

"""Methods that are not copi's: what copi must beat, run on the same episodes.

Each is an :class:`copi.online.Agent` (``reset(task)``, ``act(obs)``) that declares the
least sensing level it needs (see :mod:`copi.online`):

==================  ========  ===========================================================
name                level     what it is
==================  ========  ===========================================================
``straight``        sensor    the global direction, no avoidance
``compass-guard``   sensor    copi's guard over the 16 compass moves, no capabilities
``vfh``             sensor    Vector Field Histogram (VFH+) on the ranges
``dwa``             sensor    Dynamic Window (velocity sampling) on the ranges
``tangent-bug``     sensor    TangentBug on the ranges
``ppo``             sensor    a local policy learnt by PPO, run in numpy (``ppo-guard``:
                              shielded by compass-guard's guard)
``tracked-mpc``     map       the model-oracle's planner on the discs it tracks in its
                              reading, their motion estimated from its own tracks
``replan``          oracle    shortest path on the current snapshot, re-planned
``navground-hrvo``  oracle    navground's HRVO (optional extra ``peers``)
``navground-hl``    oracle    navground's HL (optional extra ``peers``)
``navground-orca``  oracle    navground's ORCA (optional extra ``peers``)
==================  ========  ===========================================================

The local methods (level ``sensor``) follow the same global direction as copi's modes
(:class:`copi.online.Steering`): the static route at ``map``, the goal at ``sensor``.
"""

from __future__ import annotations

from copi.baselines._common import Steered
from copi.baselines._dwa import DWA
from copi.baselines._navground import (
    NAVGROUND_BEHAVIORS,
    NavgroundAgent,
    NavgroundMissingError,
    navground_available,
)
from copi.baselines._ppo import (
    MAX_FRAMES,
    MAX_LAYERS,
    MAX_WIDTH,
    OBSERVATION,
    OBSERVATION_V3,
    OBSERVATIONS,
    PolicyFormatError,
    PolicyWeights,
    PPOAgent,
    check_layout,
    compass_move,
    direction_frame,
    features,
    features_v3,
    load_policy,
    observation_size,
    packaged_policy,
    save_policy,
    to_world,
)
from copi.baselines._replan import Replan
from copi.baselines._sarl import HUMAN as SARL_HUMAN
from copi.baselines._sarl import MAX_HUMANS as SARL_MAX_HUMANS
from copi.baselines._sarl import NETS as SARL_NETS
from copi.baselines._sarl import SELF as SARL_SELF
from copi.baselines._sarl import SHIPPED as SARL_SHIPPED
from copi.baselines._sarl import WIDTHS as SARL_WIDTHS
from copi.baselines._sarl import (
    SARLAgent,
    SARLFormatError,
    SARLReward,
    SARLWeights,
    load_sarl,
    packaged_sarl,
    sarl_state,
    sarl_values,
    save_sarl,
)
from copi.baselines._simple import CompassGuard, Straight
from copi.baselines._tangent_bug import TangentBug
from copi.baselines._tracked import DiscTracker, TrackedMPC
from copi.baselines._vfh import VFH

__all__ = [
    "CompassGuard",
    "DWA",
    "DiscTracker",
    "MAX_FRAMES",
    "MAX_LAYERS",
    "MAX_WIDTH",
    "NAVGROUND_BEHAVIORS",
    "NavgroundAgent",
    "NavgroundMissingError",
    "OBSERVATION",
    "OBSERVATIONS",
    "OBSERVATION_V3",
    "PPOAgent",
    "PolicyFormatError",
    "PolicyWeights",
    "Replan",
    "SARLAgent",
    "SARLFormatError",
    "SARLReward",
    "SARLWeights",
    "SARL_HUMAN",
    "SARL_MAX_HUMANS",
    "SARL_NETS",
    "SARL_SELF",
    "SARL_SHIPPED",
    "SARL_WIDTHS",
    "Steered",
    "Straight",
    "TangentBug",
    "TrackedMPC",
    "VFH",
    "check_layout",
    "compass_move",
    "direction_frame",
    "features",
    "features_v3",
    "load_policy",
    "load_sarl",
    "navground_available",
    "observation_size",
    "packaged_policy",
    "packaged_sarl",
    "sarl_state",
    "sarl_values",
    "save_policy",
    "save_sarl",
    "to_world",
]

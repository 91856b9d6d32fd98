"""Offline, task-independent capability learning (paper §II, Fig. 1).

exploration -> :class:`GrowingNeuralGas` context map -> :func:`skeletonize` into
landmarks -> symmetry reduction (:class:`SymmetryGroup`, the paper's
:class:`PermutationAutomaton`) -> local policy templates -> :class:`Capabilities`.
:func:`learn` runs the whole chain.
"""

from __future__ import annotations

from copi.learning._capabilities import FORMAT_VERSION, Capabilities
from copi.learning._explore import Exploration, explore
from copi.learning._gng import GrowingNeuralGas
from copi.learning._motion import (
    MotionModel,
    learn_motion,
    motion_errors,
    motion_tables,
    sample_motion,
)
from copi.learning._pipeline import LearnParams, learn, simulated_steps
from copi.learning._policies import (
    ActionPriors,
    AStarLearner,
    PolicyLearner,
    PolicySet,
    ValueIterationLearner,
    compass,
    local_world,
)
from copi.learning._safety import (
    Probes,
    SafetyModel,
    design_matrix,
    fork_simulator,
    predict,
    probe_actions,
)
from copi.learning._skeleton import Landmarks, bootstrap_landmarks, skeletonize
from copi.learning._symmetry import (
    Operator,
    PermutationAutomaton,
    Reduction,
    SymmetryGroup,
    reduce_landmarks,
    ring_operators,
)
from copi.learning._tracking import WELL, MotionTracker, detect_discs, fit_circle

__all__ = [
    "AStarLearner",
    "ActionPriors",
    "Capabilities",
    "Exploration",
    "FORMAT_VERSION",
    "GrowingNeuralGas",
    "Landmarks",
    "LearnParams",
    "MotionModel",
    "MotionTracker",
    "Operator",
    "PermutationAutomaton",
    "PolicyLearner",
    "PolicySet",
    "Probes",
    "Reduction",
    "SafetyModel",
    "SymmetryGroup",
    "ValueIterationLearner",
    "WELL",
    "bootstrap_landmarks",
    "compass",
    "design_matrix",
    "detect_discs",
    "explore",
    "fit_circle",
    "fork_simulator",
    "learn",
    "learn_motion",
    "local_world",
    "motion_errors",
    "motion_tables",
    "predict",
    "probe_actions",
    "reduce_landmarks",
    "ring_operators",
    "sample_motion",
    "simulated_steps",
    "skeletonize",
]

"""What is possible in an episode, run beside the methods.

- :class:`Clairvoyant` (level ``future``): knows the obstacles' whole future and searches
  space and time for a contact-free path, replayed through the simulator: the share of
  episodes solvable at all. A bound, marked so in every table
  (:attr:`copi.methods.MethodSpec.bound`).
- :class:`ModelOracle` (level ``oracle`` plus the obstacles' motion model): plans
  against sampled futures of the obstacles' random walk, replanning every step: a
  reference planner that knows the present and how the world moves, but not its future.
  Not a bound: methods that know less match it in most families (docs/ceilings.md).
"""

from copi.bounds._clairvoyant import Clairvoyant
from copi.bounds._model_oracle import TURN_SD, ModelOracle
from copi.planning import GoalField
from copi.planning.futures import compass_moves

__all__ = [
    "Clairvoyant",
    "GoalField",
    "ModelOracle",
    "TURN_SD",
    "compass_moves",
]

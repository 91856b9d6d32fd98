"""Ceilings: bounds on what any method could do in an episode, run beside the methods.

- :class:`Clairvoyant` (level ``future``): knows the obstacles' whole future and searches
  space and time for a contact-free path, replayed through the simulator: the share of
  episodes solvable at all.
- :class:`ModelOracle` (level ``oracle`` plus the obstacles' motion model): plans
  against sampled futures of the obstacles' random walk, replanning every step: what an
  agent that knows the present and how the world moves, but not its future, can expect.

Both are marked as bounds in every table (:attr:`copi.experiments.MethodSpec.bound`).
"""

from copi.ceilings._clairvoyant import Clairvoyant, compass_moves
from copi.ceilings._field import GoalField
from copi.ceilings._model_oracle import TURN_SD, ModelOracle

__all__ = ["TURN_SD", "Clairvoyant", "GoalField", "ModelOracle", "compass_moves"]

"""Online policy instantiation (paper §III): the context chain, global strategies (the
causal map of one world among them), and the protocol every navigating method answers
(:class:`Agent`, at a sensing level)."""

from __future__ import annotations

from copi.online._agent import (
    SENSING_LEVELS,
    SENSOR_STRATEGIES,
    Agent,
    CopiAgent,
    Observation,
    Steering,
    Task,
    check_sensing,
    check_strategy,
)
from copi.online._causal import CausalMap, CausalMapFormatError, CausalStrategy
from copi.online._controller import ContextController, Decision
from copi.online._learnt import LearntAgent
from copi.online._mapping import Mapping
from copi.online._strategies import GlobalStrategy, Greedy, Route, make_strategy

__all__ = [
    "Agent",
    "CausalMap",
    "CausalMapFormatError",
    "CausalStrategy",
    "ContextController",
    "CopiAgent",
    "Decision",
    "GlobalStrategy",
    "Greedy",
    "LearntAgent",
    "Mapping",
    "Observation",
    "Route",
    "SENSING_LEVELS",
    "SENSOR_STRATEGIES",
    "Steering",
    "Task",
    "check_sensing",
    "check_strategy",
    "make_strategy",
]

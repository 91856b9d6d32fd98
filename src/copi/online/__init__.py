"""Online policy instantiation (paper §III): the context chain, copi's agents, and the
global strategies (the causal map of one world among them). The interface every method
answers (``Agent``, ``Task``, ``Observation``, sensing levels) is :mod:`copi.core`."""

from __future__ import annotations

from copi.online._agent import CopiAgent, Steering
from copi.online._causal import CausalStrategy
from copi.online._causal_file import CausalMapFormatError
from copi.online._causal_map import CausalMap, CausalMapFile
from copi.online._controller import ContextController, Decision
from copi.online._learnt import LearntAgent
from copi.online._mapping import Mapping
from copi.online._predictive import PredictiveAgent
from copi.online._strategies import GlobalStrategy, Greedy, Route, make_strategy

__all__ = [
    "CausalMap",
    "CausalMapFile",
    "CausalMapFormatError",
    "CausalStrategy",
    "ContextController",
    "CopiAgent",
    "Decision",
    "GlobalStrategy",
    "Greedy",
    "LearntAgent",
    "Mapping",
    "PredictiveAgent",
    "Route",
    "Steering",
    "make_strategy",
]

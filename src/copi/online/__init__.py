"""Online policy instantiation (paper §III): the context chain and global strategies."""

from __future__ import annotations

from copi.online._controller import ContextController, Decision
from copi.online._strategies import GlobalStrategy, Greedy, Route, make_strategy

__all__ = ["ContextController", "Decision", "GlobalStrategy", "Greedy", "Route", "make_strategy"]

"""Moved to :mod:`copi.results` (this path warns, and hands every name on)."""

from copi._moved import forward

__getattr__ = forward(
    __name__, "copi.results", "copi.results._rows", renamed={"GameRecord": "GameRow"}
)

"""Moved to :mod:`copi.bounds` (this path warns, and hands every name on)."""

from copi._moved import forward

__getattr__ = forward(__name__, "copi.bounds")

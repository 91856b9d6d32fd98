"""Moved to :mod:`copi.reports` and :mod:`copi.results` (this path warns, and hands
every name on)."""

from copi._moved import forward

__getattr__ = forward(__name__, "copi.reports", "copi.results", "copi.reports._benchmark")

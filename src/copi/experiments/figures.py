"""Moved to :mod:`copi.reports` (this path warns, and hands every name on)."""

from copi._moved import forward

__getattr__ = forward(__name__, "copi.reports", renamed={"_figure": "new_figure"})

"""The ``copi`` command (thin: parse, call the library, print)."""

from __future__ import annotations

from copi.cli.main import app, main

__all__ = ["app", "main"]

"""Offline, task-independent capability learning (paper §II)."""

from __future__ import annotations

from copi.learning._gng import GrowingNeuralGas

__all__ = ["GrowingNeuralGas"]

"""What runs leave behind, read back: the results store (one SQLite file, resumable),
one row type per table, and the paired statistics every comparison is made with.

Running (:mod:`copi.runs`), storing (here) and reporting (:mod:`copi.reports`) are three
places: a report reads a store and never imports the experiment that wrote it.
"""

from __future__ import annotations

from copi.errors import ResultsError
from copi.results._legacy import LEGACY_NAMES, split_legacy_name
from copi.results._rows import EpisodeRow, GameRow, LifeRow, Row, RunRow
from copi.results._stats import (
    MIN_PAIRS,
    PairedDifference,
    format_difference,
    lives_difference,
    pair_episodes,
    paired_difference,
    statistic,
    summarize_rows,
    verdict,
)
from copi.results._store import ResultsStore

__all__ = [
    "EpisodeRow",
    "GameRow",
    "LEGACY_NAMES",
    "LifeRow",
    "MIN_PAIRS",
    "PairedDifference",
    "ResultsError",
    "ResultsStore",
    "Row",
    "RunRow",
    "format_difference",
    "lives_difference",
    "pair_episodes",
    "paired_difference",
    "split_legacy_name",
    "statistic",
    "summarize_rows",
    "verdict",
]

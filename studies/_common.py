"""What the studies share."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

__all__ = ["kept_times"]


def kept_times(path: Path, measured: dict[str, tuple[float, Any]]) -> dict[str, Any]:
    """The wall times of the runs that did the work, in the JSON file ``path``:
    ``measured`` maps a part to (seconds it just took, what to keep); a part is kept
    anew when it is missing or took more than 30 s (a rerun that only resumes keeps the
    first run's times)."""
    times = json.loads(path.read_text()) if path.is_file() else {}
    for key, (took, value) in measured.items():
        if key not in times or took > 30:
            times[key] = value
    path.write_text(json.dumps(times))
    return times

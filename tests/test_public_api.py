"""The public surface (STYLE.md §6) and the direction of imports (DESIGN.md)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "copi"
PACKAGES = [
    "copi",
    "copi.errors",
    "copi.geometry",
    "copi.world",
    "copi.planning",
    "copi.learning",
    "copi.online",
    "copi.baselines",
    "copi.experiments",
    "copi.cli",
]
# Each part may import only the parts listed after it (DESIGN.md, "Parts").
ORDER = ["cli", "experiments", "baselines", "online", "games", "learning", "planning", "world", "geometry"]


@pytest.mark.parametrize("name", PACKAGES)
def test_all_is_sorted_and_exists(name: str) -> None:
    module = importlib.import_module(name)
    names = list(module.__all__)
    assert names == sorted(names), f"{name}.__all__ is not sorted"
    for n in names:
        assert hasattr(module, n), f"{name}.__all__ lists {n}, which does not exist"


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("copi."):
            found.add(node.module.split(".")[1])
        elif isinstance(node, ast.Import):
            found |= {a.name.split(".")[1] for a in node.names if a.name.startswith("copi.")}
    return found


@pytest.mark.parametrize("part", [p for p in ORDER if (SRC / p).is_dir()])
def test_imports_point_one_way(part: str) -> None:
    allowed = set(ORDER[ORDER.index(part) :]) | {"errors", "_rng", "_registration"}
    for path in (SRC / part).rglob("*.py"):
        bad = {m for m in _imports(path) if m in ORDER and m not in allowed}
        assert not bad, f"{path.relative_to(SRC)} imports {sorted(bad)} (above {part})"

"""The public surface and the architecture (docs/design.md, "Parts"): every package says
what it exports; imports point down the floors only, never into another part's private
module; no module imports itself back through others; no module grows past 600 lines;
and the old import paths still work, warning where the names went."""

from __future__ import annotations

import ast
import importlib
import warnings
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "copi"
PACKAGES = [
    "copi",
    "copi.errors",
    "copi.geometry",
    "copi.world",
    "copi.core",
    "copi.planning",
    "copi.games",
    "copi.learning",
    "copi.online",
    "copi.bounds",
    "copi.baselines",
    "copi.results",
    "copi.methods",
    "copi.runs",
    "copi.reports",
    "copi.experiments",
    "copi.envs",
    "copi.rl",
    "copi.cli",
]
ORDER = [
    "__main__", "cli", "_warmup", "testing", "rl",  # top
    "envs", "experiments", "reports", "runs", "methods", "results",  # the platform
    "baselines", "bounds",  # the others
    "online", "learning",  # the paper
    "games", "planning", "core", "world", "geometry",  # the domain
]  # fmt: skip
"""Every part, from the top floor down: a part may import the parts after it only."""
FOUNDATION = {"errors", "_files", "_npz", "_rng", "_plugins", "_validation", "_moved",
              "_kernel_cache"}
"""What every part may import (errors, files, seeds, plugins, argument checks, the kernels'
cache)."""
MOVED = {"ceilings"}
"""Parts that moved (their shims import nothing but :mod:`copi._moved`)."""
MOST_LINES = 600


def _part(path: Path) -> str:
    rel = path.relative_to(SRC)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def _modules() -> list[Path]:
    return sorted(p for p in SRC.rglob("*.py") if p.name != "__init__.py" or p.parent != SRC)


def _imported(path: Path) -> list[str]:
    """Every copi module ``path`` imports, wherever the import stands (a function-local
    import counts: importing inside a function to dodge a circle is still a circle)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.startswith("copi."):
                found.append(node.module)
                # "from copi.online import kernels": the module is named as a name
                found += [f"{node.module}.{a.name}" for a in node.names
                          if (SRC.joinpath(*node.module.split(".")[1:], f"{a.name}.py")).exists()]  # fmt: skip
        elif isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.startswith("copi.")]
    return found


@pytest.mark.parametrize("name", PACKAGES)
def test_all_is_sorted_and_exists(name: str) -> None:
    module = importlib.import_module(name)
    names = list(module.__all__)
    assert names == sorted(names), f"{name}.__all__ is not sorted"
    for n in names:
        assert hasattr(module, n), f"{name}.__all__ lists {n}, which does not exist"


def test_every_part_is_placed_on_a_floor() -> None:
    parts = {_part(p) for p in _modules()}
    assert parts <= set(ORDER) | FOUNDATION | MOVED, sorted(parts - set(ORDER) - FOUNDATION)


@pytest.mark.parametrize("part", ORDER)
def test_imports_point_down_the_floors_and_never_into_another_part_s_private_module(
    part: str,
) -> None:
    allowed = set(ORDER[ORDER.index(part) :]) | FOUNDATION
    for path in _modules():
        if _part(path) != part:
            continue
        for module in _imported(path):
            names = module.split(".")[1:]
            target = names[0]
            where = path.relative_to(SRC)
            assert target in allowed, f"{where} imports {module}, a part above {part}"
            if target != part and target not in FOUNDATION:
                private = [n for n in names[1:] if n.startswith("_")]
                assert not private, f"{where} imports {module}, a private module of {target}"


def test_no_module_imports_itself_back_through_others() -> None:
    graph: dict[str, set[str]] = {}
    for path in _modules():
        rel = path.relative_to(SRC).with_suffix("")
        name = ".".join(("copi", *rel.parts)).removesuffix(".__init__")
        graph[name] = set()
        for module in _imported(path):
            # an import of a package runs its __init__; of a module, that module
            graph[name].add(module)
    known = set(graph)
    edges = {m: {t for t in ts if t in known and t != m} for m, ts in graph.items()}
    # a package's __init__ that hands on its own modules' names is no circle with them
    for m, ts in edges.items():
        edges[m] = {t for t in ts if not t.startswith(m + ".")}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for t in sorted(edges[m]):
            if state.get(t) == 1:
                loop = stack[stack.index(t) :] + [t]
                pytest.fail("import circle: " + " -> ".join(loop))
            if t not in state:
                visit(t)
        stack.pop()
        state[m] = 2

    for m in sorted(edges):
        if m not in state:
            visit(m)


def test_no_module_is_over_600_lines() -> None:
    long = {str(p.relative_to(SRC)): n for p in _modules()
            if (n := len(p.read_text().splitlines())) > MOST_LINES}  # fmt: skip
    assert not long, long


SHIMS = {"copi.ceilings", "copi.experiments.methods", "copi.experiments.store",
         "copi.experiments.rows", "copi.experiments.benchmark_report"}  # fmt: skip
"""Moved modules (the others are packages some of whose names moved)."""
OLD_PATHS = [
    ("copi.experiments", "make_agent", "copi.methods"),
    ("copi.experiments", "run_episode", "copi.runs"),
    ("copi.experiments", "ResultsStore", "copi.results"),
    ("copi.experiments", "EpisodeResult", "copi.results"),
    ("copi.experiments.methods", "register_method", "copi.methods"),
    ("copi.experiments.methods", "split_legacy_name", "copi.results"),
    ("copi.experiments.store", "APPLICATION_ID", "copi.results"),
    ("copi.experiments.rows", "GameRecord", "copi.results"),
    ("copi.experiments.benchmark_report", "paired_difference", "copi.results"),
    ("copi.experiments.navigation", "draw_episode", "copi.runs"),
    ("copi.ceilings", "ModelOracle", "copi.bounds"),
    ("copi.world", "NavigationEnv", "copi.envs"),
    ("copi.games", "parallel_env", "copi.envs"),
]


@pytest.mark.parametrize(("old", "name", "new"), OLD_PATHS)
def test_an_old_path_still_works_and_says_where_the_name_went(
    old: str, name: str, new: str
) -> None:
    import sys

    if old in SHIMS:
        sys.modules.pop(old, None)  # a moved module warns when it is imported
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        value = getattr(importlib.import_module(old), name)
    assert any(issubclass(w.category, DeprecationWarning) and new in str(w.message)
               for w in caught), [str(w.message) for w in caught]  # fmt: skip
    assert value is not None

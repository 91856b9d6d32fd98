"""The command examples of the README and the guides, as a user copies them: every
``copi`` line parses (its command exists, its options are known and well typed), every
file it reads is there (shipped with copi, or written by an earlier line of the same
page), and, in ``make bench``, every line runs, in order, in an empty directory, with its
counts cut down (the one change made to it: the table :data:`SMALLER`)."""

from __future__ import annotations

import re
import shlex
from pathlib import Path
from typing import Any

import pytest
import typer

from copi.cli._common import app
from copi.world import shipped_map

ROOT = Path(__file__).resolve().parents[1]
PAGES = ["README.md", "docs/index.md", *sorted(
    str(p.relative_to(ROOT)) for p in [*(ROOT / "docs" / "guide").glob("*.md"),
                                       *(ROOT / "docs" / "tutorials").glob("*.md")])]  # fmt: skip

PLACEHOLDER = re.compile(r"\b[A-Z]{3,}\b|path/to/")
"""A word a user replaces (``tcp://HOST:8786``, ``path/to/my_package``): such a line is
parsed, never run."""

INPUTS = {"capabilities", "map_file", "world_file", "results", "worlds", "from_maps", "store"}
"""Parameters that name a file the command reads."""


def command_lines(page: str, *, optional: bool = False) -> list[list[str]]:
    """The ``copi`` lines of a page's shell blocks, as arguments: the comment dropped,
    ``.venv/bin/copi`` read as ``copi``, and an optional part of the synopsis
    (``[--json]``) left out, or with ``optional``, taken in."""
    text = (ROOT / page).read_text()
    lines = []
    for block in re.findall(r"```(?:sh|bash|console)\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = re.sub(r"\s+#.*$", "", line).strip()
            line = re.sub(r"^\.venv/bin/copi\b", "copi", line)
            if not line.startswith("copi "):
                continue
            line = re.sub(r"\[([^\]]*)\]", r"\1" if optional else "", line)
            lines.append(shlex.split(line)[1:])
    return lines


def _parse(args: list[str]) -> tuple[Any, dict[str, Any]]:
    import copi.cli.main  # noqa: F401 - registers every command group

    command: Any = typer.main.get_command(app)
    ctx = command.make_context("copi", list(args))
    while hasattr(command, "resolve_command"):
        name, sub, rest = command.resolve_command(ctx, [*ctx._protected_args, *ctx.args])
        ctx = sub.make_context(name, rest, parent=ctx)
        command = sub
    return command, ctx.params


def _outputs(params: dict[str, Any]) -> list[Path]:
    return [Path(v) for k, v in params.items() if k in ("output", "out") and v is not None]


@pytest.mark.parametrize("page", PAGES)
@pytest.mark.parametrize("optional", [False, True], ids=["plain", "with-options"])
def test_every_command_example_parses_and_finds_its_inputs(page: str, optional: bool) -> None:
    lines = command_lines(page, optional=optional)
    made: list[Path] = []
    for args in lines:
        if PLACEHOLDER.search(" ".join(args)) and "--scheduler" in args:
            i = args.index("--scheduler")  # parsed without it: reading it asks the scheduler
            args = args[:i] + args[i + 2 :]
        try:
            _, params = _parse(args)
        except Exception as exc:  # a usage error: unknown command or option, bad value
            pytest.fail(f"{page}: copi {shlex.join(args)}: {exc}")
        for key, value in params.items():
            if key not in INPUTS or not isinstance(value, str | Path) or PLACEHOLDER.search(
                    str(value)):  # fmt: skip
                continue
            p = shipped_map(value) if key == "map_file" else Path(value)
            there = p.exists() or (ROOT / p).exists() or any(
                p == m or m in p.parents for m in made)  # fmt: skip
            assert there, (f"{page}: copi {shlex.join(args)}: {value} is neither shipped "
                           "nor written by an earlier line of the page")  # fmt: skip
        made += _outputs(params)


def test_the_pages_hold_command_examples() -> None:
    assert len(command_lines("README.md")) >= 10
    assert len(command_lines("docs/guide/cli.md")) >= 20


SMALLER = {
    "--worlds": "2", "--episodes": "2", "--games": "2", "--tasks": "3", "--steps": "2048",
    "--probe-worlds": "4", "--probe-steps": "40", "--imitation-episodes": "4",
    "--curriculum": "star:512,polygon:1024",
}
"""Counts cut down for the run (a page's ``--worlds 1549`` runs 2 worlds)."""

QUICKER = {"learn": ["--worlds", "6", "--steps", "150", "--probe-worlds", "4",
                     "--probe-steps", "40"],
           "benchmark": ["--episodes", "2"], "reproduce": ["--quick"],
           "train": ["--steps", "2048"]}  # fmt: skip
"""Counts added where a line gives none (a learn at full scale takes a minute)."""


def _smaller(args: list[str]) -> list[str]:
    out = list(args)
    for i, a in enumerate(out[:-1]):
        if a in SMALLER:
            out[i + 1] = SMALLER[a]
    head = out[0] if out[0] not in ("world", "rl") else out[1]
    for opt, value in zip(QUICKER.get(head, [])[::2], QUICKER.get(head, [])[1::2],
                          strict=True):  # fmt: skip
        if opt not in out:
            out += [opt, value]
    return out


@pytest.mark.slow
@pytest.mark.timeout(3600)  # the README's benchmark learns every preset at full scale
@pytest.mark.parametrize("page", PAGES)
def test_every_command_example_runs(page: str, tmp_path: Path, monkeypatch) -> None:
    """Each line of the page, in order, in one empty directory (``make bench``)."""
    from copi.cli import main

    monkeypatch.chdir(tmp_path)
    for args in command_lines(page):
        if PLACEHOLDER.search(" ".join(args)):
            continue
        run = _smaller(args)
        print(f"$ copi {shlex.join(run)}", flush=True)
        with pytest.raises(SystemExit) as done:
            main(run)
        assert done.value.code == 0, f"{page}: copi {shlex.join(run)} exited {done.value.code}"

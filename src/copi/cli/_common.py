"""What the command groups share: the app, the consoles, progress and file names."""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

T = TypeVar("T")

app = typer.Typer(
    name="copi",
    help="Context-based Online Policy Instantiation: worlds, capabilities, experiments.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
world_app = typer.Typer(help="Sample, show and import worlds.", no_args_is_help=True)
app.add_typer(world_app, name="world")

console = Console(stderr=True, soft_wrap=True)
out = Console(soft_wrap=True)


def progress() -> Progress:
    """The progress bar used by long commands (on stderr; silent when not a terminal)."""
    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    )


def _with_progress(label: str, total: int, run: Callable[[Callable[[int, int], None]], T]) -> T:
    """``run(report)`` under a progress bar that ``report(done, total)`` advances."""
    with progress() as bar:
        task = bar.add_task(label, total=total)
        return run(lambda done, _total: bar.update(task, completed=done))


def safe_name(name: str) -> str:
    """A file name made from a world name."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "world"

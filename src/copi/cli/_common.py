"""What the command groups share: the app, the consoles, progress and file names."""

from __future__ import annotations

import importlib
import math
import os
import re
import time
from collections.abc import Callable, Iterable
from types import TracebackType
from typing import Annotated, Any, TypeVar

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)
from typer.core import TyperOption

T = TypeVar("T")

app = typer.Typer(
    name="copi",
    help="Context-based Online Policy Instantiation: worlds, capabilities, experiments.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
world_app = typer.Typer(help="Sample, show and import worlds.", no_args_is_help=True)


def _flag_type(self: TyperOption, ctx: Any) -> str | None:
    """Typer's help panels give on/off flags (``--gif``, ``--help``) a "<bool>" type,
    as if they took a value; they take none."""
    if self.is_flag and not self.count:
        return None
    return _option_type(self, ctx)


_option_type = TyperOption.display_type_rich
TyperOption.display_type_rich = _flag_type  # type: ignore[method-assign]
app.add_typer(world_app, name="world")

# markup off: what copi prints holds file names, method descriptions and values ("[nan,
# 0.0]") that rich would otherwise read as its markup and drop or refuse
console = Console(stderr=True, soft_wrap=True, markup=False)
out = Console(soft_wrap=True, markup=False)


def _print_version(value: bool) -> None:
    if value:
        from copi import __version__

        out.print(f"copi {__version__}", highlight=False)
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_print_version, is_eager=True, help="Print the version and exit."
        ),
    ] = False,
) -> None:
    """Context-based Online Policy Instantiation: worlds, capabilities, experiments."""


class PlainProgress:
    """Progress as plain lines on stderr, for logs and pipes (where a bar would print
    nothing): ``label: done/total (pct), rate/s, ETA``, at most every ``every`` seconds
    and once at the end of each task. The subset of :class:`rich.progress.Progress`'s
    interface the commands use."""

    def __init__(self, *, every: float = 10.0, console: Console = console) -> None:
        self.every = float(every)
        self.console = console
        self._tasks: list[dict[str, Any]] = []

    def __enter__(self) -> PlainProgress:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        for task in self._tasks:  # a last line for tasks that moved since their last one
            if task["printed"] != task["done"] and kind is None:
                self._print(task)

    def add_task(self, description: str, total: float | None = None, **_: Any) -> TaskID:
        now = time.monotonic()
        self._tasks.append(
            {"label": description, "total": total, "done": 0.0, "start": now,
             "last": now, "printed": None, "base": 0.0}
        )  # fmt: skip
        return TaskID(len(self._tasks) - 1)

    def update(
        self,
        task_id: TaskID,
        *,
        completed: float | None = None,
        advance: float | None = None,
        total: float | None = None,
        resumed: bool = False,
        **_: Any,
    ) -> None:
        """``resumed``: ``completed`` was done before this run (a resumed store), so the
        rate and the time left count only what is done from here."""
        task = self._tasks[task_id]
        if total is not None:
            task["total"] = total
        if completed is not None:
            task["done"] = completed
            if resumed:
                task["base"] = completed
                task["start"] = time.monotonic()
        if advance is not None:
            task["done"] += advance
        now = time.monotonic()
        finished = task["total"] is not None and task["done"] >= task["total"]
        if task["printed"] != task["done"] and (finished or now - task["last"] >= self.every):
            self._print(task)

    def advance(self, task_id: TaskID, advance: float = 1) -> None:
        self.update(task_id, advance=advance)

    def _print(self, task: dict[str, Any]) -> None:
        now = time.monotonic()
        done, total = task["done"], task["total"]
        elapsed = now - task["start"]
        rate = (done - task["base"]) / elapsed if elapsed > 0 else math.nan
        parts = [f"{task['label']}: {done:g}"]
        if total:
            parts[0] += f"/{total:g} ({100 * done / total:.0f} %)"
        if done > task["base"] and math.isfinite(rate):
            parts.append(
                f"{rate:,.0f}/s" if rate >= 100 else f"{rate:.1f}/s" if rate >= 1
                else f"{1 / rate:.1f} s each"
            )  # fmt: skip
            if total and done < total:
                parts.append(f"ETA {_duration((total - done) / rate)}")
        parts.append(f"elapsed {_duration(elapsed)}")
        self.console.print(", ".join(parts), highlight=False, markup=False)
        task["last"] = now
        task["printed"] = done


def _duration(seconds: float) -> str:
    s = round(seconds)
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{s % 3600 // 60:02d}m"


def progress() -> Progress | PlainProgress:
    """The progress display of long commands, on stderr: a bar on a terminal, else
    plain periodic lines (every ``COPI_PROGRESS_EVERY`` seconds, default 10). Says first,
    once, when numba's kernels are about to be compiled (:func:`compiling_notice`)."""
    compiling_notice()
    if not console.is_terminal:
        every = os.environ.get("COPI_PROGRESS_EVERY", "10")
        try:
            seconds = float(every)
        except ValueError:
            seconds = 10.0
        return PlainProgress(every=seconds)
    return Progress(
        TextColumn("{task.description}", markup=False),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    )


def _with_progress(label: str, total: int, run: Callable[[Callable[[int, int], None]], T]) -> T:
    """``run(report)`` under a progress display that ``report(done, total)`` advances."""
    with progress() as bar:
        task = bar.add_task(label, total=total)
        first = True

        def report(done: int, _total: int) -> None:
            nonlocal first  # a first report of work done: done before this run, resumed
            bar.update(task, completed=done, resumed=first and done > 0)  # (a bar: a field)
            first = False

        return run(report)


# numba kernels (a dispatcher each module calls first) and their compile time, seconds,
# measured on one core of a 2024 laptop-class machine
_KERNELS = {
    "copi.geometry.kernels:step_world": 4,
    "copi.planning.kernels:visibility_edges": 8,
    "copi.online.kernels:decide": 2,
}
_noticed = False


def compiling_notice(kernels: Iterable[str] | None = None) -> None:
    """One line on stderr when some of copi's numba ``kernels`` (default: the
    simulator's, the planner's, the online chain's) have no valid on-disk cache yet,
    so that the first run's silent compilation is explained. Said once per process."""
    global _noticed
    if _noticed:
        return
    seconds = 0
    for name in kernels or _KERNELS:
        module, _, func = name.partition(":")
        try:
            dispatcher = getattr(importlib.import_module(module), func)
            cached = bool(dispatcher._cache._cache_file._load_index())
        except Exception:  # numba's cache internals moved: say nothing rather than fail
            cached = True
        if not cached:
            seconds += _KERNELS.get(name, 3)
    if seconds:
        _noticed = True
        console.print(
            f"compiling kernels once (numba), ~{seconds} s; later runs reuse them",
            highlight=False,
        )


# -- options shared by several commands (defined once) ---------------------------------

SCHEDULER_HELP = (
    "Dask scheduler tcp://HOST:PORT instead of local processes; its workers must read the "
    "input files (capabilities, worlds) at the same paths."
)


def seed_option(what: str = "the episodes") -> Any:
    """``--seed``: an int in 0 .. 2**63 - 1 (what a results store keeps)."""
    from copi._rng import MAX_SEED

    return typer.Option("--seed", min=0, max=MAX_SEED, help=f"Seed of {what}.")


Seed = Annotated[int, seed_option()]
Workers = Annotated[int, typer.Option("--workers", min=1, max=512, help="Local processes.")]
def _reach_scheduler(value: str | None) -> str | None:
    """The scheduler, once it has answered: asked while the command line is read, so that
    one that cannot be reached is refused before anything is written (no directory, no
    store, no capabilities learnt for nothing)."""
    if value is not None:
        from copi.runs import make_executor

        with make_executor(1, value):
            pass
    return value


Scheduler = Annotated[
    str | None, typer.Option("--scheduler", help=SCHEDULER_HELP, callback=_reach_scheduler)
]
Preset = Annotated[
    str | None,
    typer.Option(
        "--preset",
        help="copi's mode: faithful (the paper's chain), extended, learnt or learnt-motion "
        "(default: the mode the capabilities file was learnt for).",
    ),
]
Method = Annotated[
    str | None,
    typer.Option("--method", help="A registered method (copi list names them); default: "
                 "the preset's."),
]  # fmt: skip
SensorStrategy = Annotated[
    str,
    typer.Option("--sensor-strategy",
                 help="Global strategy at level sensor: greedy, mapping or causal."),
]  # fmt: skip
Guard = Annotated[
    float | None,
    typer.Option("--guard", min=0.0,
                 help="The hand-written guard of copi's modes and compass-guard (default: the "
                 "method's); not with --preset, which sets it."),
]  # fmt: skip


def names_epilog() -> str:
    """The registered methods, families and presets, for a command's --help (computed only
    when help is asked for: the registry imports every method)."""
    from copi.methods import PRESETS, method_names
    from copi.world import family_names

    return (
        f"Methods: {', '.join(method_names())}. Families: {', '.join(family_names())}. "
        f"Presets: {', '.join(PRESETS)}."
    )


def safe_name(name: str) -> str:
    """A file name made from a world name."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "world"

"""Entry point of the ``copi`` command.

Every error on bad input ends with one line on stderr (``copi: error: ...``) and exit
code 2, without a traceback: copi's own errors (CopiError), an OSError on a path the user
gave, SQLite's failures, input too deep or too large to parse, and the option parser's
usage errors. Ctrl-C ends with one line saying what was saved, and exit code 130.
Commands live in one module per group (``world``, ``learning``, ``experiments``).
"""

from __future__ import annotations

import importlib
import os
import sqlite3
import sys
import threading
import warnings

import typer
from rich.text import Text

try:  # typer >= 0.20 carries its own copy of click
    from typer._click import exceptions as _click
except ImportError:  # pragma: no cover - older typer, on click itself
    from click import exceptions as _click  # type: ignore[no-redef]

from copi.cli._common import app, console
from copi.errors import CopiError, PluginWarning, ctrl_c_behind

# Importing a group's module registers its commands; this order is the order of --help.
for _group in ("world", "learning", "experiments", "watch", "rl", "crowd"):
    importlib.import_module(f"copi.cli.{_group}")


def _error(message: str) -> None:
    line = " ".join(str(message).split())  # one line, whatever the message held
    console.print(Text("copi: error:", style="red"), Text(line), highlight=False)
    sys.exit(2)


_show_warning = warnings.showwarning


def _warning(message, category, filename, lineno, file=None, line=None):  # type: ignore[no-untyped-def]
    """Another package's entry point that could not be loaded: one line, and on we go."""
    if issubclass(category, PluginWarning):
        text = " ".join(str(message).split())
        console.print(Text("copi: warning:", style="yellow"), Text(text), highlight=False)
        return
    _show_warning(message, category, filename, lineno, file, line)


def _interrupted(exc: BaseException | None) -> None:
    detail = str(exc) if exc is not None and str(exc) else ""
    console.print(f"copi: interrupted{': ' + detail if detail else ''}", highlight=False)
    if _threads_left():
        # An interrupted process pool's manager thread can outlive the pool's bounded stop
        # (copi.runs._executor._stop_now); the interpreter would join it at exit and
        # hang. Everything is saved (each chunk is committed), so leave now.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(130)


def _threads_left() -> bool:
    main_thread = threading.main_thread()
    return any(
        t is not main_thread and t.is_alive() and not t.daemon
        and type(t).__module__.startswith("concurrent.futures")
        for t in threading.enumerate()
    )  # fmt: skip


_PATH_OPTIONS = frozenset({"-o", "--output", "--checkpoints", "--maps", "--from-maps"})
"""Options naming a directory or a file to write, where "." is a sensible value."""

_NAMED = ("evaluate", "benchmark", "watch", "lifelong", "learn", "pursuit", "crowd")
"""Commands whose --help ends with the registered methods, families and presets."""


def _run(argv: list[str] | None) -> None:
    """Parse and invoke without click's own handlers, so that every error comes here."""
    command = typer.main.get_command(app)
    args = sys.argv[1:] if argv is None else list(argv)
    for i, arg in enumerate(args):
        # an empty value ("-o ''") would be read as the current directory: nothing of
        # copi's takes an empty name, so it is a slip, refused before anything is written
        if arg == "" or (arg.startswith("--") and arg.endswith("=")):
            option = arg[:-1] if arg else (args[i - 1] if i and args[i - 1][:1] == "-" else "")
            if not option:
                raise CopiError(f"an empty argument{' after ' + args[i - 1] if i else ''}: "
                                "give a value")  # fmt: skip
            here = " (or . for the current directory)" if option in _PATH_OPTIONS else ""
            raise CopiError(f"an empty value for {option}: give one{here}")
    if ("--help" in args or "-h" in args) and args and args[0] in _NAMED:
        # the registry imports every method: only when help is asked for
        from copi.cli._common import names_epilog

        sub = command.commands[args[0]]  # type: ignore[attr-defined]
        sub.epilog = names_epilog()
    with command.make_context("copi", args) as ctx:
        command.invoke(ctx)


def main(argv: list[str] | None = None) -> None:
    """Run the command line; bad input ends with one line on stderr and exit code 2."""
    warnings.showwarning = _warning
    try:
        _run(argv)
        sys.exit(0)  # as click's standalone mode always did
    except _click.NoArgsIsHelpError as exc:
        console.print(exc.ctx.get_help() if exc.ctx else "", highlight=False, markup=False)
        sys.exit(2)
    except typer.Exit as exc:
        sys.exit(exc.exit_code)
    except typer.Abort as exc:
        _interrupted(ctrl_c_behind(exc))
    except _click.ClickException as exc:  # usage errors: bad options, missing arguments
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else ""
        _error(f"{where}{exc.format_message()}")
    except CopiError as exc:
        _error(str(exc))
    except BrokenPipeError:
        # the reader went away (``copi inspect --json | head``): not an error of copi's;
        # stop quietly, as the Python documentation advises (stdout to devnull first, so
        # that flushing at exit raises nothing)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        sys.exit(1)
    except OSError as exc:
        where = f"{exc.filename}: " if exc.filename else ""
        _error(f"{where}{exc.strerror or exc}")
    except sqlite3.Error as exc:
        _error(f"results file: {exc}")
    except RecursionError:
        _error("input nested too deeply to read")
    except OverflowError as exc:
        _error(f"a number is too large ({exc})")
    except MemoryError:
        _error("out of memory: the input is too large")
    except KeyboardInterrupt as exc:
        _interrupted(exc)
    except SystemError as exc:
        stop = ctrl_c_behind(exc)
        if stop is None:
            raise
        _interrupted(stop)


if __name__ == "__main__":  # pragma: no cover
    main()

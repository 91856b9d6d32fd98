"""Entry point of the ``copi`` command.

Errors on bad input (a CopiError, or an OSError on a path the user gave) are printed as
one line and exit with code 2, without a traceback; usage errors are typer's (also 2).
Commands live in one module per group (``world``, ``learning``, ``experiments``).
"""

from __future__ import annotations

import importlib
import sys

from copi.cli._common import app, console
from copi.errors import CopiError

# Importing a group's module registers its commands; this order is the order of --help.
for _group in ("world", "learning", "experiments", "watch"):
    importlib.import_module(f"copi.cli.{_group}")


def main(argv: list[str] | None = None) -> None:
    """Run the command line; bad input ends with one line on stderr and exit code 2."""
    try:
        app(args=argv, prog_name="copi")
    except CopiError as exc:
        console.print(f"[red]copi: error:[/red] {exc}", highlight=False, markup=True)
        sys.exit(2)
    except OSError as exc:
        where = f" {exc.filename}" if exc.filename else ""
        console.print(f"[red]copi: error:[/red]{where}: {exc.strerror or exc}", highlight=False)
        sys.exit(2)
    except KeyboardInterrupt:
        console.print("copi: interrupted")
        sys.exit(130)


if __name__ == "__main__":  # pragma: no cover
    main()

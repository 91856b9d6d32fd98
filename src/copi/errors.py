"""Exceptions raised by copi.

Every error copi raises on bad input derives from :class:`CopiError`, and its message
says what was expected and what was found, so that the command line can print it as one
line and exit with code 2.
"""

from __future__ import annotations

__all__ = [
    "CapabilitiesFormatError",
    "CopiError",
    "Interrupted",
    "InvalidArgumentError",
    "InvalidQueryError",
    "InvalidWorldError",
    "MapFileError",
    "MethodError",
    "NotFittedError",
    "PluginWarning",
    "ResultsError",
    "WorldFileError",
    "ctrl_c_behind",
]


class CopiError(Exception):
    """Base class of all errors copi raises on bad input."""


class InvalidArgumentError(CopiError, ValueError):
    """An argument has the wrong shape, type or value (NaN, negative radius, ...)."""


class InvalidWorldError(CopiError, ValueError):
    """World geometry is invalid: not a simple polygon, a hole outside, holes crossing, ...

    ``where`` is the path of the offending part in the world's JSON form, e.g.
    ``("holes", 2)`` (empty when the world as a whole is at fault); world files use it to
    point at the line.
    """

    def __init__(self, message: str, *, where: tuple[str | int, ...] = ()) -> None:
        super().__init__(message)
        self.where = where


class WorldFileError(CopiError, ValueError):
    """A world file cannot be read: missing, not JSON, or not in copi's world format.

    The message starts with ``path:line:column:`` when the place is known.
    """


class InvalidQueryError(CopiError, ValueError):
    """A planning query is impossible as asked: its start or goal is not in free space."""


class MapFileError(CopiError, ValueError):
    """A Moving AI ``.map`` or ``.scen`` file cannot be read."""


class CapabilitiesFormatError(CopiError, ValueError):
    """A capabilities file is missing, truncated, foreign, inconsistent or too new."""


class NotFittedError(CopiError, ValueError):
    """An estimator or controller was used before it was fitted or configured."""


class MethodError(CopiError):
    """A method broke the :class:`~copi.core.Agent` contract during an episode: it raised,
    or returned something that is not a velocity. The message names the method, the step,
    and what it did; the run stops there (what was stored stays)."""


class PluginWarning(UserWarning):
    """Another package's entry point could not be loaded: it is skipped (what it would
    have registered is missing), and only a command that names one of its methods or
    families fails, saying why."""


class ResultsError(CopiError):
    """A results file is not a copi results store, or holds a different run."""


class Interrupted(KeyboardInterrupt):
    """A run stopped by Ctrl-C (SIGINT), after committing what had finished; the message
    says what is saved and how to resume. A KeyboardInterrupt, so that it stops callers
    as Ctrl-C does."""


def ctrl_c_behind(exc: BaseException) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt that ``exc`` is, or was raised while handling (numba reports
    a Ctrl-C that lands inside a compiled call as a SystemError whose context it is);
    None if there is none."""
    met: set[int] = set()  # a chain may loop
    seen: BaseException | None = exc
    while seen is not None and id(seen) not in met:
        if isinstance(seen, KeyboardInterrupt):
            return seen
        met.add(id(seen))
        seen = seen.__cause__ or seen.__context__
    return None

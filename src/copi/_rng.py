"""The one seeding idiom of copi: every random callable takes ``seed`` (an int or a
``numpy.random.Generator``), normalised here."""

from __future__ import annotations

import numbers

import numpy as np

from copi.errors import InvalidArgumentError

Seed = int | np.random.Generator | None

MAX_SEED = 2**63 - 1
"""The largest seed of a run (a results store keeps seeds as 64-bit integers)."""


def check_seed(seed: object, name: str = "seed") -> int:
    """``seed`` as an int in 0 .. :data:`MAX_SEED`, else one clear error (checked before
    a run is registered, so that it cannot fail half-way).

    Examples
    --------
    >>> check_seed(7)
    7
    >>> try:
    ...     check_seed(2**65)
    ... except InvalidArgumentError as err:
    ...     print(err)
    seed must be an int in 0 .. 9223372036854775807; got 36893488147419103232
    """
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or not (
        0 <= int(seed) <= MAX_SEED
    ):
        raise InvalidArgumentError(f"{name} must be an int in 0 .. {MAX_SEED}; got {seed!r}")
    return int(seed)


def as_generator(seed: Seed = None) -> np.random.Generator:
    """Return a :class:`numpy.random.Generator` for ``seed``.

    Parameters
    ----------
    seed : int, Generator or None
        An int seeds a new PCG64 generator; a Generator is returned unchanged (so that a
        caller can thread one stream through many calls); None draws fresh OS entropy.

    Examples
    --------
    >>> int(as_generator(3).integers(100)) == int(as_generator(3).integers(100))
    True
    """
    if seed is None or isinstance(seed, np.random.Generator):
        return np.random.default_rng(seed)
    if isinstance(seed, numbers.Integral) and not isinstance(seed, bool):
        if int(seed) < 0:
            raise InvalidArgumentError(f"seed must be a non-negative int; got {seed}")
        return np.random.default_rng(int(seed))
    raise InvalidArgumentError(
        f"seed must be an int, a numpy Generator or None; got {type(seed).__name__}"
    )

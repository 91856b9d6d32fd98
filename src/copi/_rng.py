"""The one seeding idiom of copi (STYLE.md §5)."""

from __future__ import annotations

import numbers

import numpy as np

from copi.errors import InvalidArgumentError

Seed = int | np.random.Generator | None


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

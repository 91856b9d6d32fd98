"""Checks of arguments every part shares: arrays, counts, numbers. One clear message per
mistake, saying what was expected and what was found."""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError

FloatArray = NDArray[np.float64]


def real_array(value: Any) -> FloatArray:
    """``value`` as float64, refusing what would only cast with a loss or a warning:
    complex numbers, objects, strings and ints too large for a float (TypeError or
    ValueError, as ``np.asarray`` raises for what it cannot read)."""
    if isinstance(value, np.ndarray) and value.dtype == np.float64:
        return value
    try:
        arr = np.asarray(value)
    except OverflowError:
        raise ValueError("a number is too large for a float") from None
    if arr.dtype.kind == "O":  # ragged, mixed, or ints beyond a float's range
        try:
            np.asarray(value, dtype=np.float64)
        except OverflowError:
            raise ValueError("a number is too large for a float") from None
        except (TypeError, ValueError):
            pass
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"expected real numbers, found {arr.dtype} values")
    try:
        return arr.astype(np.float64)
    except OverflowError:  # pragma: no cover - numpy reads such ints as objects
        raise ValueError("a number is too large for a float") from None


def as_points(value: Any, name: str, *, allow_single: bool = True) -> tuple[FloatArray, bool]:
    """``value`` as a C-contiguous float64 array of shape (n, 2).

    Returns the array and whether a single point of shape (2,) was given.
    """
    try:
        arr = real_array(value)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(f"{name} must be numbers of shape (n, 2); got {exc}") from None
    single = arr.ndim == 1
    if single and allow_single:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        expected = "(2,) or (n, 2)" if allow_single else "(n, 2)"
        raise InvalidArgumentError(
            f"{name} must have shape {expected}; got shape {np.shape(value)}"
        )
    check_finite(arr, name)
    return np.ascontiguousarray(arr), single


def as_vector(value: Any, name: str, *, length: int | None = None) -> FloatArray:
    """``value`` as a finite float64 array of shape (n,) (or (length,))."""
    try:
        arr = real_array(value)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(f"{name} must be numbers of shape (n,); got {exc}") from None
    if arr.ndim != 1 or (length is not None and arr.shape[0] != length):
        expected = f"({length},)" if length is not None else "(n,)"
        raise InvalidArgumentError(f"{name} must have shape {expected}; got shape {arr.shape}")
    check_finite(arr, name)
    return np.ascontiguousarray(arr)


def as_segments(value: Any, name: str = "segments") -> FloatArray:
    """``value`` as a finite float64 array of shape (m, 4): rows (px, py, qx, qy)."""
    try:
        arr = real_array(value)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(f"{name} must be numbers of shape (m, 4); got {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise InvalidArgumentError(f"{name} must have shape (m, 4); got shape {arr.shape}")
    check_finite(arr, name)
    return np.ascontiguousarray(arr)


def as_discs(centers: Any, radii: Any) -> tuple[FloatArray, FloatArray]:
    """Disc centres (d, 2) and radii (d,), both empty when ``centers`` is None."""
    if centers is None:
        if radii is not None:
            raise InvalidArgumentError("radii given without centers")
        return np.zeros((0, 2)), np.zeros(0)
    c, _ = as_points(centers, "centers")
    r = (
        np.broadcast_to(_real_scalar(radii, "radii"), (c.shape[0],))
        if np.ndim(radii) == 0
        else as_vector(radii, "radii", length=c.shape[0])
    )
    r = np.ascontiguousarray(r, dtype=np.float64)
    check_finite(r, "radii")
    if np.any(r < 0):
        raise InvalidArgumentError(f"radii must be >= 0; got {r[r < 0][0]}")
    return c, r


def _real_scalar(value: Any, name: str) -> float:
    try:
        return float(real_array(value))
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{name} must be a real number; got {value!r}") from None


def positive(value: Any, name: str) -> float:
    """``value`` as a finite float > 0."""
    v = _real_scalar(value, name)
    if not np.isfinite(v) or v <= 0:
        raise InvalidArgumentError(f"{name} must be a finite number > 0; got {v}")
    return v


def positive_int(value: Any, name: str) -> int:
    """``value`` as an int >= 1 (bools refused)."""
    try:
        ok = not isinstance(value, bool) and int(value) == value and value >= 1
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InvalidArgumentError(f"{name} must be a positive int; got {value!r}")
    return int(value)


def check_finite(arr: NDArray[Any], name: str) -> None:
    """Raise if ``arr`` holds NaN or infinity, naming the first bad index."""
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        where = idx[0] if len(idx) == 1 else idx
        raise InvalidArgumentError(
            f"{name} must be finite; found {arr[tuple(idx)]} at index {where}"
        )


def check_count(value: int, name: str, most: int) -> int:
    """``value`` if it is at most ``most``; otherwise one clear error (a count beyond it
    is a typing error, refused before any work starts)."""
    if value > most:
        raise InvalidArgumentError(
            f"{name} must be at most {most:,} (a run of more would take days and the memory "
            f"of its bookkeeping); got {value:,}"
        )
    return value


def non_negative(value: Any, name: str) -> float:
    """``value`` as a finite float >= 0 (bools refused)."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not ok or not math.isfinite(value) or value < 0:
        raise InvalidArgumentError(f"{name} must be a finite number >= 0; got {value!r}")
    return float(value)


def check_flag(value: Any, name: str) -> bool:
    """``value`` if it is True or False (numpy's too); anything else is refused, rather
    than read as true because it is not empty."""
    if isinstance(value, bool | np.bool_):
        return bool(value)
    raise InvalidArgumentError(f"{name} must be True or False; got {value!r}")

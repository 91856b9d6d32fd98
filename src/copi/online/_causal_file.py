"""The file format of a causal map (``.npz``, no pickle): the arrays of what a life in one
world taught (:meth:`copi.online.CausalMap.save` lays them out), the occupancy grid
learnt beside it, and what it is of (the world's identity, the capabilities' content
hash). Read with the one npz reader copi's files share (:mod:`copi._npz`), every array
checked before a map is built from it."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import write_npz
from copi._npz import read_metadata, read_npz
from copi.errors import CopiError
from copi.online._mapping import _CEIL, _FLOOR

__all__ = ["CausalMapFormatError", "check_arrays", "read_causal_file", "write_causal_file"]

FORMAT = "copi-causal-map"
FORMAT_VERSION = 1
MAX_COUNT = 1e9
"""Largest count (options, steps, outcomes, hits) a file may hold: a life of 10,000
tasks of 1,000 steps records 1e7 steps."""
OCCUPANCY = (_FLOOR, _CEIL)
"""The occupancy grid's bounds (see :class:`~copi.online.Mapping`)."""
_MEMBERS = (
    "n", "steps", "contacts", "outcome_keys", "outcome_counts", "context_keys",
    "context_stats", "context_outcome_keys", "context_outcome_counts", "occupancy", "hits",
    "metadata",
)  # fmt: skip
"""The only members read from a file; any other is ignored, never unpacked."""
MAX_TOTAL_BYTES = 1 << 31


class CausalMapFormatError(CopiError):
    """A causal map file is missing, truncated, foreign, newer, or for another world or
    other capabilities."""


def write_causal_file(
    path: str | os.PathLike[str], arrays: dict[str, NDArray[Any]], meta: dict[str, Any]
) -> Path:
    """Write a map's ``arrays`` and its metadata (its parameters, and what it is of) to
    ``path``, atomically."""
    meta = {"format": FORMAT, "version": FORMAT_VERSION, **meta}
    return write_npz(path, {**arrays, "metadata": np.array(json.dumps(meta, sort_keys=True))},
                     "causal map")


def read_causal_file(
    path: str | os.PathLike[str],
    *,
    world: str | None,
    capabilities: str | None,
    max_member: int,
) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
    """(the map's parameters, its arrays) from a file written by
    :func:`write_causal_file`; with ``world`` / ``capabilities`` given, a file of another
    world or of other capabilities is refused, saying which. A member unpacking to more
    than ``max_member`` bytes (the largest map's counts) is refused unread."""
    p = Path(path)
    a = read_npz(p, _MEMBERS, error=CausalMapFormatError, what="causal map file",
                 max_member=max_member, max_total=MAX_TOTAL_BYTES)  # fmt: skip
    meta = read_metadata(a, p, fmt=FORMAT, version=FORMAT_VERSION, error=CausalMapFormatError,
                         what="causal map")  # fmt: skip
    if world is not None and meta.get("world") != world:
        raise CausalMapFormatError(
            f"{p}: a causal map of world {meta.get('world')!r}, not of {world!r}"
        )
    if capabilities is not None and meta.get("capabilities") != capabilities:
        raise CausalMapFormatError(
            f"{p}: learnt with other capabilities (content {meta.get('capabilities')!r:.20}"
            f", not {capabilities!r:.20}): its contexts are another map's templates"
        )
    params = meta.get("params")
    if not isinstance(params, dict):
        raise CausalMapFormatError(f"{p}: bad parameters (not a mapping: {params!r:.40})")
    return params, a


def check_arrays(p: Path, m: int, a: dict[str, NDArray[Any]]) -> None:
    """Refuse arrays that are not the counts of an m x m map (shapes, types, bounds)."""
    size = m * m
    shapes = {
        "n": (size, 8), "steps": (size, 8), "contacts": (size, 8),
        "outcome_keys": (-1, 3), "outcome_counts": (-1,), "context_keys": (-1, 3),
        "context_stats": (-1, 3), "context_outcome_keys": (-1, 4),
        "context_outcome_counts": (-1,),
    }  # fmt: skip
    for name, shape in shapes.items():
        if name not in a:
            raise CausalMapFormatError(f"{p}: missing array {name!r}")
        arr = a[name]
        if arr.dtype.kind not in ("iu" if name.endswith("keys") else "f"):
            raise CausalMapFormatError(f"{p}: array {name!r} has dtype {arr.dtype}")
        if arr.ndim != len(shape) or any(s not in (-1, h) for s, h in zip(shape, arr.shape,
                                                                             strict=True)):
            raise CausalMapFormatError(
                f"{p}: array {name!r} has shape {arr.shape}, expected {shape} (-1: any)"
            )
        if arr.dtype.kind == "f" and not (
            np.isfinite(arr).all() and (arr >= 0).all() and (arr <= MAX_COUNT).all()
        ):
            raise CausalMapFormatError(
                f"{p}: array {name!r} holds counts that are not in 0 .. {MAX_COUNT:g} (what a "
                "life can record)"
            )
    if (a["contacts"] > a["n"] + 1e-9).any():
        raise CausalMapFormatError(f"{p}: more contacts than options executed")
    pairs = [("outcome_keys", "outcome_counts"), ("context_keys", "context_stats"),
             ("context_outcome_keys", "context_outcome_counts")]  # fmt: skip
    for keys, vals in pairs:
        if len(a[keys]) != len(a[vals]):
            raise CausalMapFormatError(f"{p}: {keys} and {vals} differ in length")
    for name, place_cols, option_col in (
        ("outcome_keys", (0, 2), 1), ("context_keys", (0,), 2),
        ("context_outcome_keys", (0, 3), 2),
    ):  # fmt: skip
        k = a[name]
        if len(k) and (
            (k[:, list(place_cols)] < 0).any() or (k[:, list(place_cols)] >= size).any()
            or (k[:, option_col] < 0).any() or (k[:, option_col] >= 8).any()
        ):  # fmt: skip
            raise CausalMapFormatError(f"{p}: {name} names places or options off the map")
    if "occupancy" in a:
        occ = a["occupancy"]
        if (
            occ.dtype.kind != "f" or occ.ndim != 2 or occ.shape[0] != occ.shape[1]
            or not np.isfinite(occ).all()
        ):  # fmt: skip
            raise CausalMapFormatError(f"{p}: occupancy is not a finite square grid of numbers")
        if (occ < OCCUPANCY[0] - 1e-9).any() or (occ > OCCUPANCY[1] + 1e-9).any():
            raise CausalMapFormatError(
                f"{p}: occupancy outside the grid's bounds [{OCCUPANCY[0]:g}, {OCCUPANCY[1]:g}]"
            )
        hits = a.get("hits")
        if hits is not None and (
            hits.dtype.kind not in "iu" or hits.shape != occ.shape or (hits < 0).any()
            or (hits > MAX_COUNT).any()
        ):  # fmt: skip
            raise CausalMapFormatError(
                f"{p}: hits are not counts in 0 .. {MAX_COUNT:g} on the occupancy grid"
            )



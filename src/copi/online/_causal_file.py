"""The file format of a causal map (``.npz``, no pickle): what a life in one world taught
(:class:`~copi.online._causal_map.CausalMap`), the occupancy grid learnt beside it, and
what it is of (the world's identity, the capabilities' content hash). Read with the one
npz reader copi's files share (:mod:`copi._npz`)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import write_npz
from copi._npz import read_metadata, read_npz
from copi.errors import CopiError, InvalidArgumentError
from copi.online._causal_map import MAX_SIDE, CausalMap
from copi.online._mapping import _CEIL, _FLOOR

__all__ = ["CausalMapFormatError", "load_causal_map", "save_causal_map"]

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
MAX_MEMBER_BYTES = 8 * 8 * MAX_SIDE * MAX_SIDE + 4096
"""A member unpacking to more than this (the largest map's counts) is refused unread."""
MAX_TOTAL_BYTES = 1 << 31


class CausalMapFormatError(CopiError):
    """A causal map file is missing, truncated, foreign, newer, or for another world or
    other capabilities."""


def save_causal_map(
    cmap: CausalMap,
    path: str | os.PathLike[str],
    *,
    world: str = "",
    capabilities: str = "",
    occupancy: NDArray[np.float64] | None = None,
    hits: NDArray[np.int64] | None = None,
) -> Path:
    """Write the map to ``path`` (``.npz``, no pickle), atomically, with what it is of:
    ``world`` (an identity of the world it was learnt in), ``capabilities`` (the
    content hash of the capabilities file whose templates are its contexts), and
    optionally the occupancy grid learnt beside it."""
    keys = sorted(cmap.outcomes)
    out_rows = [(p, a, q, c) for p, a in keys for q, c in sorted(cmap.outcomes[(p, a)].items())]
    ckeys = sorted(cmap.by_context)
    ctx_rows = [(p, c, a, *cmap.by_context[(p, c, a)][:3]) for p, c, a in ckeys]
    ctx_out = [
        (p, c, a, q, k)
        for p, c, a in ckeys
        for q, k in sorted(cmap.by_context[(p, c, a)][3].items())
    ]
    arrays: dict[str, NDArray[Any]] = {
        "n": cmap.n,
        "steps": cmap.steps,
        "contacts": cmap.contacts,
        "outcome_keys": np.array([r[:3] for r in out_rows], dtype=np.int64).reshape(-1, 3),
        "outcome_counts": np.array([r[3] for r in out_rows], dtype=np.float64),
        "context_keys": np.array([r[:3] for r in ctx_rows], dtype=np.int64).reshape(-1, 3),
        "context_stats": np.array([r[3:] for r in ctx_rows], dtype=np.float64).reshape(-1, 3),
        "context_outcome_keys": np.array(
            [r[:4] for r in ctx_out], dtype=np.int64
        ).reshape(-1, 4),
        "context_outcome_counts": np.array([r[4] for r in ctx_out], dtype=np.float64),
    }
    if occupancy is not None:
        arrays["occupancy"] = np.asarray(occupancy, dtype=np.float64)
        if hits is not None:
            arrays["hits"] = np.asarray(hits, dtype=np.int64)
    meta = {
        "format": FORMAT,
        "version": FORMAT_VERSION,
        "params": cmap.params,
        "world": world,
        "capabilities": capabilities,
    }
    arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
    return write_npz(path, arrays)



def load_causal_map(
    path: str | os.PathLike[str],
    *,
    world: str | None = None,
    capabilities: str | None = None,
) -> tuple[CausalMap, NDArray[np.float64] | None, NDArray[np.int64] | None]:
    """(map, occupancy grid or None, its hit counts or None) from a file written by
    :func:`save_causal_map`; with ``world`` / ``capabilities`` given, a file of another
    world or of other capabilities is refused, saying which. Every member is bounded in
    size before it is read and in value by its meaning (counts within what a life can
    produce, occupancy within the grid's bounds)."""
    p = Path(path)
    a = read_npz(p, _MEMBERS, error=CausalMapFormatError, what="causal map file",
                 max_member=MAX_MEMBER_BYTES, max_total=MAX_TOTAL_BYTES)  # fmt: skip
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
    try:
        cmap = CausalMap(**params)
    except (InvalidArgumentError, TypeError, KeyError, ValueError, OverflowError) as exc:
        raise CausalMapFormatError(f"{p}: bad parameters ({exc})") from None
    _check_arrays(p, cmap, a)
    cmap.n = a["n"].astype(np.float64)
    cmap.steps = a["steps"].astype(np.float64)
    cmap.contacts = a["contacts"].astype(np.float64)
    for (pl, opt, q), c in zip(a["outcome_keys"].tolist(), a["outcome_counts"].tolist(),
                               strict=True):  # fmt: skip
        cmap.outcomes.setdefault((pl, opt), {})[q] = c
    for (pl, c, opt), st in zip(a["context_keys"].tolist(), a["context_stats"].tolist(),
                                strict=True):  # fmt: skip
        cmap.by_context[(pl, c, opt)] = [st[0], st[1], st[2], {}]
    for (pl, c, opt, q), k in zip(
        a["context_outcome_keys"].tolist(), a["context_outcome_counts"].tolist(),
        strict=True,
    ):  # fmt: skip
        entry = cmap.by_context.get((pl, c, opt))
        if entry is None:
            raise CausalMapFormatError(f"{p}: inconsistent contents (outcome of no option)")
        entry[3][q] = k
    occ = a.get("occupancy")
    hits = a.get("hits")
    return (
        cmap,
        None if occ is None else occ.astype(np.float64),
        None if hits is None else hits.astype(np.int64),
    )


def _check_arrays(p: Path, cmap: CausalMap, a: dict[str, NDArray[Any]]) -> None:
    size = cmap.m * cmap.m
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



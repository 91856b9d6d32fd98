"""The causal map of one world, learnt from the agent's own experience (paper §III), and
the global strategy that plans with it.

§III ends with what turns task-independent capabilities into competence in one place:
"one must learn a causal map (specified in the language of landmark contexts and
associated policies) of a particular environment ... executing some policy from a
specific template leads to other templates with some probability". Here a *state* is a
(place, context) pair: a square cell of side ``place`` of the agent's odometry frame,
and the template its reading was recognised as (-1 for a method without contexts). An
*edge* is an option executed from a state, "make for the neighbouring place in
direction a" (one of eight), carried out step by step by the method's local policies;
it ends when the agent enters another place, or after ``patience`` steps in the same
one (no headway). Each edge keeps its observed outcomes: the place it ended in, the
steps it took, and whether it ended in a contact.

Inference (:func:`~copi.online._causal_kernels.option_values`) is value iteration over
places with those outcome probabilities, the occupancy grid the agent builds from its
ranges (:class:`~copi.online.Mapping`) as the prior of an option not tried yet
(optimistic: unknown space is free). So the agent prefers the options that worked here
before and avoids those that led to contacts or went nowhere; the context-conditional
outcomes decide among the options at the state the agent is in.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.online._causal_file import (
    CausalMapFormatError,
    check_arrays,
    read_causal_file,
    write_causal_file,
)
from copi.online._causal_kernels import OFFSETS, option_values

__all__ = ["CausalMap", "CausalMapFile"]

_LENGTH = np.hypot(OFFSETS[:, 0], OFFSETS[:, 1])  # an option's length, in places
MAX_SIDE = 2048
"""Places a side at most (a map of 2048^2 x 8 options is 270 MB)."""
MAX_MEMBER_BYTES = 8 * 8 * MAX_SIDE * MAX_SIDE + 4096
"""An array of a file unpacking to more than this (the largest map's counts) is refused
unread."""
MAX_PATIENCE = 1000
"""Most steps an option may spend in its place (a task has at most 1000 steps)."""
MAX_WEIGHT = 1e4
"""Largest prior weight or contact cost (in steps or pseudo-observations): beyond it an
option's value is the parameter alone, whatever the agent experienced."""


class CausalMap:
    """What a life in one world taught: per option, its outcomes (paper §III).

    Parameters
    ----------
    extent : float
        Half the side of the square of the odometry frame the map covers.
    place : float
        Side of a place, agent steps.
    prior : float
        Pseudo-observations of what the static map predicts for an option (its intended
        neighbour when the occupancy grid shows a way, else staying put).
    contact_cost : float
        The cost of a contact, in steps (a contact ends the task).
    patience : int
        Steps an option may spend in its place before it counts as going nowhere.
    context_prior : float
        Pseudo-observations of the place's outcomes (all contexts pooled) added to an
        option's outcomes in one context.
    """

    def __init__(
        self,
        *,
        extent: float = 80.0,
        place: float = 2.0,
        prior: float = 1.0,
        contact_cost: float = 50.0,
        patience: int = 10,
        context_prior: float = 2.0,
    ) -> None:
        for key, v in (("extent", extent), ("place", place), ("prior", prior)):
            if not (_number(v) and 0 < v <= MAX_WEIGHT):
                raise InvalidArgumentError(
                    f"{key} must be a number in (0, {MAX_WEIGHT:g}]; got {v!r}"
                )
        for key, v in (("contact_cost", contact_cost), ("context_prior", context_prior)):
            if not (_number(v) and 0 <= v <= MAX_WEIGHT):
                raise InvalidArgumentError(
                    f"{key} must be a number in [0, {MAX_WEIGHT:g}]; got {v!r}"
                )
        if not (_number(patience) and int(patience) == patience and 1 <= patience <= MAX_PATIENCE):
            raise InvalidArgumentError(
                f"patience must be an int in 1 .. {MAX_PATIENCE}; got {patience!r}"
            )
        self.extent = float(extent)
        self.place = float(place)
        self.prior = float(prior)
        self.contact_cost = float(contact_cost)
        self.patience = int(patience)
        self.context_prior = float(context_prior)
        if 2 * self.extent / self.place > MAX_SIDE:
            raise InvalidArgumentError(
                f"extent / place gives {2 * self.extent / self.place:.0f} places a side; at "
                f"most {MAX_SIDE}"
            )
        self.m = int(math.ceil(2 * self.extent / self.place))
        size = self.m * self.m
        self.n = np.zeros((size, 8))
        self.steps = np.zeros((size, 8))
        self.contacts = np.zeros((size, 8))
        # (place, option) -> {next place: count}; contacts are counted apart
        self.outcomes: dict[tuple[int, int], dict[int, float]] = {}
        # (place, context, option) -> [n, steps, contacts, {next place: count}]
        self.by_context: dict[tuple[int, int, int], list[Any]] = {}

    # -- where ------------------------------------------------------------------------

    @property
    def params(self) -> dict[str, Any]:
        return {
            "extent": self.extent, "place": self.place, "prior": self.prior,
            "contact_cost": self.contact_cost, "patience": self.patience,
            "context_prior": self.context_prior,
        }  # fmt: skip

    def place_of(self, xy: Any) -> int:
        """The place (id j * m + i) of a point of the odometry frame (clipped to the map)."""
        i = int(math.floor((float(xy[0]) + self.extent) / self.place))
        j = int(math.floor((float(xy[1]) + self.extent) / self.place))
        i = min(max(i, 0), self.m - 1)
        j = min(max(j, 0), self.m - 1)
        return j * self.m + i

    def centre(self, p: int) -> NDArray[np.float64]:
        """Centre of place ``p`` in the odometry frame."""
        j, i = divmod(int(p), self.m)
        return (np.array([i, j], dtype=np.float64) + 0.5) * self.place - self.extent

    def neighbour(self, p: int, a: int) -> int:
        """The place option ``a`` of ``p`` makes for (-1 off the map)."""
        j, i = divmod(int(p), self.m)
        qi, qj = i + int(OFFSETS[a, 0]), j + int(OFFSETS[a, 1])
        if 0 <= qi < self.m and 0 <= qj < self.m:
            return qj * self.m + qi
        return -1

    # -- experience -------------------------------------------------------------------

    def record(
        self, p: int, context: int, a: int, nxt: int | None, steps: float, contact: bool
    ) -> None:
        """One executed option: from place ``p`` in ``context``, option ``a``, ended in
        place ``nxt`` (None after a contact) after ``steps`` steps."""
        if not (0 <= p < self.m * self.m and 0 <= a < 8):
            raise InvalidArgumentError(f"no place {p} / option {a} on this map")
        if not contact and (nxt is None or not 0 <= nxt < self.m * self.m):
            raise InvalidArgumentError(f"an outcome needs a next place on the map; got {nxt!r}")
        self.n[p, a] += 1
        self.steps[p, a] += steps
        ctx = self.by_context.setdefault((p, int(context), a), [0.0, 0.0, 0.0, {}])
        ctx[0] += 1
        ctx[1] += steps
        if contact:
            self.contacts[p, a] += 1
            ctx[2] += 1
            return
        assert nxt is not None
        out = self.outcomes.setdefault((p, a), {})
        out[nxt] = out.get(nxt, 0.0) + 1
        ctx[3][nxt] = ctx[3].get(nxt, 0.0) + 1

    @property
    def n_options(self) -> int:
        """Options executed so far."""
        return int(self.n.sum())

    def _csr(self) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
        size = self.m * self.m * 8
        counts = np.zeros(size + 1, dtype=np.int64)
        for (p, a), out in self.outcomes.items():
            counts[p * 8 + a + 1] = len(out)
        offs = np.cumsum(counts)
        nxt = np.empty(int(offs[-1]), dtype=np.int64)
        cnt = np.empty(int(offs[-1]))
        for (p, a), out in self.outcomes.items():
            start = int(offs[p * 8 + a])
            for r, (q, c) in enumerate(out.items()):
                nxt[start + r] = q
                cnt[start + r] = c
        return offs, nxt, cnt

    # -- inference --------------------------------------------------------------------

    def solve(
        self,
        goal: int,
        plaus: NDArray[np.bool_],
        places: NDArray[np.int64],
        *,
        tol: float = 1e-3,
        max_sweeps: int = 2000,
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """(V, best option) over ``places`` for the goal place ``goal``, with the static
        map's verdict ``plaus[p, a]`` as the prior of each option (shape (m*m, 8))."""
        size = self.m * self.m
        offs, nxt, cnt = self._csr()
        value = np.empty(size)
        best = np.empty(size, dtype=np.int64)
        option_values(
            np.ascontiguousarray(places, dtype=np.int64), self.m, int(goal), plaus, self.n,
            self.steps, self.contacts, offs, nxt, cnt, self.prior, _LENGTH * self.place,
            float(self.patience), self.contact_cost, value, best, tol, max_sweeps,
        )  # fmt: skip
        return value, best

    def option_value(
        self,
        p: int,
        a: int,
        value: NDArray[np.float64],
        plausible: bool,
        context: int | None = None,
    ) -> float:
        """Q of option ``a`` at place ``p`` (in ``context``: its outcomes there, with the
        place's as a prior of weight ``context_prior``), under the values ``value``."""
        q = self.neighbour(p, a)
        if plausible and q >= 0:
            cost0, fut0 = _LENGTH[a] * self.place, float(value[q])
        else:
            cost0, fut0 = float(self.patience), float(value[p])
        n = float(self.n[p, a])
        total = self.prior + n
        future = self.prior * fut0 + sum(
            c * float(value[r]) for r, c in self.outcomes.get((p, a), {}).items()
        )
        q_place = (
            self.prior * cost0 + self.steps[p, a] + self.contacts[p, a] * self.contact_cost
            + future
        ) / total  # fmt: skip
        if context is None:
            return float(q_place)
        ctx = self.by_context.get((p, int(context), a))
        if ctx is None or ctx[0] == 0:
            return float(q_place)
        own = ctx[1] + ctx[2] * self.contact_cost + sum(
            c * float(value[r]) for r, c in ctx[3].items()
        )
        return float((self.context_prior * q_place + own) / (self.context_prior + ctx[0]))

    # -- persistence ------------------------------------------------------------------

    def save(
        self,
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
        optionally the occupancy grid learnt beside it and its hit counts."""
        keys = sorted(self.outcomes)
        out_rows = [(p, a, q, c) for p, a in keys for q, c in sorted(self.outcomes[(p, a)].items())]
        ckeys = sorted(self.by_context)
        ctx_rows = [(p, c, a, *self.by_context[(p, c, a)][:3]) for p, c, a in ckeys]
        ctx_out = [
            (p, c, a, q, k)
            for p, c, a in ckeys
            for q, k in sorted(self.by_context[(p, c, a)][3].items())
        ]
        arrays: dict[str, NDArray[Any]] = {
            "n": self.n,
            "steps": self.steps,
            "contacts": self.contacts,
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
        meta = {"params": self.params, "world": world, "capabilities": capabilities}
        return write_causal_file(path, arrays, meta)

    @classmethod
    def read(
        cls,
        path: str | os.PathLike[str],
        *,
        world: str | None = None,
        capabilities: str | None = None,
    ) -> CausalMapFile:
        """Everything a file written by :meth:`save` holds; with ``world`` /
        ``capabilities`` given, a file of another world or of other capabilities is
        refused, saying which. Every array is bounded in size before it is read and in
        value by its meaning (counts within what a life can produce, occupancy within
        the grid's bounds)."""
        p = Path(path)
        params, a = read_causal_file(p, world=world, capabilities=capabilities,
                                     max_member=MAX_MEMBER_BYTES)  # fmt: skip
        try:
            cmap = cls(**params)
        except (InvalidArgumentError, TypeError, KeyError, ValueError, OverflowError) as exc:
            raise CausalMapFormatError(f"{p}: bad parameters ({exc})") from None
        check_arrays(p, cmap.m, a)
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
        return CausalMapFile(
            cmap,
            None if occ is None else occ.astype(np.float64),
            None if hits is None else hits.astype(np.int64),
        )

    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str],
        *,
        world: str | None = None,
        capabilities: str | None = None,
    ) -> tuple[CausalMap, NDArray[np.float64] | None]:
        """(map, occupancy grid or None) from a file written by :meth:`save` (see
        :meth:`read`)."""
        f = cls.read(path, world=world, capabilities=capabilities)
        return f.map, f.occupancy


@dataclass(frozen=True)
class CausalMapFile:
    """What a causal map file holds (:meth:`CausalMap.read`)."""

    map: CausalMap
    occupancy: NDArray[np.float64] | None
    """The occupancy grid learnt beside the map (None if it was saved without)."""
    hits: NDArray[np.int64] | None
    """The grid's hit counts (None if saved without)."""


def _number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)

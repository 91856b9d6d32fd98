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

import json
import math
import os
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import write_npz
from copi.errors import CopiError, InvalidArgumentError
from copi.online._causal_kernels import OFFSETS, option_values, plausible_options
from copi.online._mapping import Mapping

__all__ = ["CausalMap", "CausalMapFormatError", "CausalStrategy"]

FORMAT = "copi-causal-map"
FORMAT_VERSION = 1
_LENGTH = np.hypot(OFFSETS[:, 0], OFFSETS[:, 1])  # an option's length, in places
_MAX_SIDE = 2048  # places a side at most (a map of 2048^2 x 8 options is 270 MB)


class CausalMapFormatError(CopiError):
    """A causal map file is missing, truncated, foreign, newer, or for another world or
    other capabilities."""


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
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise InvalidArgumentError(f"{key} must be a finite number > 0; got {v!r}")
        for key, v in (("contact_cost", contact_cost), ("context_prior", context_prior)):
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise InvalidArgumentError(f"{key} must be a finite number >= 0; got {v!r}")
        if int(patience) != patience or patience < 1:
            raise InvalidArgumentError(f"patience must be a positive int; got {patience!r}")
        self.extent = float(extent)
        self.place = float(place)
        self.prior = float(prior)
        self.contact_cost = float(contact_cost)
        self.patience = int(patience)
        self.context_prior = float(context_prior)
        if 2 * self.extent / self.place > _MAX_SIDE:
            raise InvalidArgumentError(
                f"extent / place gives {2 * self.extent / self.place:.0f} places a side; at "
                f"most {_MAX_SIDE}"
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
        optionally the occupancy grid learnt beside it."""
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
        meta = {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "params": self.params,
            "world": world,
            "capabilities": capabilities,
        }
        arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
        return write_npz(path, arrays)

    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str],
        *,
        world: str | None = None,
        capabilities: str | None = None,
    ) -> tuple[CausalMap, NDArray[np.float64] | None]:
        """(map, occupancy grid or None) from a file written by :meth:`save`; with
        ``world`` / ``capabilities`` given, a file of another world or of other
        capabilities is refused, saying which."""
        p = Path(path)
        if not p.is_file():
            raise CausalMapFormatError(f"{p}: no such causal map file")
        try:
            with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
                a = {k: z[k] for k in z.files}
        except (zipfile.BadZipFile, EOFError, zlib.error, ValueError, OSError) as exc:
            raise CausalMapFormatError(
                f"{p}: not a complete causal map file (truncated or corrupt: {exc})"
            ) from None
        try:
            meta = json.loads(str(a["metadata"][()]))
        except (KeyError, json.JSONDecodeError, TypeError, IndexError):
            raise CausalMapFormatError(f"{p}: not a copi causal map (no metadata)") from None
        if not isinstance(meta, dict) or meta.get("format") != FORMAT:
            found = meta.get("format") if isinstance(meta, dict) else None
            raise CausalMapFormatError(f"{p}: not a copi causal map (format {found!r})")
        version = meta.get("version")
        if not isinstance(version, int) or version < 1:
            raise CausalMapFormatError(f"{p}: bad format version {version!r}")
        if version > FORMAT_VERSION:
            raise CausalMapFormatError(
                f"{p}: written by a newer copi (format version {version}); this copi reads "
                f"versions up to {FORMAT_VERSION}: upgrade copi"
            )
        if world is not None and meta.get("world") != world:
            raise CausalMapFormatError(
                f"{p}: a causal map of world {meta.get('world')!r}, not of {world!r}"
            )
        if capabilities is not None and meta.get("capabilities") != capabilities:
            raise CausalMapFormatError(
                f"{p}: learnt with other capabilities (content {meta.get('capabilities')!r:.20}"
                f", not {capabilities!r:.20}): its contexts are another map's templates"
            )
        try:
            cmap = cls(**meta["params"])
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
        return cmap, None if occ is None else occ.astype(np.float64)

    @staticmethod
    def _hits(path: str | os.PathLike[str]) -> NDArray[np.int64] | None:
        """The grid's hit counts saved beside the map (None in a file without them)."""
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            return None if "hits" not in z.files else z["hits"].astype(np.int64)


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
        if arr.dtype.kind == "f" and not (np.isfinite(arr).all() and (arr >= 0).all()):
            raise CausalMapFormatError(f"{p}: array {name!r} holds counts that are not >= 0")
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
        hits = a.get("hits")
        if hits is not None and (
            hits.dtype.kind not in "iu" or hits.shape != occ.shape or (hits < 0).any()
        ):
            raise CausalMapFormatError(f"{p}: hits are not counts on the occupancy grid")


class CausalStrategy:
    """The global strategy ``causal``: map as :class:`~copi.online.Mapping` does, and
    learn a :class:`CausalMap` from the agent's own options (paper §III).

    Needs only the `sensor` level (the ranges, the relative goal, and in a lifelong run
    the odometry; with no odometry it lives in the goal's frame, as ``mapping`` does,
    and keeps nothing between tasks). Each step the reading is folded into the
    occupancy grid, whose own plan is made as ``mapping`` makes it, and the option under
    way is checked: when the agent has entered another place, or has spent ``patience``
    steps in its own, the option's outcome is recorded and the next option is chosen at
    the new state (place, context). The grid's way (the option its plan takes out of the
    place) is kept unless the causal map's value of it, given what was learnt at this
    state, is worse than the best option's by more than ``slack`` steps: then the causal
    map's option is followed, aiming at the farthest point of its planned chain of places
    in a straight line on the grid within ``lookahead``. So where nothing was learnt the
    strategy is ``mapping``; what it learns (options that led to contacts, or went
    nowhere, in this context) turns it elsewhere. Values are recomputed at each new
    task, after an option ended somewhere else than planned, and every ``every`` steps.
    """

    name = "causal"

    def __init__(
        self,
        causal_map: CausalMap | None = None,
        *,
        mapping: Mapping | None = None,
        every: int = 25,
        lookahead: float = 6.0,
        margin: int = 3,
        slack: float = 8.0,
    ) -> None:
        self.map = causal_map or CausalMap()
        self.mapping = mapping or Mapping(extent=self.map.extent)
        if abs(self.mapping.extent - self.map.extent) > 1e-9:
            raise InvalidArgumentError(
                "the occupancy grid and the causal map must cover the same square"
            )
        k = self.map.place / self.mapping.cell
        if abs(k - round(k)) > 1e-9 or round(k) < 1:
            raise InvalidArgumentError(
                f"a place ({self.map.place}) must be a whole number of grid cells "
                f"({self.mapping.cell})"
            )
        self.k = int(round(k))
        self.every = int(every)
        self.lookahead = float(lookahead)
        self.margin = int(margin)
        self.slack = float(slack)
        self.follows_grid = True
        self.overrides = 0
        self._occupancy: NDArray[np.float64] | None = None
        self._hits: NDArray[np.int64] | None = None
        self.plans = 0
        self.tasks = 0

    def load_occupancy(
        self, occupancy: NDArray[np.float64], hits: NDArray[np.int64] | None = None
    ) -> None:
        """Start from an occupancy grid (and its hit counts) saved with the map."""
        self._occupancy = np.asarray(occupancy, dtype=np.float64)
        self._hits = None if hits is None else np.asarray(hits, dtype=np.int64)

    def reset(self, task: Any) -> None:
        """Start a task; the causal map and the grid are kept in a lifelong run."""
        keep = bool(getattr(task, "lifelong", False))
        if not keep:
            self.map = CausalMap(**self.map.params)
        self.mapping.reset(task.n_rays, task.max_range, task.agent_radius, keep=keep)
        if self._occupancy is not None:
            if self._occupancy.shape != self.mapping.occupancy.shape:
                raise InvalidArgumentError(
                    f"the saved occupancy grid has shape {self._occupancy.shape}; this map "
                    f"needs {self.mapping.occupancy.shape}"
                )
            self.mapping.occupancy[...] = self._occupancy
            if self._hits is not None:
                self.mapping.hits[...] = self._hits
            self._occupancy = self._hits = None
        size = self.map.m * self.map.m
        self._seen = np.zeros(self.mapping.n * self.mapping.n, dtype=np.int64)
        self._queue = np.empty(4 * self.k * self.k, dtype=np.int64)
        self._plaus = np.zeros((size, 8), dtype=np.bool_)
        if not hasattr(self, "_visited") or not keep:
            self._visited = np.zeros(size, dtype=np.bool_)
        self._visited |= self.map.n.sum(1) > 0  # places a loaded map has been in
        self.value = np.full(size, 1e9)
        self.best = np.full(size, -1, dtype=np.int64)
        self.goal_place = -1
        self.option: tuple[int, int, int] | None = None  # (place, context, option)
        self.option_steps = 0
        self.age = 0
        self.tasks += 1

    # -- planning ---------------------------------------------------------------------

    def _plan(self, here: int, goal: int) -> None:
        self.plans += 1
        self.age = 0
        free = ~self.mapping._blocked()
        self.mapping.planner.free[...] = free
        m = self.map.m
        # Plan over the places seen (visited, or in the grid's sight) and those of the
        # agent and the goal, with a margin of unknown (free) space around them.
        idx = np.flatnonzero(self._visited)
        pts = np.concatenate([idx, [here, goal]])
        jj, ii = np.divmod(pts, m)
        ys, xs = np.nonzero(self.mapping.occupancy)
        i_lo, i_hi = int(ii.min()), int(ii.max())
        j_lo, j_hi = int(jj.min()), int(jj.max())
        if len(xs):
            i_lo, i_hi = min(i_lo, int(xs.min()) // self.k), max(i_hi, int(xs.max()) // self.k)
            j_lo, j_hi = min(j_lo, int(ys.min()) // self.k), max(j_hi, int(ys.max()) // self.k)
        i0, i1 = max(0, i_lo - self.margin), min(m, i_hi + self.margin + 1)
        j0, j1 = max(0, j_lo - self.margin), min(m, j_hi + self.margin + 1)
        plausible_options(free, self.k, m, i0, i1, j0, j1, OFFSETS, self._plaus, self._seen,
                          self._queue)  # fmt: skip
        gi, gj = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1))
        places = (gj * m + gi).ravel()
        self.value, self.best = self.map.solve(goal, self._plaus, places)

    def _choose(self, p: int, context: int) -> int:
        best, best_q = -1, math.inf
        for a in range(8):
            q = self.map.option_value(p, a, self.value, bool(self._plaus[p, a]), context)
            if q < best_q:
                best, best_q = a, q
        return best

    # -- acting -----------------------------------------------------------------------

    def _frame(self, obs: Any) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        g = np.asarray(obs.goal, dtype=np.float64)
        if obs.odometry is None:
            return -g, np.zeros(2)
        p = np.asarray(obs.odometry, dtype=np.float64)
        return p, p + g

    def aim(self, obs: Any, context: int = -1) -> tuple[NDArray[np.float64], float]:
        """(desired direction, distance to the point aimed at)."""
        pos, goal_at = self._frame(obs)
        g = goal_at - pos
        mapping = self.mapping
        # The grid's own plan (this also folds the reading into the grid).
        fine = mapping.aim(obs.ranges, g, None if obs.odometry is None else pos)
        cmap = self.map
        here = cmap.place_of(pos)
        goal = cmap.place_of(goal_at)
        self._visited[here] = True
        self.age += 1
        replan = goal != self.goal_place or self.age >= self.every
        if self.option is not None:
            p, c, a = self.option
            self.option_steps += 1
            if here != p or self.option_steps >= cmap.patience:
                cmap.record(p, c, a, here, self.option_steps, False)
                replan = replan or here != cmap.neighbour(p, a)
                self.option = None
        if replan:
            self.goal_place = goal
            self._plan(here, goal)
        if self.option is None and here != goal:
            self._start_option(here, int(context))
        dist = math.hypot(g[0], g[1])
        if here == goal or self.value[here] >= 1e9 or self.follows_grid:
            return fine
        if dist <= self.lookahead and mapping._clear_line(pos, goal_at):
            return g, dist
        assert self.option is not None
        # The chain of places: the chosen option, then the planned best ones.
        aim = cmap.centre(cmap.neighbour(here, self.option[2]))
        q = cmap.neighbour(here, self.option[2])
        seen: set[int] = {here}
        while q >= 0 and q not in seen and math.dist(pos, cmap.centre(q)) <= self.lookahead:
            seen.add(q)
            point = goal_at if q == goal else cmap.centre(q)
            if not mapping._clear_line(pos, point):
                break
            aim = point
            if q == goal or self.best[q] < 0:
                break
            q = cmap.neighbour(q, int(self.best[q]))
        v = aim - pos
        return v, math.hypot(v[0], v[1])

    def _grid_option(self, here: int) -> int:
        """The option the grid's plan takes from place ``here`` (-1: none, or it leaves
        the place for one that is not a neighbour)."""
        path = self.mapping.path
        if path is None:
            return -1
        cmap = self.map
        for point in path:
            q = cmap.place_of(point)
            if q != here:
                for a in range(8):
                    if cmap.neighbour(here, a) == q:
                        return a
                return -1
        return -1

    def _start_option(self, here: int, context: int) -> None:
        """Choose the option at state (here, context): the grid's own way unless what
        was learnt here says another option is better by more than ``slack`` steps
        (then the causal map's choice is followed for the option's duration)."""
        best = self._choose(here, context)
        grid = self._grid_option(here)
        self.follows_grid = False
        if grid >= 0:
            q_grid = self.map.option_value(here, grid, self.value, bool(self._plaus[here, grid]),
                                           context)  # fmt: skip
            q_best = self.map.option_value(here, best, self.value, bool(self._plaus[here, best]),
                                           context)  # fmt: skip
            if q_grid <= q_best + self.slack:
                best, self.follows_grid = grid, True
        self.option = (here, context, best)
        self.option_steps = 0
        self.overrides += not self.follows_grid

    def finish(self, outcome: str) -> None:
        """The task ended: an option cut short by a contact is recorded as one."""
        if self.option is not None and outcome == "collision":
            p, c, a = self.option
            self.map.record(p, c, a, None, self.option_steps + 1, True)
        self.option = None

    def save(
        self, path: str | os.PathLike[str], *, world: str = "", capabilities: str = ""
    ) -> Path:
        """Save the causal map and the occupancy grid (see :meth:`CausalMap.save`)."""
        return self.map.save(path, world=world, capabilities=capabilities,
                             occupancy=self.mapping.occupancy,
                             hits=self.mapping.hits)  # fmt: skip

    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str],
        *,
        world: str | None = None,
        capabilities: str | None = None,
        **kwargs: Any,
    ) -> CausalStrategy:
        """A strategy resuming the life saved in ``path`` (see :meth:`CausalMap.load`)."""
        cmap, occ = CausalMap.load(path, world=world, capabilities=capabilities)
        try:
            strategy = cls(cmap, **kwargs)
        except InvalidArgumentError as exc:
            raise CausalMapFormatError(f"{path}: {exc}") from None
        if occ is not None:
            n = int(math.ceil(2 * strategy.mapping.extent / strategy.mapping.cell))
            if occ.shape != (n, n):
                raise CausalMapFormatError(
                    f"{path}: occupancy grid of shape {occ.shape}, expected {(n, n)}"
                )
            strategy.load_occupancy(occ, CausalMap._hits(path))
        return strategy

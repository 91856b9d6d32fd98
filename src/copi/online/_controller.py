"""Online policy instantiation (paper §III): the lookup chain from a reading to an action."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.geometry import ring_angles
from copi.learning import Capabilities, GrowingNeuralGas
from copi.online import kernels

__all__ = ["ContextController", "Decision"]


@dataclass(frozen=True)
class Decision:
    """One decision, explained (``ContextController.decide(..., explain=True)``)."""

    node: int
    """chi_t: the context map's node nearest to the reading (Euclidean d_S)."""
    distance: float
    """d_S(s_t, chi_t), agent steps."""
    unfamiliar: bool
    """Whether the distance exceeded the familiarity threshold."""
    landmark: int
    """chi^_t: the node's landmark by graph distance d_G."""
    template: int
    """chi~_t: the reduced landmark (template) the landmark maps onto."""
    element: str
    """The group element g (as an operator word) with template ~ g . landmark."""
    candidates: list[str]
    """Directions (template frame) of the template's policies, i.e. g^-1 pi(chi~_t)."""
    candidate_actions: NDArray[np.float64]
    """Those policies' first moves mapped back to the world by g^-1, shape (k, 2)."""
    choice: str | None
    """The direction the global strategy picked (None: nothing could be done; "escape":
    with a guard, no policy was safe and the agent moved where the reading left most room;
    "compass D": the template offers no policy here, so the compass direction D, in the
    world frame, was taken)."""
    action: NDArray[np.float64]
    """The velocity sent to the world."""


class ContextController:
    """The paper's online chain (§III), from a sensor reading to a velocity.

    1. chi_t = argmin over the context map's nodes of d_S(s_t, chi), Euclidean;
    2. chi^_t = the landmark of chi_t by graph distance d_G (precomputed per node);
    3. (chi~_t, g_t) = the template of chi^_t and the group element with
       chi~_t ~ g_t . chi^_t (precomputed per landmark);
    4. candidates = g_t^-1 . pi for every policy pi of chi~_t: the template's first
       moves turned back into the world frame (precomputed per node);
    5. a global strategy's desired direction picks the candidate best aligned with it,
       and sets the step length (never past the point it aims at).

    So a decision is one nearest-neighbour search and table lookups. Readings farther
    than ``threshold`` from every node are flagged unfamiliar; with ``continual`` they
    also train a second, growing map whose nodes attach to the landmark (and symmetry)
    that fits them best, so the agent grows contexts for what it had not seen (§III:
    "the agent may reinstate the GNG learning temporarily").

    Parameters
    ----------
    capabilities : Capabilities
    threshold : float, optional
        Familiarity threshold on d_S; default: the distance within which 99 % of the
        training readings lay from their nearest node (stored at learning time), or
        twice the mean quantisation error for files that lack it.
    continual : bool
        Learn unfamiliar contexts as they come.
    grow_every : int
        In continual mode, the second map inserts a node every ``grow_every``
        unfamiliar readings (its GNG's lambda).
    guard : float
        0 (the paper's chain, the default) or a clearance: a candidate policy is then kept
        only if, after its step, the live reading's hit points are all at least ``guard``
        away (and its path grazes none closer than half of that), i.e. the template's
        passability is checked against the context it is instantiated in; if no
        candidate passes, the agent escapes along the compass direction the reading
        leaves most room in. Typically the agent radius plus an obstacle's step plus a
        margin.
    chain : bool
        Whether it will decide (the default). Contexts that see motion
        (``capabilities.motion``) are refused then: the chain recognises a reading alone.
        ``chain=False`` keeps only the context growth (the learnt preset's, which
        recognises contexts with their motion).
    """

    def __init__(
        self,
        capabilities: Capabilities,
        *,
        threshold: float | None = None,
        continual: bool = False,
        guard: float = 0.0,
        grow_every: int = 20,
        chain: bool = True,
    ) -> None:
        caps = capabilities
        self.chain = bool(chain)
        if self.chain and caps.motion:
            raise InvalidArgumentError(
                "these capabilities hold contexts that see motion (learnt with motion=True); "
                "the chain of the faithful and extended presets recognises a reading alone: "
                "use them with the learnt preset, or learn without motion"
            )
        self.capabilities = caps
        self.n_rays = caps.n_rays
        self.names = list(caps.policies.names)
        stats = caps.stats
        if threshold is None:
            threshold = stats.get("familiarity_threshold")
            if threshold is None:
                threshold = 2.0 * float(stats.get("quantization_error", np.inf))
        try:
            self.threshold = float(threshold)
        except (TypeError, ValueError):
            raise InvalidArgumentError(f"threshold must be a number; got {threshold!r}") from None
        if not self.threshold >= 0:  # NaN too
            raise InvalidArgumentError(
                f"threshold must be >= 0 (inf: all familiar); got {threshold!r}"
            )
        self.continual = bool(continual)
        if int(grow_every) != grow_every or grow_every < 1:
            raise InvalidArgumentError(f"grow_every must be a positive int; got {grow_every!r}")
        self.grow_every = int(grow_every)
        if not (isinstance(guard, int | float) and math.isfinite(guard) and guard >= 0):
            raise InvalidArgumentError(f"guard must be a finite number >= 0; got {guard!r}")
        self.guard = float(guard)
        angles = ring_angles(self.n_rays)
        self._cos = np.cos(angles)
        self._sin = np.sin(angles)
        self.max_range = float(caps.params.get("max_range", 10.0))
        self._no_static = np.full(self.n_rays, np.inf)  # no map: every hit counts
        self._out = np.empty(5)
        self._nodes = np.ascontiguousarray(caps.nodes, dtype=np.float64)
        self._nodes_t = np.ascontiguousarray(self._nodes.T)  # the kernels' layout (dim, n)
        self._screen = screen_nodes(self._nodes)  # decide_batch's screen
        self._gram: NDArray[np.float32] | None = None  # decide_batch's product, reused
        self._landmark = caps.landmarks.node_landmark
        self._template = caps.node_template
        self._element = caps.node_element
        self._cand, self._ok = self._candidates(self._template, self._element)
        self._extra: GrowingNeuralGas | None = None
        self._pending: list[NDArray[np.float64]] = []
        self._extra_template = np.zeros(0, dtype=np.int64)
        self._extra_element = np.zeros(0, dtype=np.int64)
        self.n_decisions = 0
        self.n_unfamiliar = 0

    def _candidates(
        self, template: NDArray[np.int64], element: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Per node: its template's policies' first moves mapped back to the world by
        g^-1 (n, D, 2), and which of them exist (n, D)."""
        pol = self.capabilities.policies
        mats = self.capabilities.group.matrices[element]  # (n, 2, 2)
        # g^-1 = g^T for the ring's rotations and mirrors; solve() keeps any matrix exact.
        acts = pol.actions[template]  # (n, D, 2)
        cand = np.linalg.solve(mats[:, None], acts[..., None])[..., 0]
        return np.ascontiguousarray(cand), np.ascontiguousarray(pol.passable[template])

    # -- the chain ---------------------------------------------------------------------

    def _static(self, static: Any, shape: tuple[int, ...]) -> NDArray[np.float64]:
        """The static map's reading(s): ``shape``, ranges >= 0 (inf: nothing there)."""
        st = _floats(static, "static")
        if st.shape != shape:
            raise InvalidArgumentError(f"static must have shape {shape}; got {st.shape}")
        if not (st >= 0).all():
            raise InvalidArgumentError(
                "static readings must be ranges >= 0 (NaN or negative found)"
            )
        return st

    def _static_shape(self, static: Any) -> NDArray[np.float64]:
        """One static reading as floats of the ray count (its values are checked in the
        compiled chain)."""
        st = _floats(static, "static")
        if st.shape != (self.n_rays,):
            raise InvalidArgumentError(f"static must have shape ({self.n_rays},); got {st.shape}")
        return st

    def _check(self, ranges: Any) -> NDArray[np.float64]:
        """Readings as floats with the capabilities' ray count (finiteness is checked in
        the compiled chain)."""
        s = _floats(ranges, "ranges")
        if s.shape[-1:] != (self.n_rays,):
            raise InvalidArgumentError(
                f"readings must have {self.n_rays} rays (as the capabilities); got shape {s.shape}"
            )
        return s

    def decide(
        self,
        ranges: Any,
        desired: Any,
        *,
        reach: float = math.inf,
        static: Any = None,
        explain: bool = False,
    ) -> tuple[NDArray[np.float64], Decision | None]:
        """The velocity for one reading, given the global strategy's desired direction.

        Parameters
        ----------
        ranges : array_like of shape (n_rays,)
        desired : array_like of shape (2,)
            Where the global strategy wants to go (any length).
        reach : float
            How far the strategy's aim lies along ``desired``: the step is cut so as not
            to go past it (1 at most).
        static : array_like of shape (n_rays,), optional
            The reading the static map alone would give here (known to a strategy that
            knows the map); with a guard, only hits it does not explain are hazards.
        explain : bool
            Also return a :class:`Decision` saying how the action came about.
        """
        self._check_chain()
        s = _floats(ranges, "ranges")
        if s.shape != (self.n_rays,):
            raise InvalidArgumentError(
                f"a reading must have shape ({self.n_rays},) (as the capabilities); got {s.shape}"
            )
        want = _floats(desired, "desired")
        if want.shape != (2,) or not (math.isfinite(want[0]) and math.isfinite(want[1])):
            raise InvalidArgumentError(
                f"desired must be a finite direction of shape (2,); got {want.tolist()}"
            )
        reach = _reach(reach)
        out = self._out
        nodes_t, cand, ok = self._nodes_t, self._cand, self._ok
        st = self._no_static if static is None else self._static_shape(static)
        kernels.decide(
            s, st, nodes_t, cand, ok, want[0], want[1], reach, self.guard,
            self._cos, self._sin, self.max_range, out,
        )  # fmt: skip
        if out[2] == -1.0:
            raise InvalidArgumentError(f"readings must be finite ranges >= 0; got {s.tolist()}")
        if out[2] == -2.0:
            raise InvalidArgumentError(
                "static readings must be ranges >= 0 (NaN or negative found)"
            )
        self.n_decisions += 1
        dist = math.sqrt(out[3])
        unfamiliar = dist > self.threshold
        if unfamiliar:
            self.n_unfamiliar += 1
            if self.continual:
                nodes, cand, ok = self._learn_unfamiliar(s)
                kernels.decide(
                    s, st, np.ascontiguousarray(nodes.T), cand, ok, want[0], want[1], reach,
                    self.guard, self._cos, self._sin, self.max_range, out,
                )  # fmt: skip
        action = out[:2].copy()
        if not explain:
            return action, None
        node, choice = int(out[2]), int(out[4])
        extra = node >= len(self._nodes)
        t = int(self._extra_template[node - len(self._nodes)] if extra else self._template[node])
        g = int(self._extra_element[node - len(self._nodes)] if extra else self._element[node])
        mask = ok[node]
        return action, Decision(
            node=node,
            distance=float(dist),
            unfamiliar=bool(unfamiliar),
            landmark=-1 if extra else int(self._landmark[node]),
            template=t,
            element=self.capabilities.group.words[g] or "id",
            candidates=[self.names[d] for d in np.flatnonzero(mask)],
            candidate_actions=cand[node][mask].copy(),
            choice=(
                None if choice == -1 else "escape" if choice == -2
                else f"compass {self.names[-3 - choice]}" if choice <= -3
                else self.names[choice]
            ),  # fmt: skip
            action=action,
        )

    def decide_batch(
        self, ranges: Any, desired: Any, reach: Any = None, static: Any = None
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Velocities for many agents at once (same results as :meth:`decide` row by
        row); returns (actions (b, 2), nodes (b,)). Not to be called from several
        threads on one controller at once (the screen's buffer is reused)."""
        self._check_chain()
        s = self._check(ranges)
        if s.ndim != 2:
            raise InvalidArgumentError(
                f"readings must have shape (b, {self.n_rays}); got {s.shape}"
            )
        if not (s >= 0).all():
            raise InvalidArgumentError("readings must be ranges >= 0 (NaN or negative found)")
        want = _floats(desired, "desired")
        if want.shape != (len(s), 2):
            raise InvalidArgumentError(f"desired must have shape ({len(s)}, 2); got {want.shape}")
        if not np.isfinite(want).all():
            raise InvalidArgumentError("desired directions must be finite")
        if reach is None:
            r = np.full(len(s), math.inf)
        else:
            r = _floats(reach, "reach")
            if r.ndim == 0:
                r = np.full(len(s), float(r))
            if r.shape != (len(s),):
                raise InvalidArgumentError(f"reach must have shape ({len(s)},); got {r.shape}")
            if not (r >= 0).all():
                raise InvalidArgumentError(
                    "reach must be >= 0 (inf: no limit); NaN or negative found"
                )
        out = np.empty((len(s), 5))
        st = (
            np.broadcast_to(self._no_static, s.shape)
            if static is None
            else self._static(static, s.shape)
        )
        s = np.ascontiguousarray(s)
        # Screen the nearest-node search with one float32 matrix product (BLAS); the
        # kernel then measures the few close nodes exactly.
        self._gram, sq = screen_products(s, self._screen, self._gram)
        kernels.decide_batch(
            s, np.ascontiguousarray(st), self._nodes_t, self._gram, sq, self._cand, self._ok,
            want, r, self.guard, self._cos, self._sin, self.max_range, out,
        )  # fmt: skip
        if (out[:, 2] < 0).any():
            raise InvalidArgumentError("readings must be finite")
        self.n_decisions += len(s)
        self.n_unfamiliar += int((np.sqrt(out[:, 3]) > self.threshold).sum())
        return out[:, :2].copy(), out[:, 2].astype(np.int64)

    def _check_chain(self) -> None:
        if not self.chain:
            raise InvalidArgumentError("this controller was made with chain=False: it grows "
                                       "contexts but does not decide")  # fmt: skip

    # -- continual learning ----------------------------------------------------------

    def _learn_unfamiliar(self, s: NDArray[np.float64]):  # type: ignore[no-untyped-def]
        """Feed an unfamiliar reading to the second map (started once two have come);
        return nodes and tables covering both maps."""
        if self._extra is None:
            self._pending.append(s)
            if len(self._pending) < 2:
                return self._nodes, self._cand, self._ok
            self._extra = GrowingNeuralGas(max_nodes=200, lambda_=self.grow_every,
                                           random_state=0)  # fmt: skip
            self._extra.partial_fit(np.array(self._pending))
        else:
            self._extra.partial_fit(s[None])
        new = self._extra.nodes_
        self._attach(new)
        return (
            np.ascontiguousarray(np.concatenate([self._nodes, new])),
            self._all_cand,
            self._all_ok,
        )

    def _attach(self, new: NDArray[np.float64]) -> None:
        """Give each new node the landmark and symmetry h that fit it best
        (landmark ~ h . node); its template is then ~ g . h . node, g the landmark's."""
        caps = self.capabilities
        lm, red, group = caps.landmarks.points, caps.reduction, caps.group
        moved = new[:, group.perms]  # (m, G, n): h . node for every h
        res = ((moved[:, None, :, :] - lm[None, :, None, :]) ** 2).mean(-1)  # (m, L, G)
        flat = res.reshape(len(new), -1).argmin(1)
        best_lm, h = np.divmod(flat, len(group))
        self._extra_template = red.template_of[best_lm]
        self._extra_element = np.array(
            [group.compose(int(red.element[j]), int(e)) for j, e in zip(best_lm, h, strict=True)],
            dtype=np.int64,
        )
        cand, ok = self._candidates(self._extra_template, self._extra_element)
        self._all_cand = np.concatenate([self._cand, cand])
        self._all_ok = np.concatenate([self._ok, ok])

    @property
    def n_learnt(self) -> int:
        """Nodes grown online for unfamiliar contexts (continual mode)."""
        return 0 if self._extra is None else len(self._extra.nodes_)

    @property
    def unfamiliar_rate(self) -> float:
        """Share of decisions so far whose reading was unfamiliar."""
        return self.n_unfamiliar / self.n_decisions if self.n_decisions else 0.0


def screen_nodes(nodes: NDArray[np.float64]) -> NDArray[np.float32]:
    """The nodes as the batched screen takes them: float32 rows [node, -|node|^2 / 2]
    (see :func:`screen_products`)."""
    n32 = np.asarray(nodes, dtype=np.float32)
    return np.ascontiguousarray(np.column_stack([n32, -0.5 * (n32 * n32).sum(1)]))


def screen_products(
    s: NDArray[np.float64], nodes: NDArray[np.float32], buf: NDArray[np.float32] | None = None
) -> tuple[NDArray[np.float32], NDArray[np.float64]]:
    """The screen of the batched nearest-node searches: for readings ``s`` (b, dim) and
    ``nodes`` (:func:`screen_nodes`), the float32 products s . node - |node|^2 / 2 of
    every reading and node, by one matrix product (BLAS) into ``buf`` when it has the
    shape (b, nodes), and each reading's squared norm; |s|^2 - 2 product approximates
    the squared distance, and the kernels screen with it row by row
    (:func:`copi.online.kernels._screened_nearest`). Non-finite readings read as 0
    here (the kernels refuse them)."""
    b, dim = s.shape
    s32 = np.empty((b, dim + 1), dtype=np.float32)
    s32[:, :dim] = np.nan_to_num(s, nan=0.0, posinf=0.0, neginf=0.0)
    s32[:, dim] = 1.0
    shape = (b, len(nodes))
    gram = buf if buf is not None and buf.shape == shape else np.empty(shape, np.float32)
    np.matmul(s32, nodes.T, out=gram)
    sq = s32[:, :dim].astype(np.float64)
    return gram, (sq * sq).sum(1)


def _floats(x: Any, name: str) -> NDArray[np.float64]:
    """``x`` as a float array, or an InvalidArgumentError saying what it was (complex
    numbers and objects are refused, not cast)."""
    if isinstance(x, np.ndarray) and x.dtype == np.float64:
        return x
    try:
        a = np.asarray(x)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(f"{name} must be real numbers; got {x!r} ({exc})") from None
    if a.dtype.kind not in "biuf":
        raise InvalidArgumentError(f"{name} must be real numbers; got {a.dtype} values")
    return a.astype(np.float64, copy=False)


def _reach(reach: Any) -> float:
    try:
        r = float(reach)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"reach must be a number >= 0; got {reach!r}") from None
    if not r >= 0:
        raise InvalidArgumentError(f"reach must be a number >= 0 (inf: no limit); got {reach!r}")
    return r

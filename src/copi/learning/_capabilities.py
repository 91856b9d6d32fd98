"""Capabilities: everything the offline phase learns, in one object and one file."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import write_npz
from copi._npz import read_metadata, read_npz
from copi.errors import CapabilitiesFormatError
from copi.learning._contexts import MOTION_CLIP, context_blocks, motion_contexts
from copi.learning._motion import MOTION_MEMBERS, MotionModel, motion_arrays, motion_from
from copi.learning._policies import ActionPriors, PolicySet
from copi.learning._safety import HIDDEN, SafetyModel
from copi.learning._skeleton import Landmarks
from copi.learning._symmetry import Operator, Reduction, SymmetryGroup

__all__ = ["FORMAT_VERSION", "Capabilities"]

FORMAT = "copi-capabilities"
FORMAT_VERSION = 1

_REQUIRED = (
    "nodes", "edges", "lm_points", "lm_members", "lm_node_landmark", "lm_anchors",
    "lm_curve", "lm_criterion", "lm_merges", "op_perms", "op_matrices", "group_perms",
    "group_matrices", "red_templates", "red_template_of", "red_element", "red_residual",
    "pol_directions", "pol_passable", "pol_actions", "pol_lengths", "pol_path_xy",
    "pol_path_start",
)  # fmt: skip
_SAFETY = ("safety_net", "safety_template", "safety_counts")
_MEMBERS = (*_REQUIRED, "prior_counts", "prior_probabilities", *_SAFETY, *MOTION_MEMBERS,
            "metadata")  # fmt: skip
"""The only members read from a file; any other is ignored, never unpacked."""
MAX_MEMBER_BYTES = 1 << 28
"""A member unpacking to more than this (256 MiB) is refused before it is unpacked."""
MAX_TOTAL_BYTES = 1 << 30
MAX_RANGE = 1000.0
"""Largest sensor range a file may give (agent steps)."""
MAX_RADIUS = 10.0
"""Largest agent radius a file may give (agent steps)."""
MAX_RAYS = 1024
MAX_COUNT = 1e9
"""Largest count (probes, moves) a file may hold: learning makes at most millions."""
MAX_WEIGHT = 1e3
"""Largest absolute weight of a safety network (trained with L2 regularisation, its
weights stay within tens)."""
_NDIM = {
    "nodes": 2, "edges": 2, "lm_points": 2, "lm_members": 1, "lm_node_landmark": 1,
    "lm_anchors": 1, "lm_curve": 1, "lm_criterion": 1, "lm_merges": 2, "op_perms": 2,
    "op_matrices": 3, "group_perms": 2, "group_matrices": 3, "red_templates": 1,
    "red_template_of": 1, "red_element": 1, "red_residual": 1, "pol_directions": 2,
    "pol_passable": 2, "pol_actions": 3, "pol_lengths": 2, "pol_path_xy": 2,
    "pol_path_start": 1, "prior_counts": 2, "prior_probabilities": 2,
    "safety_net": 3, "safety_template": 2, "safety_counts": 2,
    "motion_turn": 2, "motion_speed": 2, "motion_start": 1,
}  # fmt: skip

# Members holding indices, counts or flags: written as integers (or booleans), and
# refused as floats (a NaN or 1e19 cast to an index would be read as anything).
_INTEGER = frozenset(
    {"edges", "op_perms", "group_perms", "lm_members", "lm_node_landmark", "lm_anchors",
     "lm_merges", "red_templates", "red_template_of", "red_element", "pol_passable",
     "pol_path_start"}
)  # fmt: skip


@dataclass(frozen=True, eq=False)
class Capabilities:
    """Landmark contexts, symmetry operators and local policies (the paper's
    "capabilities", §II), with the context map they were distilled from.

    Save with :meth:`save` and read back with :meth:`load`: one ``.npz`` of plain arrays
    plus a JSON metadata entry, read with ``allow_pickle=False``.
    """

    nodes: NDArray[np.float64]
    """The context map's nodes (GNG), shape (n_nodes, n_rays) — or (n_nodes, 2 n_rays)
    for contexts that see motion (the reading, then its change; :attr:`motion`)."""
    edges: NDArray[np.int64]
    """The context map's edges, shape (n_edges, 2)."""
    landmarks: Landmarks
    group: SymmetryGroup
    reduction: Reduction
    policies: PolicySet
    priors: ActionPriors | None = None
    safety: SafetyModel | None = None
    """Safety priors from counterfactual probes (``learn --preset learnt``), else None."""
    motion_model: MotionModel | None = None
    """The learnt model of what moves (``learn --preset predictive``), else None."""
    params: dict[str, Any] = field(default_factory=dict)
    """How they were learnt (JSON-able): sensor, agent, exploration, GNG, ..."""
    stats: dict[str, Any] = field(default_factory=dict)
    """What each stage produced and how long it took (JSON-able)."""

    # -- shortcuts used online --------------------------------------------------------

    @property
    def motion(self) -> bool:
        """Whether a context is [reading, its change] (learnt with ``motion=True``)."""
        return bool(self.params.get("motion", False))

    @property
    def n_rays(self) -> int:
        """Rays of the sensor the contexts were learnt for."""
        return int(self.nodes.shape[1]) // context_blocks(self.motion)

    def contexts(self, readings: Any, previous: Any = None) -> NDArray[np.float64]:
        """The contexts of readings (..., n_rays) after ``previous`` (same shape; the
        readings themselves when None: no change seen), as the map's nodes hold them."""
        s = np.asarray(readings, dtype=np.float64)
        if not self.motion:
            return s
        return motion_contexts(s, s if previous is None else previous)

    @property
    def node_template(self) -> NDArray[np.int64]:
        """For every map node, the template of its landmark (chi_t -> chi^_t -> chi~_t)."""
        return self.reduction.template_of[self.landmarks.node_landmark]

    @property
    def node_element(self) -> NDArray[np.int64]:
        """For every map node, the group element g with template ~ g . landmark."""
        return self.reduction.element[self.landmarks.node_landmark]

    def summary(self) -> dict[str, Any]:
        """Counts of each stage's output (JSON-able)."""
        return {
            "contexts": "reading+change" if self.motion else "reading",
            "nodes": int(self.nodes.shape[0]),
            "edges": int(self.edges.shape[0]),
            "landmarks": self.landmarks.n_landmarks,
            "reduced_landmarks": int(len(self.reduction.templates)),
            "group_elements": len(self.group),
            "directions": len(self.policies.names),
            "policies": self.policies.n_policies,
            "learner": self.policies.learner,
        }

    # -- files -----------------------------------------------------------------------

    def _arrays(self) -> dict[str, NDArray[Any]]:
        lm, g, red, pol = self.landmarks, self.group, self.reduction, self.policies
        out: dict[str, NDArray[Any]] = {
            "nodes": self.nodes,
            "edges": self.edges,
            "lm_points": lm.points,
            "lm_members": lm.members,
            "lm_node_landmark": lm.node_landmark,
            "lm_anchors": lm.anchors,
            "lm_curve": lm.curve,
            "lm_criterion": lm.criterion,
            "lm_merges": lm.merges,
            "op_perms": np.array([o.perm for o in g.operators]),
            "op_matrices": np.array([o.matrix for o in g.operators]),
            "group_perms": g.perms,
            "group_matrices": g.matrices,
            "red_templates": red.templates,
            "red_template_of": red.template_of,
            "red_element": red.element,
            "red_residual": red.residual,
            "pol_directions": pol.directions,
            "pol_passable": pol.passable,
            "pol_actions": pol.actions,
            "pol_lengths": pol.lengths,
            "pol_path_xy": pol.path_xy,
            "pol_path_start": pol.path_start,
        }
        if self.priors is not None:
            out["prior_counts"] = self.priors.counts
            out["prior_probabilities"] = self.priors.probabilities
        if self.safety is not None:
            out["safety_net"] = self.safety.net
            out["safety_template"] = self.safety.template_safe
            out["safety_counts"] = self.safety.template_counts
        if self.motion_model is not None:
            out.update(motion_arrays(self.motion_model))
        return out

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the capabilities to ``path`` (``.npz``), atomically: an existing file is
        replaced only once the new one is complete.

        The same capabilities always give the same bytes (fixed member order and zip
        timestamps; stage timings are left out of the file), so a file's hash names
        its content."""
        from copi import __version__

        meta = {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "copi": __version__,
            "landmark_k": self.landmarks.k,
            "operators": [o.name for o in self.group.operators],
            "words": self.group.words,
            "directions": self.policies.names,
            "learner": self.policies.learner,
            "params": self._params(),
            "stats": _without_timings(self.stats),
        }
        if self.motion_model is not None:
            meta["motion_model"] = {"radius": self.motion_model.radius,
                                    "stats": self.motion_model.stats}  # fmt: skip
        arrays = self._arrays()
        arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
        return write_npz(path, arrays, "capabilities")

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Capabilities:
        """Read capabilities saved by :meth:`save`.

        Raises
        ------
        CapabilitiesFormatError
            For a missing, truncated, foreign or newer file, saying which.
        """
        p = Path(path)
        arrays = read_npz(p, _MEMBERS, error=CapabilitiesFormatError, what="capabilities file",
                          max_member=MAX_MEMBER_BYTES, max_total=MAX_TOTAL_BYTES)  # fmt: skip
        return cls._from_arrays(p, arrays)

    @classmethod
    def _from_arrays(cls, p: Path, a: dict[str, NDArray[Any]]) -> Capabilities:
        meta = read_metadata(a, p, fmt=FORMAT, version=FORMAT_VERSION,
                             error=CapabilitiesFormatError, what="capabilities file")  # fmt: skip
        missing = [k for k in _REQUIRED if k not in a]
        if missing:
            raise CapabilitiesFormatError(f"{p}: missing arrays {missing}")
        for k, v in a.items():
            if k != "metadata" and v.dtype.kind not in "biuf":
                raise CapabilitiesFormatError(
                    f"{p}: array {k!r} has dtype {v.dtype}, expected numbers"
                )
            if k in _INTEGER and v.dtype.kind not in "biu":
                raise CapabilitiesFormatError(
                    f"{p}: array {k!r} has dtype {v.dtype}, expected integers (indices)"
                )
        _check_arrays(p, meta, a)
        try:
            caps = cls._build(meta, a)
        except (KeyError, IndexError, ValueError, TypeError) as exc:
            raise CapabilitiesFormatError(f"{p}: inconsistent contents ({exc})") from None
        try:
            _check_consistent(p, caps)
        except (IndexError, ValueError, TypeError) as exc:
            if isinstance(exc, CapabilitiesFormatError):
                raise
            raise CapabilitiesFormatError(f"{p}: inconsistent contents ({exc})") from None
        return caps

    @classmethod
    def _build(cls, meta: dict[str, Any], a: dict[str, NDArray[Any]]) -> Capabilities:
        ops = tuple(
            Operator(name, perm, mat)
            for name, perm, mat in zip(
                meta["operators"], a["op_perms"], a["op_matrices"], strict=True
            )
        )
        group = SymmetryGroup(
            ops, a["group_perms"].astype(np.int64), a["group_matrices"], list(meta["words"])
        )
        landmarks = Landmarks(
            points=a["lm_points"],
            members=a["lm_members"].astype(np.int64),
            node_landmark=a["lm_node_landmark"].astype(np.int64),
            anchors=a["lm_anchors"].astype(np.int64),
            curve=a["lm_curve"],
            criterion=a["lm_criterion"],
            k=int(meta["landmark_k"]),
            merges=a["lm_merges"].astype(np.int64).reshape(-1, 3),
        )
        reduction = Reduction(
            a["red_templates"].astype(np.int64),
            a["red_template_of"].astype(np.int64),
            a["red_element"].astype(np.int64),
            a["red_residual"],
        )
        policies = PolicySet(
            list(meta["directions"]),
            a["pol_directions"],
            a["pol_passable"].astype(bool),
            a["pol_actions"],
            a["pol_lengths"],
            a["pol_path_xy"].reshape(-1, 2),
            a["pol_path_start"].astype(np.int64),
            str(meta["learner"]),
        )
        priors = (
            ActionPriors(a["prior_counts"], a["prior_probabilities"])
            if "prior_counts" in a and "prior_probabilities" in a
            else None
        )
        safety = (
            SafetyModel(a["safety_net"], a["safety_template"], a["safety_counts"],
                        bool(meta.get("params", {}).get("safety_static", False)))
            if all(k in a for k in _SAFETY)
            else None
        )
        return cls(
            nodes=a["nodes"].astype(np.float64),
            edges=a["edges"].astype(np.int64).reshape(-1, 2),
            landmarks=landmarks,
            group=group,
            reduction=reduction,
            policies=policies,
            priors=priors,
            safety=safety,
            motion_model=motion_from(meta, a),
            params=dict(meta.get("params", {})),
            stats=dict(meta.get("stats", {})),
        )

    def _params(self) -> dict[str, Any]:
        """The parameters a file records: the learning's, and whether its safety
        networks see the static reading (a model given in place of the learnt one says)."""
        if self.safety is None:
            return self.params
        if self.params.get("safety_static", False) == self.safety.static_aware:
            return self.params
        return {**self.params, "safety_static": self.safety.static_aware}

    def equals(self, other: Capabilities) -> bool:
        """Same arrays and metadata (used to check a save/load round trip)."""
        a, b = self._arrays(), other._arrays()
        return (
            a.keys() == b.keys()
            and all(a[k].shape == b[k].shape and np.array_equal(a[k], b[k]) for k in a)
            and self.group.words == other.group.words
            and self.policies.names == other.policies.names
            and self.policies.learner == other.policies.learner
            and self.landmarks.k == other.landmarks.k
            and (self.motion_model is None) == (other.motion_model is None)
            and (self.motion_model is None or other.motion_model is None
                 or self.motion_model.radius == other.motion_model.radius)
            and self._params() == other._params()
            and _without_timings(self.stats) == _without_timings(other.stats)
        )


def _check_consistent(p: Path, c: Capabilities) -> None:
    """Cross-check shapes and index ranges, so that a doctored file fails here, not
    deep inside the online loop."""
    n, dim = c.nodes.shape
    L = c.landmarks.n_landmarks
    G = len(c.group)
    T = len(c.reduction.templates)
    D = len(c.policies.names)
    problems = []
    motion = c.params.get("motion", False)
    if not isinstance(motion, bool):
        problems.append(f"motion must be true or false; got {motion!r}")
        motion = False
    static = c.params.get("safety_static", False)
    if not isinstance(static, bool):
        problems.append(f"safety_static must be true or false; got {static!r}")
    blocks = context_blocks(motion)
    rays = c.params.get("n_rays", dim // blocks)
    if rays * blocks != dim:
        what = "readings and changes" if motion else "readings"
        problems.append(
            f"the map's contexts have {dim} components but {blocks} x its sensor's {rays} "
            f"rays ({what}) were expected"
        )
    if c.edges.size and (c.edges.min() < 0 or c.edges.max() >= n):
        problems.append("edges refer to missing nodes")
    # Nodes and landmarks are readings (ranges within the sensor's reach): a value far
    # outside would overflow the online search's arithmetic.
    reach = float(c.params.get("max_range", 10.0))
    for what, pts in (("nodes", c.nodes), ("landmark points", c.landmarks.points)):
        if pts.size and not (np.abs(pts) <= 10.0 * reach).all():
            problems.append(f"{what} lie beyond 10 x the sensor's range {reach:g}")
    if c.landmarks.points.shape != (L, dim):
        problems.append(
            f"landmark points have shape {c.landmarks.points.shape}, expected ({L}, {dim})"
        )
    for name in ("members", "node_landmark"):
        arr = getattr(c.landmarks, name)
        if arr.shape != (n,) or (n and (arr.min() < 0 or arr.max() >= L)):
            problems.append(f"landmark {name} must map {n} nodes to 0..{L - 1}")
    if (
        c.group.perms.shape != (G, dim)
        or c.group.matrices.shape != (G, 2, 2)
        or len(c.group.words) != G
    ):
        problems.append("group arrays disagree in size")
    if c.reduction.template_of.shape != (L,) or (L and c.reduction.template_of.max() >= T):
        problems.append("reduction does not cover the landmarks")
    if c.reduction.element.shape != (L,):
        problems.append(
            f"reduction elements have shape {c.reduction.element.shape}, expected ({L},)"
        )
    elif L and (c.reduction.element.min() < 0 or c.reduction.element.max() >= G):
        problems.append("reduction refers to missing group elements")
    if T and (c.reduction.templates.min() < 0 or c.reduction.templates.max() >= L):
        problems.append("templates refer to missing landmarks")
    if T < 1:
        problems.append("no template: the reduction holds none")
    if D not in (4, 8, 16):
        problems.append(f"{D} policy directions; capabilities have 4, 8 or 16")
    pol = c.policies
    norms = np.hypot(pol.directions[:, 0], pol.directions[:, 1]) if pol.directions.ndim == 2 \
        and pol.directions.shape[-1] == 2 else np.zeros(0)  # fmt: skip
    if norms.size and not np.allclose(norms, 1.0, atol=1e-6):
        problems.append("policy directions are not unit vectors")
    if (
        pol.passable.shape != (T, D)
        or pol.actions.shape != (T, D, 2)
        or pol.directions.shape != (D, 2)
    ):
        problems.append("policy arrays disagree with the templates and directions")
    if pol.path_start.shape != (T * D + 1,) or (
        pol.path_start.size and pol.path_start[-1] != len(pol.path_xy)
    ):
        problems.append("policy paths are not indexed consistently")
    problems += _more_problems(c)
    if problems:
        raise CapabilitiesFormatError(f"{p}: inconsistent contents: {'; '.join(problems)}")


def _without_timings(stats: dict[str, Any]) -> dict[str, Any]:
    """``stats`` without the stages' wall times (which differ from one run to the next,
    and so are not written: the same capabilities give the same file)."""
    out = dict(stats)
    if isinstance(out.get("stages"), list):
        out["stages"] = [
            {k: v for k, v in st.items() if k != "seconds"} if isinstance(st, dict) else st
            for st in out["stages"]
        ]
    return out


MAX_TEXT = 200
"""Longest text a capabilities file's parameter may hold (a family's name, a label)."""


def _check_arrays(p: Path, meta: dict[str, Any], a: dict[str, NDArray[Any]]) -> None:
    """Metadata types and finite numbers, member by member, before anything is built."""

    def strings(key: str) -> bool:
        v = meta.get(key)
        return isinstance(v, list) and all(isinstance(x, str) for x in v)

    bad = [k for k in ("operators", "words", "directions") if not strings(k)]
    if not isinstance(meta.get("learner"), str):
        bad.append("learner")
    k = meta.get("landmark_k")
    if not isinstance(k, int) or isinstance(k, bool) or k < 0:
        bad.append("landmark_k")
    bad += [k for k in ("params", "stats") if not isinstance(meta.get(k, {}), dict)]
    if bad:
        raise CapabilitiesFormatError(f"{p}: metadata entries {bad} have the wrong type")
    for name, arr in a.items():
        if name in _NDIM and arr.ndim != _NDIM[name]:
            raise CapabilitiesFormatError(
                f"{p}: member {name!r} has shape {arr.shape}, expected {_NDIM[name]} dimensions"
            )
        if name == "metadata" or arr.dtype.kind != "f":
            continue
        if name == "pol_lengths":  # an impassable direction's length is +inf
            ok = not (np.isnan(arr).any() or np.isneginf(arr).any())
        else:
            ok = bool(np.isfinite(arr).all())
        if not ok:
            raise CapabilitiesFormatError(f"{p}: member {name!r} holds NaN or infinite values")
    params, stats = meta.get("params", {}), meta.get("stats", {})
    long = sorted(k for k, v in params.items() if isinstance(v, str) and len(v) > MAX_TEXT)
    if long:
        raise CapabilitiesFormatError(
            f"{p}: parameters {long} hold text longer than {MAX_TEXT} characters (names of "
            "families, learners, labels)"
        )
    for key, top in (("max_range", MAX_RANGE), ("agent_radius", MAX_RADIUS)):
        v = params.get(key)
        if v is not None and not (_number(v) and math.isfinite(v) and 0 < v <= top):
            raise CapabilitiesFormatError(
                f"{p}: parameter {key} must be a number in (0, {top:g}]; got {v!r}"
            )
    for key in ("familiarity_threshold", "quantization_error"):
        v = stats.get(key)
        if v is not None and not (_number(v) and v >= 0):
            raise CapabilitiesFormatError(f"{p}: statistic {key} must be a number >= 0; got {v!r}")
    rays = params.get("n_rays")
    if rays is not None and not (
        isinstance(rays, int) and not isinstance(rays, bool) and 4 <= rays <= MAX_RAYS
    ):
        raise CapabilitiesFormatError(
            f"{p}: parameter n_rays must be an int in 4 .. {MAX_RAYS}; got {rays!r}"
        )


def _number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and not math.isnan(v)


def _in_range(arr: NDArray[Any], n: int) -> bool:
    return not arr.size or (int(arr.min()) >= 0 and int(arr.max()) < n)


def _more_problems(c: Capabilities) -> list[str]:
    """Index ranges, permutations and plane actions that the online chain relies on."""
    n, dim = c.nodes.shape
    lm, g, red, pol = c.landmarks, c.group, c.reduction, c.policies
    L, T, D = lm.n_landmarks, len(red.templates), len(pol.names)
    problems = []
    if (c.nodes[:, : c.n_rays] < 0).any():
        problems.append("map nodes hold negative ranges")
    if c.motion and dim == 2 * c.n_rays:
        for what, pts in (("map nodes", c.nodes), ("landmark points", lm.points)):
            change = pts[:, c.n_rays :] if pts.shape[1:] == (dim,) else np.zeros(0)
            if not (np.abs(change) <= MOTION_CLIP + 1e-9).all():
                problems.append(f"{what} hold changes beyond +-{MOTION_CLIP} (the clip)")
        if g.perms.ndim == 2 and g.perms.shape[1] == dim and not (
            g.perms[:, c.n_rays :] == g.perms[:, : c.n_rays] + c.n_rays
        ).all():
            problems.append("the group does not act on the reading and its change alike")
    if lm.anchors.shape != (L,) or not _in_range(lm.anchors, n):
        problems.append(f"landmark anchors must be {L} nodes in 0..{n - 1}")
    if not _in_range(lm.merges, n + len(lm.merges)):
        problems.append("landmark merges refer to missing nodes")
    if not _in_range(red.template_of, max(T, 1)) or not _in_range(red.templates, max(L, 1)):
        problems.append("reduction indices out of range")
    if red.residual.shape != (L,):
        problems.append(f"reduction residuals have shape {red.residual.shape}, expected ({L},)")
    ident = np.arange(dim)
    for what, perms, mats in (
        ("group", g.perms, g.matrices),
        ("operator", np.array([o.perm for o in g.operators]).reshape(-1, dim),
         np.array([o.matrix for o in g.operators]).reshape(-1, 2, 2)),
    ):  # fmt: skip
        if perms.ndim != 2 or perms.shape[1] != dim or not (np.sort(perms, 1) == ident).all():
            problems.append(f"{what} permutations are not permutations of 0..{dim - 1}")
        elif (
            mats.shape != (len(perms), 2, 2)
            # entries of a rotation or reflection lie in [-1, 1]; checked first, so that
            # a tampered huge entry cannot overflow the product below
            or not (np.abs(mats) <= 1 + 1e-6).all()
            or not np.allclose(mats @ mats.transpose(0, 2, 1), np.eye(2), atol=1e-6)
        ):
            problems.append(f"{what} matrices are not rotations or reflections")
    if not problems and len(g.perms) <= 64:
        known = {row.tobytes() for row in g.perms}
        if len(known) != len(g.perms) or ident.astype(g.perms.dtype).tobytes() not in known:
            problems.append("the group's elements are not distinct or lack the identity")
        elif any(a[b].tobytes() not in known for a in g.perms for b in g.perms):
            problems.append("the group is not closed under composition")
    if (
        pol.actions.shape == (T, D, 2)
        and (np.hypot(*np.moveaxis(pol.actions, -1, 0)) > 1 + 1e-6).any()
    ):
        problems.append("policy actions are longer than one step")
    start = pol.path_start
    if start.size and (start[0] != 0 or (np.diff(start) < 0).any()):
        problems.append("policy path offsets are not increasing from 0")
    if c.priors is not None:
        if c.priors.counts.shape != (T, D) or c.priors.probabilities.shape != (T, D):
            problems.append(f"action priors must have shape ({T}, {D})")
        problems += _counts_and_probabilities("action priors", c.priors.counts,
                                              c.priors.probabilities)  # fmt: skip
    if c.safety is not None:
        net = c.safety.net
        f = 1 + 4 * c.n_rays
        if net.shape != (2, HIDDEN + 1, f):
            problems.append(
                f"the safety networks have shape {net.shape}; training makes (2, {HIDDEN + 1}, "
                f"{f}) ({HIDDEN} hidden units over {c.n_rays} rays)"
            )
        elif not (np.abs(net) <= MAX_WEIGHT).all():
            problems.append(
                f"the safety networks hold weights beyond +-{MAX_WEIGHT:g}, which no training "
                "yields"
            )
        elif not np.abs(net).reshape(2, -1).max(1).all():
            problems.append("a safety network is all zero (nothing training yields)")
        if c.safety.template_safe.shape != (T, D) or c.safety.template_counts.shape != (T, D):
            problems.append(f"safety priors must have shape ({T}, {D})")
        problems += _counts_and_probabilities("safety priors", c.safety.template_counts,
                                              c.safety.template_safe)  # fmt: skip
    return problems


def _counts_and_probabilities(what: str, counts: NDArray[Any], prob: NDArray[Any]) -> list[str]:
    """Counts are whole numbers in 0 .. MAX_COUNT; probabilities in [0, 1]."""
    out = []
    if counts.size and not (
        (counts >= 0).all() and (counts <= MAX_COUNT).all() and (counts == np.round(counts)).all()
    ):
        out.append(f"{what} hold counts that are not whole numbers in 0 .. {MAX_COUNT:g}")
    if prob.size and not ((prob >= 0).all() and (prob <= 1).all()):
        out.append(f"{what} hold probabilities outside [0, 1]")
    return out

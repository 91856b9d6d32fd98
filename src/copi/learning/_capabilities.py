"""Capabilities: everything the offline phase learns, in one object and one file."""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import atomic_write
from copi.errors import CapabilitiesFormatError
from copi.learning._policies import ActionPriors, PolicySet
from copi.learning._skeleton import Landmarks
from copi.learning._symmetry import Operator, Reduction, SymmetryGroup

__all__ = ["FORMAT_VERSION", "Capabilities"]

FORMAT = "copi-capabilities"
FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class Capabilities:
    """Landmark contexts, symmetry operators and local policies (the paper's
    "capabilities", §II), with the context map they were distilled from.

    Save with :meth:`save` and read back with :meth:`load`: one ``.npz`` of plain arrays
    plus a JSON metadata entry, read with ``allow_pickle=False``.
    """

    nodes: NDArray[np.float64]
    """The context map's nodes (GNG), shape (n_nodes, n_rays)."""
    edges: NDArray[np.int64]
    """The context map's edges, shape (n_edges, 2)."""
    landmarks: Landmarks
    group: SymmetryGroup
    reduction: Reduction
    policies: PolicySet
    priors: ActionPriors | None = None
    params: dict[str, Any] = field(default_factory=dict)
    """How they were learnt (JSON-able): sensor, agent, exploration, GNG, ..."""
    stats: dict[str, Any] = field(default_factory=dict)
    """What each stage produced and how long it took (JSON-able)."""

    # -- shortcuts used online --------------------------------------------------------

    @property
    def n_rays(self) -> int:
        return int(self.nodes.shape[1])

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
        return out

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the capabilities to ``path`` (``.npz``), atomically: an existing file is
        replaced only once the new one is complete."""
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
            "params": self.params,
            "stats": self.stats,
        }
        arrays = self._arrays()
        arrays["metadata"] = np.array(json.dumps(meta))
        return atomic_write(path, lambda fh: np.savez_compressed(fh, **arrays))  # type: ignore[arg-type]

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Capabilities:
        """Read capabilities saved by :meth:`save`.

        Raises
        ------
        CapabilitiesFormatError
            For a missing, truncated, foreign or newer file, saying which.
        """
        p = Path(path)
        if not p.exists():
            raise CapabilitiesFormatError(f"{p}: no such capabilities file")
        if p.is_dir():
            raise CapabilitiesFormatError(f"{p}: is a directory, expected a .npz capabilities file")
        try:
            # Our own handle, closed whatever np.load makes of a broken file.
            with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as data:
                arrays = {k: data[k] for k in data.files}
        except (zipfile.BadZipFile, EOFError) as exc:
            raise CapabilitiesFormatError(
                f"{p}: not a complete .npz archive (truncated or corrupt: {exc})"
            ) from None
        except ValueError as exc:
            raise CapabilitiesFormatError(f"{p}: not a copi capabilities file ({exc})") from None
        except OSError as exc:
            raise CapabilitiesFormatError(f"{p}: cannot read ({exc})") from None
        return cls._from_arrays(p, arrays)

    @classmethod
    def _from_arrays(cls, p: Path, a: dict[str, NDArray[Any]]) -> Capabilities:
        if "metadata" not in a:
            raise CapabilitiesFormatError(f"{p}: not a copi capabilities file (no metadata entry)")
        try:
            meta = json.loads(str(a["metadata"][()]))
        except (json.JSONDecodeError, TypeError, IndexError) as exc:
            raise CapabilitiesFormatError(f"{p}: metadata is not JSON ({exc})") from None
        found = meta.get("format") if isinstance(meta, dict) else None
        if found != FORMAT:
            raise CapabilitiesFormatError(f"{p}: not a copi capabilities file (format {found!r})")
        version = meta.get("version")
        if not isinstance(version, int) or version < 1:
            raise CapabilitiesFormatError(f"{p}: bad format version {version!r}")
        if version > FORMAT_VERSION:
            raise CapabilitiesFormatError(
                f"{p}: written by a newer copi (format version {version}); this copi reads "
                f"versions up to {FORMAT_VERSION}: upgrade copi"
            )
        required = [
            "nodes", "edges", "lm_points", "lm_members", "lm_node_landmark", "lm_anchors",
            "lm_curve", "lm_criterion", "lm_merges", "op_perms", "op_matrices", "group_perms",
            "group_matrices", "red_templates", "red_template_of", "red_element", "red_residual",
            "pol_directions", "pol_passable", "pol_actions", "pol_lengths", "pol_path_xy",
            "pol_path_start",
        ]  # fmt: skip
        missing = [k for k in required if k not in a]
        if missing:
            raise CapabilitiesFormatError(f"{p}: missing arrays {missing}")
        for k, v in a.items():
            if k != "metadata" and v.dtype.kind not in "biuf":
                raise CapabilitiesFormatError(
                    f"{p}: array {k!r} has dtype {v.dtype}, expected numbers"
                )
        try:
            caps = cls._build(meta, a)
        except (KeyError, IndexError, ValueError, TypeError) as exc:
            raise CapabilitiesFormatError(f"{p}: inconsistent contents ({exc})") from None
        _check_consistent(p, caps)
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
        return cls(
            nodes=a["nodes"].astype(np.float64),
            edges=a["edges"].astype(np.int64).reshape(-1, 2),
            landmarks=landmarks,
            group=group,
            reduction=reduction,
            policies=policies,
            priors=priors,
            params=dict(meta.get("params", {})),
            stats=dict(meta.get("stats", {})),
        )

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
            and self.params == other.params
            and self.stats == other.stats
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
    rays = c.params.get("n_rays", dim)
    if rays != dim:
        problems.append(f"the map's readings have {dim} rays but its sensor {rays}")
    if c.edges.size and (c.edges.min() < 0 or c.edges.max() >= n):
        problems.append("edges refer to missing nodes")
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
    if L and (c.reduction.element.min() < 0 or c.reduction.element.max() >= G):
        problems.append("reduction refers to missing group elements")
    if T and (c.reduction.templates.min() < 0 or c.reduction.templates.max() >= L):
        problems.append("templates refer to missing landmarks")
    pol = c.policies
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
    if problems:
        raise CapabilitiesFormatError(f"{p}: inconsistent contents: {'; '.join(problems)}")

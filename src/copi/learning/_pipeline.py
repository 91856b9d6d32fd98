"""The whole offline phase (paper §II, Fig. 1): exploration -> context map -> landmarks ->
symmetry reduction -> policy templates -> capabilities."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from copi._validation import check_count, positive_int
from copi.errors import InvalidArgumentError
from copi.learning._capabilities import Capabilities
from copi.learning._contexts import (
    block_operators,
    context_blocks,
    motion_contexts,
    previous_in_world,
)
from copi.learning._explore import explore
from copi.learning._gng import GrowingNeuralGas
from copi.learning._motion import learn_motion
from copi.learning._policies import ActionPriors, AStarLearner, ValueIterationLearner, compass
from copi.learning._safety import PROBE_LABELS, learn_safety, probe_states
from copi.learning._skeleton import bootstrap_landmarks, skeletonize
from copi.learning._symmetry import SymmetryGroup, reduce_landmarks, ring_operators
from copi.world import RangeSensor, check_family

__all__ = ["LearnParams", "learn", "simulated_steps"]


MOST = {"worlds": 100_000, "steps": 100_000, "workers": 512, "n_rays": 4096,
        "epochs": 1_000, "probe_worlds": 100_000, "probe_steps": 100_000,
        "probe_horizon": 1_000, "predict_worlds": 100_000, "predict_steps": 100_000}  # fmt: skip
"""The largest value of each count of :class:`LearnParams` (the paper's 100 worlds of 300
steps, 20 passes; a count beyond these is a typing error, refused before any work)."""
MOST_READINGS = 10_000_000
"""Most readings an exploration may gather (worlds x steps; 1.3 GB of float32 ranges)."""
MOST_PROBED = 2_000_000
"""Most states the probing walks may visit (probe_worlds x probe_steps)."""


@dataclass(frozen=True)
class LearnParams:
    """Parameters of :func:`learn`; the defaults are the paper's setting (§IV)."""

    worlds: int = 100
    """Random worlds explored (paper: 100)."""
    family: str = "star"
    """World family explored ("star": the paper's random worlds; see copi.world)."""
    steps: int = 300
    """Random-walk steps in each world (paper: 300)."""
    seed: int = 0
    """World k of the exploration draws from default_rng([seed, k]); the map from seed
    (unless ``map_seed`` says otherwise)."""
    map_seed: int | None = None
    """Seed of the context map and of its bootstrap (None: ``seed``), to vary the map on
    the same readings."""
    workers: int = 1
    """Processes exploring worlds in parallel (results do not depend on it)."""
    n_rays: int = 32
    """Rays of the ring sensor (paper: 32)."""
    max_range: float = 10.0
    """Sensor range, in agent steps."""
    agent_radius: float = 0.3
    """Radius of the disc agent, in agent steps."""
    max_nodes: int | None = None
    """Cap on the context map's nodes (None: as many as the signals grow, ~600)."""
    epochs: int = 2
    """Passes of the GNG over the readings (2 x 30,000 = the paper's ~600 nodes)."""
    landmarks: int | None = None
    """Force this many landmarks instead of the rule's choice (the paper found 9)."""
    skeleton_method: str = "knee"
    """How k is chosen on H(k): "knee", "curvature", "lmethod", ... (see
    copi.learning.skeletonize)."""
    skeleton_bootstrap: int = 32
    """Maps of bootstrap resamples of the readings whose median choice gives the number of
    landmarks (copi.learning.bootstrap_landmarks); 0: the map's own H(k) alone (copi
    0.2's rule, whose count moved with the seed from 23 to 95)."""
    symmetry_tol: float | None = None
    """Largest difference on any ray (agent steps) with which a landmark still maps onto a
    template (the tolerance of the paper's automaton, §II-C); None: derived from the
    training data with ``symmetry_quantile``."""
    symmetry_quantile: float = 95.0
    """Percentile of the context map's per-ray error |reading[i] - nearest node[i]|, over
    every training reading and ray, used as ``symmetry_tol`` when that is None."""
    directions: int = 4
    """Local policies per template: 4 (E, N, W, S, the paper's), 8 or 16."""
    learner: str = "astar"
    """Policy learner: "astar" (the paper's) or "value-iteration"."""
    safety: bool = False
    """Also learn safety priors from counterfactual probes (the ``learnt`` preset; see
    :mod:`copi.learning._safety`)."""
    probe_worlds: int = 60
    """Worlds of the probing walks (the families of ``probe_families`` in turn)."""
    probe_steps: int = 150
    """Random-walk steps per probing world (every second state is probed)."""
    probe_horizon: int = 3
    """Steps each probed action is held while the obstacles move."""
    probe_families: str = "star,crowd,polygon,indoor"
    """Comma-separated world families of the probing walks (task-independent: no goal)."""
    probe_label: str = "hold"
    """How a probe is judged safe: ``"hold"`` (its action held ``probe_horizon`` steps
    without contact) or ``"escape"`` (taken once, leaving a clear second move: the
    model-oracle's check; see :mod:`copi.learning._safety`)."""
    safety_static: bool = False
    """The safety networks learn with the static map's reading (what a ``map``-level
    agent is handed): their closeness block then sees only the hits the static map does
    not explain, i.e. what moves. Off by default (the registered preset's networks see
    the reading alone, at every level)."""
    predict: bool = False
    """Also learn the model of what moves (the ``predictive`` preset; see
    :mod:`copi.learning._motion`): from ``predict_worlds`` random walks of
    ``predict_steps`` steps among moving bodies, in the families of ``probe_families``."""
    predict_worlds: int = 80
    predict_steps: int = 200
    motion: bool = False
    """Contexts that see motion: the context map, landmarks, templates and priors live
    on [reading, its change since the last step] (see :mod:`copi.learning._contexts`),
    the symmetry acting on both blocks alike. The local policies are still learnt on a
    template's reading block (its static local world)."""

    def __post_init__(self) -> None:
        for name in MOST:
            positive_int(getattr(self, name), name)
            check_count(int(getattr(self, name)), name, MOST[name])
        for a, b, most in (("worlds", "steps", MOST_READINGS),
                           ("probe_worlds", "probe_steps", MOST_PROBED),
                           ("predict_worlds", "predict_steps", MOST_PROBED)):  # fmt: skip
            n = int(getattr(self, a)) * int(getattr(self, b))
            if n > most:
                raise InvalidArgumentError(
                    f"{a} x {b} must be at most {most:,} (the readings it keeps in memory); "
                    f"got {n:,}"
                )
        check_family(self.family)
        if int(self.skeleton_bootstrap) != self.skeleton_bootstrap or self.skeleton_bootstrap < 0:
            raise InvalidArgumentError(
                f"skeleton_bootstrap must be an int >= 0; got {self.skeleton_bootstrap!r}"
            )
        if self.map_seed is not None and (
            isinstance(self.map_seed, bool) or int(self.map_seed) != self.map_seed
            or self.map_seed < 0
        ):  # fmt: skip
            raise InvalidArgumentError(f"map_seed must be an int >= 0; got {self.map_seed!r}")
        for name in ("safety", "motion", "safety_static", "predict"):
            if not isinstance(getattr(self, name), bool):
                raise InvalidArgumentError(
                    f"{name} must be True or False; got {getattr(self, name)!r}"
                )
        for fam in self.probe_families.split(","):
            check_family(fam.strip())
        if self.probe_label not in PROBE_LABELS:
            raise InvalidArgumentError(
                f"probe_label must be one of {', '.join(PROBE_LABELS)}; got {self.probe_label!r}"
            )
        if self.learner not in ("astar", "value-iteration"):
            raise InvalidArgumentError(
                f"learner must be 'astar' or 'value-iteration'; got {self.learner!r}"
            )
        if self.directions not in (4, 8, 16):
            raise InvalidArgumentError(f"directions must be 4, 8 or 16; got {self.directions!r}")
        if self.landmarks is not None and self.landmarks < 1:
            raise InvalidArgumentError(f"landmarks must be >= 1; got {self.landmarks}")
        if self.symmetry_tol is not None and not self.symmetry_tol >= 0:
            raise InvalidArgumentError(f"symmetry_tol must be >= 0; got {self.symmetry_tol}")
        if not 0 <= self.symmetry_quantile <= 100:
            raise InvalidArgumentError(
                f"symmetry_quantile must be in [0, 100]; got {self.symmetry_quantile}"
            )


Progress = Callable[[str, int, int], None]
"""progress(stage, done, total), called as a stage advances."""


def simulated_steps(params: LearnParams | Mapping[str, Any]) -> dict[str, int]:
    """The simulator steps :func:`learn` takes with ``params``: its learning samples,
    counted as a reinforcement learner's environment steps are. ``exploration`` (worlds x
    steps), and with safety priors the probing ``walks`` and at most ``probes`` steps of
    counterfactual probes (every second state of a walk, each of the directions and
    waiting held ``probe_horizon`` steps, fewer where a probe touches something; with
    ``probe_label="escape"`` each taken once, and two steps of the obstacles alone a
    state: the second moves are judged against those, not simulated).
    ``params`` may be a capabilities file's ``params``.

    Examples
    --------
    >>> simulated_steps(LearnParams())["total"]
    30000
    >>> simulated_steps(LearnParams(directions=16, safety=True))["total"]
    268500
    """
    if not isinstance(params, LearnParams):
        known = {f.name for f in dataclasses.fields(LearnParams)}
        params = LearnParams(**{k: v for k, v in dict(params).items() if k in known})
    p = params
    explore_steps = p.worlds * p.steps
    walks = p.probe_worlds * p.probe_steps if p.safety else 0
    walks += p.predict_worlds * p.predict_steps if p.predict else 0
    probed = p.probe_worlds * ((p.probe_steps + 1) // 2) if p.safety else 0
    per = p.probe_horizon if p.probe_label == "hold" else 1
    probes = probed * ((p.directions + 1) * per + (2 if p.probe_label == "escape" else 0))
    return {"exploration": explore_steps, "walks": walks, "probes": probes,
            "total": explore_steps + walks + probes}  # fmt: skip


def learn(params: LearnParams | None = None, *, progress: Progress | None = None) -> Capabilities:
    """Run the offline phase and return the capabilities, with per-stage statistics in
    ``capabilities.stats["stages"]`` (what each stage produced and its seconds)."""
    p = params or LearnParams()
    report = progress or (lambda stage, done, total: None)
    stages: list[dict[str, Any]] = []
    sensor = RangeSensor(p.n_rays, p.max_range)

    t0 = time.perf_counter()
    ex = explore(
        p.worlds,
        p.steps,
        seed=p.seed,
        workers=p.workers,
        sensor=sensor,
        agent_radius=p.agent_radius,
        family=p.family,
        progress=lambda k: report("explore", k + 1, p.worlds),
    )
    stages.append(
        {"stage": "explore", "samples": ex.n_samples, "seconds": time.perf_counter() - t0}
    )

    # The contexts: the readings, or the readings with their change (in world order).
    contexts = (
        motion_contexts(ex.readings, previous_in_world(ex.readings, ex.world))
        if p.motion
        else ex.readings
    )
    if ex.n_samples < 2:
        raise InvalidArgumentError(
            f"exploration gave {ex.n_samples} reading(s); the context map needs at least 2: "
            "explore more worlds or steps"
        )
    t0 = time.perf_counter()
    report("context map", 0, 1)
    map_seed = p.seed if p.map_seed is None else p.map_seed
    gng = GrowingNeuralGas(p.max_nodes, epochs=p.epochs, random_state=map_seed).fit(contexts)
    gng.prune_unused(contexts)  # nodes that stand for no context (none on maps of readings)
    # the compiled search, not transform(): its matrix product is BLAS's, summed in an
    # order that depends on the processor
    nearest, d2 = gng._nearest(contexts)
    dist = np.sqrt(d2)
    qe = float(dist.mean())
    # Online, a reading farther than this from every node is "unfamiliar" (§III): the
    # distance that 99 % of the training readings are within.
    familiar = float(np.percentile(dist, 99))
    report("context map", 1, 1)
    stages.append(
        {
            "stage": "context map (GNG)",
            "nodes": len(gng.nodes_),
            "edges": len(gng.edges_),
            "quantization_error": qe,
            "seconds": time.perf_counter() - t0,
        }
    )

    t0 = time.perf_counter()
    report("skeleton", 0, 1)
    wanted, counts = p.landmarks, None
    if wanted is None and p.skeleton_bootstrap > 0:
        wanted, counts = bootstrap_landmarks(
            contexts, resamples=p.skeleton_bootstrap, method=p.skeleton_method, seed=map_seed,
            max_nodes=p.max_nodes, epochs=p.epochs, workers=p.workers,
            progress=lambda k, n: report("skeleton (bootstrap)", k, n),
        )  # fmt: skip
        wanted = int(min(max(wanted, 1), len(gng.nodes_)))
    lm = skeletonize(gng, method=p.skeleton_method, n_landmarks=wanted)
    report("skeleton", 1, 1)
    stage: dict[str, Any] = {"stage": "skeleton", "landmarks": lm.n_landmarks, "k": lm.k}
    if counts is not None:
        stage["bootstrap_median"] = int(np.round(np.median(counts)))
        stage["bootstrap_range"] = [int(min(counts)), int(max(counts))]
    stage["seconds"] = time.perf_counter() - t0
    stages.append(stage)

    t0 = time.perf_counter()
    group = SymmetryGroup.generate(
        block_operators(ring_operators(p.n_rays), context_blocks(p.motion))
    )
    _check_directions(group, p.directions)
    # The paper accepts chi_1 ~ g . chi_2 "or an approximation thereof, as the values may
    # be continuous" (§II-C). Its resolution here is the map's own: a training reading's
    # ray lies within this distance of the same ray of the node that represents it in
    # symmetry_quantile % of cases, so two landmarks agreeing that closely on every ray
    # differ by no more than the map already ignores within one node.
    per_ray = np.abs(contexts - gng.nodes_[nearest])
    tol = (
        p.symmetry_tol
        if p.symmetry_tol is not None
        else float(np.percentile(per_ray, p.symmetry_quantile))
    )
    del per_ray
    sizes = np.bincount(lm.members, minlength=lm.n_landmarks)
    red = reduce_landmarks(lm.points, group, tol=tol, order=np.argsort(-sizes, kind="stable"))
    stages.append(
        {
            "stage": "symmetry",
            "group_elements": len(group),
            "reduced_landmarks": int(len(red.templates)),
            "tolerance": float(tol),
            "seconds": time.perf_counter() - t0,
        }
    )

    t0 = time.perf_counter()
    report("policies", 0, 1)
    learner = (
        AStarLearner(agent_radius=p.agent_radius)
        if p.learner == "astar"
        else ValueIterationLearner(agent_radius=p.agent_radius)
    )
    templates = lm.points[red.templates][:, : p.n_rays]  # the reading block
    policies = learner.learn(templates, p.max_range, p.directions)
    priors = _priors(gng, lm, red, group, ex, contexts, p.directions)
    report("policies", 1, 1)
    stages.append(
        {
            "stage": "policies",
            "learner": learner.name,
            "policies": policies.n_policies,
            "seconds": time.perf_counter() - t0,
        }
    )
    safety = None
    if p.safety:
        t0 = time.perf_counter()
        probes = probe_states(
            tuple(f.strip() for f in p.probe_families.split(",")), p.probe_worlds,
            p.probe_steps, seed=p.seed, n_directions=p.directions, horizon=p.probe_horizon,
            agent_radius=p.agent_radius, sensor=sensor,
            progress=lambda k, n: report("safety probes", k, n), label=p.probe_label,
        )  # fmt: skip
        probed = (
            motion_contexts(probes.readings, probes.previous) if p.motion else probes.readings
        )
        landmark = lm.node_landmark[gng.predict(probed)]
        safety, safety_stats = learn_safety(
            probes, p.directions, red.template_of[landmark],
            group.matrices[red.element[landmark]], len(red.templates), seed=p.seed,
            static_aware=p.safety_static,
        )  # fmt: skip
        stages.append({"stage": "safety", **safety_stats, "seconds": time.perf_counter() - t0})
    model = None
    if p.predict:
        t0 = time.perf_counter()
        model = learn_motion(
            tuple(f.strip() for f in p.probe_families.split(",")), p.predict_worlds,
            p.predict_steps, seed=p.seed, sensor=sensor, agent_radius=p.agent_radius,
            progress=lambda k, n: report("model of what moves", k, n),
        )  # fmt: skip
        stages.append({"stage": "motion model", "examples": model.stats["examples"],
                       "radius": model.radius, "seconds": time.perf_counter() - t0})  # fmt: skip
    return Capabilities(
        nodes=gng.nodes_,
        edges=gng.edges_,
        landmarks=lm,
        group=group,
        reduction=red,
        policies=policies,
        priors=priors,
        safety=safety,
        motion_model=model,
        # without a model of what moves, its settings are left out: the file is then the
        # same, byte for byte, as one learnt before the model existed
        params={k: v for k, v in dataclasses.asdict(p).items()
                if p.predict or k not in ("predict", "predict_worlds", "predict_steps")},
        stats={
            "stages": _jsonable(stages),
            "quantization_error": float(qe),
            "familiarity_threshold": familiar,
            "symmetry_tolerance": float(tol),
        },
    )


def _check_directions(group: SymmetryGroup, n: int) -> None:
    """The compass must be closed under the group's plane actions, so that a policy
    mapped back through g^-1 is again a compass policy."""
    _, dirs = compass(n)
    for m in group.matrices:
        moved = dirs @ m.T
        if not np.all(np.abs(moved @ dirs.T).max(1) > 1 - 1e-9):
            raise InvalidArgumentError(
                f"{n} directions are not closed under the symmetry group; choose 4, 8 or 16 "
                "with quarter-turn and mirror symmetries"
            )


def _priors(gng, lm, red, group, ex, contexts, n_directions) -> ActionPriors:  # type: ignore[no-untyped-def]
    """Action priors from the exploration: the context before each move, mapped to its
    template, and the move turned into the template's frame."""
    same_world = ex.world[1:] == ex.world[:-1]
    before = contexts[:-1][same_world]
    moves = ex.moves[1:][same_world]
    landmark = lm.node_landmark[gng.predict(before)]
    template = red.template_of[landmark]
    mats = group.matrices[red.element[landmark]]
    turned = np.einsum("nij,nj->ni", mats, moves)
    return ActionPriors.from_moves(template, turned, len(red.templates), n_directions)


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.floating):
        return float(x)
    return x

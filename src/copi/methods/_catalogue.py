"""copi's built-in methods: its modes, the baselines, the peers and the bounds, each one
registration (the mechanism is :mod:`copi.methods._registry`; importing
:mod:`copi.methods` registers these once, then seals them against replacement by
accident)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from copi._files import file_sha
from copi.baselines import (
    DWA,
    NAVGROUND_BEHAVIORS,
    VFH,
    CompassGuard,
    NavgroundAgent,
    PPOAgent,
    Replan,
    SARLAgent,
    Straight,
    TangentBug,
    TrackedMPC,
    navground_available,
    packaged_policy,
    packaged_sarl,
)
from copi.bounds import Clairvoyant, ModelOracle
from copi.core import Agent
from copi.methods._registry import REGISTRY, register_method
from copi.online import CopiAgent, LearntAgent, PredictiveAgent

__all__: list[str] = []


def _navground(behavior: str) -> Callable[..., Agent]:
    def make(
        *, safety_margin: float = 0.3, horizon: float = 5.0, time_horizon: float | None = None,
        neighbours: int | None = None,
    ) -> Agent:  # fmt: skip
        return NavgroundAgent(behavior, safety_margin=safety_margin, horizon=horizon,
                              time_horizon=time_horizon, neighbours=neighbours)  # fmt: skip

    make.__name__ = f"navground_{behavior.lower()}"
    return make


_RL_POLICIES = [
    ("ppo", "ppo-mix", 0.0, "a local policy learnt by PPO (deep RL, 2M steps) on all five "
     "families, under the level's global direction; nothing hand-written"),
    ("ppo-guard", "ppo-mix", 1.05, "ppo shielded by compass-guard's hand-written guard"),
    *[(f"ppo-{f}", f"ppo-{f}", 0.0, f"PPO trained on the {f} family only")
      for f in ("star", "polygon", "indoor", "maps", "crowd")],
    ("ppo-chauffeur", "ppo-chauffeur", 0.0, "PPO trained as the evader of the homicidal "
     "chauffeur (Experiment 2), under the game's direction"),
    # the second peer: one policy per level, given what the level gives (docs/rl.md)
    *[(f"ppo-{f}-map", f"ppo-{f}-map", 0.0, f"PPO trained on the {f} family at map, seeing "
       "what copi-learnt sees there (the reading, the hits the static map does not explain, "
       "three readings stacked, its own velocity) under the route's direction; nothing "
       "hand-written") for f in ("star", "polygon", "indoor", "maps", "crowd")],
    *[(f"ppo-guard-{f}-map", f"ppo-{f}-map", 1.05, f"ppo-{f}-map shielded by compass-guard's "
       "hand-written guard") for f in ("star", "polygon", "indoor", "maps", "crowd")],
    # the second peer at level sensor, where it was trained (docs/rl.md)
    *[(f"ppo-{f}-sensor", f"ppo-{f}-sensor", 0.0, f"PPO trained on the {f} family at "
       "sensor, seeing what that level gives (the reading, three stacked, its own velocity) "
       "under the goal's direction; nothing hand-written") for f in ("star", "crowd")],
    # the second algorithm, where it was trained (docs/rl.md)
    *[(f"sac-{f}-map", f"sac-{f}-map", 0.0, f"SAC trained on the {f} family at map, seeing "
       f"what ppo-{f}-map sees (copi-local-v3); nothing hand-written")
      for f in ("star", "crowd")],
    # the imitation warm start (docs/rl.md): PPO from a clone of compass-guard
    *[(f"ppo-il-{f}-map", f"ppo-il-{f}-map", 0.0, f"ppo-{f}-map's training started from a "
       "clone of compass-guard (imitation, then DAgger), then PPO; the network decides "
       "alone (the hand-written method was its teacher, not a filter)")
      for f in ("star", "polygon", "indoor", "maps", "crowd")],
    # the clone (docs/rl.md): no RL, a classifier of compass-guard's moves
    *[(f"clone-{f}-map", f"clone-{f}-map", 0.0, f"a classifier of compass-guard's moves at "
       f"map, learnt from its demonstrations in the {f} family (DAgger; a step along one of "
       "the 32 rays of its frame, or none; no RL): the network decides alone, the step's "
       "length near the goal is compass-guard's rule (hand-written)")
      for f in ("star", "polygon", "indoor", "maps", "crowd")],
    # the second peer trained for the game, at the game's level (docs/rl.md)
    ("ppo-chauffeur-sensor", "ppo-chauffeur-sensor", 0.0, "PPO trained as the evader of the "
     "homicidal chauffeur at the game's level, seeing what ppo-F-sensor sees (the reading, "
     "three stacked, its own velocity) under the game's direction; nothing hand-written"),
    # the curriculum (docs/rl.md): ppo-crowd-map's training from easier worlds to crowds
    ("ppo-cur-crowd-map", "ppo-cur-crowd-map", 0.0, "ppo-crowd-map's training with a "
     "curriculum: its episodes in star worlds to 400k steps, polygon worlds to 1M, then "
     "crowds; nothing hand-written"),
]  # fmt: skip


def _weights_present(weights: str, where: Callable[[str], Path] = packaged_policy
                     ) -> Callable[[], bool]:  # fmt: skip
    return lambda: where(weights).is_file()


def _weights_hash(weights: str, where: Callable[[str], Path] = packaged_policy
                  ) -> Callable[[], dict[str, str]]:  # fmt: skip
    def sha() -> dict[str, str]:
        path = where(weights)
        return {"weights_sha": file_sha(path)} if path.is_file() else {}

    return sha


_SARL = [
    ("sarl", "sarl-crowd", "crowd episodes, imitating model-oracle",
     "--demo-episodes 1000 --il-epochs 26 --rl-episodes 300 --epsilon 0.3,0.05,300"),
    ("sarl-crowdnav", "sarl-circle-crossing", "CrowdNav's circle crossing, imitating "
     "crowdnav-orca (CrowdNav's scenario and demonstrator)",
     "--family circle-crossing --demonstrator crowdnav-orca --demo-episodes 1000 "
     "--il-epochs 26 --rl-episodes 600 --epsilon 0.3,0.05,300"),
]


def _register_builtins() -> None:
    # Every parameter below equals its class's default: tuned by studies/tune.py
    # (validation seed 1, all five families, 40 episodes each, four settings per method;
    # the table is docs/tuning.md). navground's ORCA was not tuned.
    reg = register_method
    reg("copi-faithful", CopiAgent, capabilities="faithful", default=True,
        summary="the paper's chain: learnt contexts, landmarks, symmetry and 4 A* policies "
        "per template; no hand-written avoidance")
    reg("copi-extended", CopiAgent, capabilities="extended", default=True,
        params={"guard": 1.05},
        summary="the chain with 16 policies per template; each candidate checked against the "
        "live reading by a hand-written guard, which escapes when none is safe")
    reg("copi-learnt", LearntAgent, capabilities="learnt", default=True,
        summary="16 compass moves scored by the route and by learnt safety (a network over "
        "the reading turned to each move, trained on counterfactual probes of a task-free "
        "exploration, shared by every direction through the symmetry); compass-guard's "
        "hand-written guard kept as a filter")
    # The learnt preset's ablations: -priors and -persist differ from copi-learnt in one
    # thing each, -motion from -priors in its contexts and its prior weight;
    # compass-guard is copi-learnt with nothing learnt (alpha = beta = 0), its guard
    # tuned on its own. Every weight: docs/tuning.md.
    reg("copi-learnt-priors", LearntAgent, capabilities="learnt", ablation=True,
        params={"beta": 1.0},
        summary="copi-learnt plus the per-template safety priors (contexts of the reading "
        "alone, each move read through the template's symmetry) in each move's score")
    reg("copi-learnt-motion", LearntAgent, capabilities="learnt-motion", ablation=True,
        params={"beta": 0.5},
        summary="copi-learnt-priors with contexts that see motion: context map, landmarks, "
        "templates and their priors over [reading, its change]")
    reg("copi-learnt-persist", LearntAgent, capabilities="learnt", ablation=True,
        params={"persist": 0.05},
        summary="copi-learnt whose last move scores more while the reading stays within its "
        "landmark (policies that last, paper §V)")
    reg("copi-learnt-continual", LearntAgent, capabilities="learnt",
        params={"continual": True},
        summary="copi-learnt growing contexts for unfamiliar readings online (paper §II-A, "
        "§III); in a lifelong run the grown contexts are kept")
    reg("straight", Straight, default=True,
        summary="the global direction, no avoidance (hand-written, nothing tuned)")
    reg("compass-guard", CompassGuard, default=True,
        summary="copi-extended's hand-written guard over 16 compass moves, no capabilities "
        "(ablation of the learnt part)")
    reg("vfh", VFH, default=True,
        summary="Vector Field Histogram (VFH+) on the ranges (hand-written)")
    reg("dwa", DWA, default=True,
        summary="Dynamic Window: sampled velocities scored on the ranges (hand-written)")
    reg("tangent-bug", TangentBug, default=True,
        summary="TangentBug on the ranges (hand-written)")
    # the model-oracle's planner on what a map-level agent makes out (0.3-3 s an episode,
    # so run apart like model-oracle: --methods tracked-mpc)
    # copi's learnt parts carrying the decision: one planning decision costs milliseconds,
    # so run apart like tracked-mpc: --methods copi-predictive
    reg("copi-predictive", PredictiveAgent, capabilities="predictive", sensing="sensor",
        levels=("map",),
        summary="plans its move over futures of what moves drawn from its learnt model "
        "(learnt once from its own task-free walks; the planner is the model-oracle's), each "
        "move also costed by the learnt safety network; no hand-written guard (also at "
        "`sensor`, on the walls it sees and has learnt: copi-predictive@sensor)")
    reg("copi-predictive-contexts", PredictiveAgent, capabilities="predictive", sensing="map",
        ablation=True, params={"beta": 0.5},
        summary="copi-predictive whose moves also cost what the recognised context's template "
        "prior says of them (paper §III)")
    reg("copi-predictive-nonet", PredictiveAgent, capabilities="predictive", sensing="map",
        ablation=True, params={"alpha": 0.0},
        summary="copi-predictive without the learnt safety network: the model of what moves "
        "and the planner alone")
    reg("tracked-mpc", TrackedMPC, sensing="map", default=False,
        summary="model-predictive control (the model-oracle's planner) on the discs it makes "
        "out in its reading (circle fits of the hits the map does not explain, velocities "
        "from their last displacement), their speed and turn spread estimated from its own "
        "tracks (hand-written; nothing learnt offline)")
    reg("replan", Replan, sensing="oracle", default=True,
        summary="shortest path on the current snapshot, obstacles inflated, re-planned "
        "(hand-written; sees every obstacle)")
    # Learnt by deep RL on copi's episodes (copi rl train; the weights ship in
    # copi/data/rl with the commands that trained them). A policy absent is left out.
    for name, weights, guard, summary in _RL_POLICIES:
        reg(name, PPOAgent, default=name in ("ppo", "ppo-guard"), requires="rl-weights",
            sensing="map" if weights.endswith("-map") else "sensor",
            available=_weights_present(weights), inputs=_weights_hash(weights),
            params={"weights": weights, "guard": guard}, summary=summary,
            missing=f"its trained weights {weights}.npz, which copi does not ship here: train "
            f"them with copi rl train{' --algo sac' if name.startswith('sac') else ''} -o "
            f"{weights}.npz (docs: copi against deep RL)")
    # CrowdNav's peer (Chen et al. 2019) at its own level: a value network attending over
    # the discs, one-step lookahead; imitation, then CrowdNav's RL (studies/sarl_train.py).
    # Not in the default run (which predates it): --methods sarl,sarl-crowdnav
    for name, weights, where, how in _SARL:
        reg(name, SARLAgent, sensing="oracle", default=False, requires="rl-weights",
            available=_weights_present(weights, packaged_sarl),
            inputs=_weights_hash(weights, packaged_sarl),
            params={"weights": weights},
            summary="CrowdNav's SARL: a value network attending over the discs (positions and "
            "velocities known) with the static reading, each of 81 moves scored by its "
            f"step's reward and the value one step on; trained on {where}, then CrowdNav's "
            "RL (learnt; the reward and the lookahead hand-written)",
            missing=f"its trained weights {weights}.npz, which copi does not ship here: "
            f"train them with python studies/sarl_train.py {how} --install (docs: copi "
            "against deep RL)")
    # Bounds, not methods: what is possible (marked so in every table and figure).
    reg("clairvoyant", Clairvoyant, sensing="future", default=True, bound=True,
        summary="a bound: space-time A* on the obstacles' recorded future (they ignore the "
        "agent), its plan replayed through the simulator: the share of episodes solvable")
    # model-oracle costs 0.1-0.3 s an episode (median; up to 3 s): not in the default run; run it
    # on fewer episodes into the same directory, the report pairs it on those.
    # Not a bound: methods that know less match it in four families of five (docs/ceilings.md)
    reg("model-oracle", ModelOracle, sensing="oracle", default=False,
        summary="a reference planner, not a bound: model-predictive control on 32 sampled "
        "futures of the obstacles' random walk (its true parameters), each solved in hindsight "
        "and the costs averaged, replanned every step; knows the present and the motion model, "
        "not the future (hand-written, tuned on seed 1; 0.1-0.3 s an episode, up to 3, so run "
        "apart: --methods model-oracle)")
    margins = {"navground-hrvo": 0.6, "navground-hl": 0.3, "navground-orca": 0.3}
    for name, behavior in NAVGROUND_BEHAVIORS.items():
        reg(name, _navground(behavior), sensing="oracle", requires="peers",
            available=navground_available, default=name != "navground-orca",
            missing="navground, which is not installed: pip install 'copi[peers]'",
            params={"safety_margin": margins[name]},
            summary=f"navground's {behavior} (sees obstacle positions and velocities)")
    # CrowdNav's robot ORCA (its test.py: time horizon 5 s, 10 neighbours within 10 m, no
    # safety space but every radius 0.01 m larger: 0.02 m between two agents, navground's
    # margin being added once to the sum of radii), in the units of its scenarios (a step
    # of 0.25 m; navground's neighbour distance is twice its horizon): the check that
    # copi's circle crossing is CrowdNav's
    reg("crowdnav-orca", _navground("ORCA"), sensing="oracle", requires="peers",
        available=navground_available,
        missing="navground, which is not installed: pip install 'copi[peers]'",
        params={"safety_margin": 0.08, "horizon": 20.0, "time_horizon": 20.0, "neighbours": 10},
        summary="navground's ORCA as CrowdNav's robot (its settings in CrowdNav's units: a time "
        "horizon of 5 s, 10 neighbours within 10 m, radii 0.01 m larger); for the CrowdNav "
        "families")


_register_builtins()
REGISTRY.seal()

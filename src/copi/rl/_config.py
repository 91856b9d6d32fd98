"""The configuration of a training run (:mod:`copi.rl._train`), PPO's or SAC's: every
field decides the policy it learns, and each is checked before anything is trained."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from copi.baselines import MAX_LAYERS, MAX_WIDTH, OBSERVATION_V3, check_layout
from copi.envs.local_policy import EPISODES_PER_FAMILY, MAX_POOL, Reward
from copi.errors import InvalidArgumentError
from copi.world import check_family

__all__ = ["ALGORITHMS", "MAX_SEED", "TrainConfig"]

MAX_SEED = 2**32 - 1
ALGORITHMS = ("ppo", "sac", "clone")
"""Stable-Baselines3's PPO (on-policy, a Gaussian policy) and SAC (off-policy, a
squashed Gaussian, its entropy tuned to a target)."""
_SAC_ONLY = ("buffer_size", "learning_starts", "gradient_steps", "tau")
_PPO_ONLY = ("n_steps", "n_epochs", "ent_coef", "log_std")
_NOT_CLONE = ("steps", "envs", "learning_rate", "batch_size", "gamma", "normalize_reward",
              "reward")
"""What no clone uses: it learns from its demonstrator's moves alone (Adam at 1e-3 in
batches of 256, as the warm start's clone), no reward, no RL steps."""
_IMITATION = ("imitate", "imitation_episodes", "dagger_rounds", "imitation_epochs")
_CHECKPOINT_BYTES = 1 << 31
"""The most a checkpoint's tensors may weigh (its reader's limit)."""


@dataclass(frozen=True)
class TrainConfig:
    """One training run; every field decides the policy it learns."""

    families: tuple[str, ...] = ("star", "polygon", "indoor", "maps", "crowd")
    """World families of the training episodes (a mix: one drawn per episode)."""
    levels: tuple[str, ...] = ("map",)
    """Sensing levels of the episodes: one for a ``copi-local-v3`` policy (it sees that
    level's reading; the first peer, ``copi-local-v2``, mixed sensor and map)."""
    task: str = "navigation"
    """"navigation" or "chauffeur" (the evader of Experiment 2's game)."""
    algorithm: str = "ppo"
    """"ppo", "sac" or "clone" (:data:`ALGORITHMS`): the last no RL at all, a classifier
    of ``imitate``'s moves (DAgger; a ``compass`` policy, :mod:`copi.rl._imitate`)."""
    steps: int = 2_000_000
    """Environment steps of training."""
    seed: int = 0
    """Seed of the network, the optimiser and the episodes' order (the episodes themselves
    are those of the training seed, copi.rl.TRAINING_SEED)."""
    envs: int = 8
    """Environments stepped together (a vectorised environment in this process)."""
    learning_rate: float = 3e-4
    """The defaults from here to ``reward``: the setting chosen on validation seed 1 among
    those docs/rl.md lists (``studies/rl_train_all.py --tune``; the first peer's were lr 1e-3,
    n_steps 256, batch 256, ent 0, log_std -1, net 64-64, no proximity penalty, the
    reward raw)."""
    n_steps: int = 512
    """PPO: steps per environment between updates."""
    batch_size: int = 512
    """Transitions per gradient step (PPO's minibatch, SAC's sample of its buffer)."""
    n_epochs: int = 10
    """PPO: passes over each rollout."""
    gamma: float = 0.99
    ent_coef: float = 0.005
    """PPO's entropy bonus (SAC tunes its own coefficient to a target entropy)."""
    log_std: float = -0.5
    """PPO: the policy's initial log standard deviation of its actions (exploration
    noise; SAC's actor learns its own from the first step)."""
    buffer_size: int = 100_000
    """SAC: transitions its replay buffer keeps (checkpointed whole)."""
    learning_starts: int = 10_000
    """SAC: steps of random actions before it learns."""
    gradient_steps: int = 1
    """SAC: gradient steps after each step of the ``envs`` environments."""
    tau: float = 0.005
    """SAC: how fast its target critics follow (Polyak)."""
    net: tuple[int, ...] = (128, 128)
    """Hidden layers of the actor (and, apart, of the critic)."""
    reward: Reward = field(default_factory=lambda: Reward(proximity=0.5))
    max_steps: int = 500
    observation: str = OBSERVATION_V3
    """What the policy sees (:mod:`copi.baselines._ppo`): ``copi-local-v3`` is one level's
    reading, ``frames`` readings stacked, and needs one level."""
    frames: int = 3
    """Readings a ``copi-local-v3`` observation stacks."""
    normalize_reward: bool = True
    """Scale the reward by the running spread of its discounted return (SB3's
    VecNormalize, the observation left raw); the first peer trained without."""
    episodes: int = EPISODES_PER_FAMILY
    """A family's pool of training episodes (:class:`copi.envs.LocalPolicyEnv`'s
    ``episodes``), for the demonstrations and for PPO."""
    imitate: str = ""
    """PPO: a registered method whose moves the policy clones before PPO starts (an
    imitation warm start, :mod:`copi.rl._imitate`; "" none). It runs at the policy's
    level and needs no capabilities file."""
    imitation_episodes: int = 2000
    """Episodes the demonstrator drives (DAgger's first round); each later round, half
    as many driven by the policy cloned so far."""
    dagger_rounds: int = 2
    """Rounds of DAgger after the first."""
    imitation_epochs: int = 30
    """Passes over the demonstrations at each round."""
    curriculum: tuple[tuple[str, int], ...] = ()
    """PPO or SAC: stages before ``families``, each (a family, the step it ends at), in
    order: the episodes are the first stage's family until its step, then the next's, and
    from the last stage's step to the end ``families``' (a curriculum, e.g. star worlds,
    then polygon worlds, then crowds). A stage changes between rollouts, at the first one
    that starts at or after its step (PPO's rollouts are ``envs`` x ``n_steps`` steps);
    an episode under way goes on in its world. Validation is on ``families`` throughout:
    the curve shows the target's success. () none."""

    def __post_init__(self) -> None:
        if self.algorithm not in ALGORITHMS:
            raise InvalidArgumentError(f"algorithm must be one of {', '.join(ALGORITHMS)}; "
                                       f"got {self.algorithm!r}")  # fmt: skip
        for f in self.families:
            check_family(f)
        if self.task not in ("navigation", "chauffeur"):
            raise InvalidArgumentError(f"task must be navigation or chauffeur; got {self.task!r}")
        for key in ("steps", "envs", "n_steps", "batch_size", "n_epochs", "max_steps",
                    "buffer_size", "gradient_steps"):  # fmt: skip
            v = getattr(self, key)
            # a plain int: int(v) of a string, NaN or infinity would raise an error of its
            # own, and a numpy int would not go into the checkpoint's JSON
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise InvalidArgumentError(f"{key} must be a positive int; got {v!r}")
        if isinstance(self.seed, bool) or not (isinstance(self.seed, int)
                                               and 0 <= self.seed <= MAX_SEED):
            raise InvalidArgumentError(f"seed must be an int in 0 .. {MAX_SEED:,} (the range "
                                       f"of the generators PPO seeds); got {self.seed!r}")
        if self.steps > 10**9:
            raise InvalidArgumentError(f"steps must be at most 1,000,000,000; got {self.steps:,}")
        if not 1 <= self.envs <= 256:
            raise InvalidArgumentError(f"envs must be in 1 .. 256; got {self.envs}")
        if not (isinstance(self.learning_starts, int) and not isinstance(self.learning_starts, bool)
                and 0 <= self.learning_starts <= 10**9):  # fmt: skip
            raise InvalidArgumentError(f"learning_starts must be an int >= 0; got "
                                       f"{self.learning_starts!r}")  # fmt: skip
        if self.buffer_size > 10_000_000:
            raise InvalidArgumentError(
                f"buffer_size must be at most 10,000,000 (a checkpoint holds the whole "
                f"buffer); got {self.buffer_size:,}"
            )
        if self.algorithm == "sac" and self.buffer_size < self.envs:
            raise InvalidArgumentError(f"buffer_size must be at least envs ({self.envs}): a "
                                       f"row a step of each; got {self.buffer_size:,}")  # fmt: skip
        for key in ("learning_rate", "gamma", "ent_coef", "tau"):
            v = getattr(self, key)
            if not (isinstance(v, int | float) and math.isfinite(v) and 0 <= v <= 1):
                raise InvalidArgumentError(f"{key} must be a number in [0, 1]; got {v!r}")
        if not (isinstance(self.log_std, int | float) and -5 <= self.log_std <= 2):
            raise InvalidArgumentError(f"log_std must be a number in [-5, 2]; got {self.log_std!r}")
        most = MAX_LAYERS - 1  # the action layer is the policy file's last
        if not (1 <= len(self.net) <= most) or not all(
            isinstance(h, int) and not isinstance(h, bool) and 1 <= h <= MAX_WIDTH
            for h in self.net
        ):
            raise InvalidArgumentError(f"net must be 1 to {most} layer widths in 1 .. "
                                       f"{MAX_WIDTH}; got {self.net!r}")  # fmt: skip
        v = self.episodes
        if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= MAX_POOL:
            raise InvalidArgumentError(f"episodes must be an int in 1 .. {MAX_POOL:,} (a family's "
                                       f"pool of training episodes); got {v!r}")  # fmt: skip
        if not isinstance(self.imitate, str):
            raise InvalidArgumentError(f"imitate must be a method's name; got {self.imitate!r}")
        if self.algorithm == "clone" and not self.imitate:
            raise InvalidArgumentError("a clone needs the method it imitates (imitate, "
                                       "--imitate METHOD)")  # fmt: skip
        if self.imitate:
            if self.algorithm not in ("ppo", "clone") or self.task != "navigation" \
                    or len(self.levels) != 1:  # fmt: skip
                raise InvalidArgumentError(
                    "imitate needs PPO or a clone on navigation episodes at one level; got "
                    f"{self.algorithm} on {self.task} at {', '.join(self.levels)}"
                )
            for key in ("imitation_episodes", "imitation_epochs"):
                v = getattr(self, key)
                if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 100_000:
                    raise InvalidArgumentError(f"{key} must be an int in 1 .. 100,000; got {v!r}")
            v = self.dagger_rounds
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 100:
                raise InvalidArgumentError(f"dagger_rounds must be an int in 0 .. 100; got {v!r}")
        if not isinstance(self.normalize_reward, bool):
            raise InvalidArgumentError("normalize_reward must be True or False; got "
                                       f"{self.normalize_reward!r}")  # fmt: skip
        if not self.families or not self.levels:
            raise InvalidArgumentError("families and levels must each name at least one; got "
                                       f"families {self.families!r}, levels {self.levels!r}")
        # the first peer's chauffeur evader was learnt at map whatever the levels said
        check_layout(self.observation, self.frames,
                     self.levels if self.task == "navigation" or self.observation == OBSERVATION_V3
                     else None)  # fmt: skip
        if self.algorithm == "sac":
            from copi.baselines import observation_size

            level = self.levels[0]  # the first peer's size is the same at every level
            # the observations twice (this one and the next) in float32, and the rest
            per = 8 * observation_size(32, self.observation, level, self.frames) + 64
            if per * self.buffer_size > _CHECKPOINT_BYTES * 0.9:
                most = int(_CHECKPOINT_BYTES * 0.9 // per)
                raise InvalidArgumentError(
                    f"buffer_size must be at most {most:,} for this observation (a "
                    f"checkpoint holds the whole buffer, {per:,} bytes a transition, and "
                    f"is at most 2 GiB); got {self.buffer_size:,}"
                )
        self._check_curriculum()

    def _check_curriculum(self) -> None:
        if not self.curriculum:
            return
        if self.algorithm == "clone" or self.imitate or self.task != "navigation":
            raise InvalidArgumentError(
                "a curriculum needs PPO or SAC on navigation episodes without --imitate; got "
                f"{self.algorithm}{' imitating ' + self.imitate if self.imitate else ''} on "
                f"{self.task}"
            )
        last = 0
        stages = []
        for stage in self.curriculum:
            if not (isinstance(stage, tuple | list) and len(stage) == 2
                    and isinstance(stage[0], str) and isinstance(stage[1], int)
                    and not isinstance(stage[1], bool)):  # fmt: skip
                raise InvalidArgumentError("a curriculum's stage must be (family, the step it "
                                           f"ends at); got {stage!r}")  # fmt: skip
            stage = (stage[0], stage[1])
            stages.append(stage)
            check_family(stage[0])
            if not last < stage[1] < self.steps:
                raise InvalidArgumentError(
                    f"a curriculum's stages must end at increasing steps, each above the "
                    f"last ({last:,}) and below steps ({self.steps:,}); got {stage[1]:,} "
                    f"for {stage[0]}"
                )
            last = stage[1]
        # as a tuple of tuples whatever it came as (a policy's info keeps lists): hashable,
        # and equal to the same stages given either way
        object.__setattr__(self, "curriculum", tuple(stages))

    def families_at(self, steps: int) -> tuple[str, ...]:
        """The families of the training episodes after ``steps`` environment steps (the
        curriculum's stage, or ``families`` past it)."""
        for family, end in self.curriculum:
            if steps < end:
                return (family,)
        return self.families

    @property
    def rollout(self) -> int:
        """Environment steps between two updates: PPO trains in whole rollouts, SAC after
        each step of its environments."""
        return self.envs * (self.n_steps if self.algorithm == "ppo" else 1)

    def updates(self, steps: int) -> int:
        """Gradient updates after ``steps`` (whole rollouts): PPO's ``n_epochs`` a rollout
        (no target_kl to stop it early); SAC's ``gradient_steps`` after each step of its
        environments once past ``learning_starts``."""
        if self.algorithm == "ppo":
            return steps // self.rollout * self.n_epochs
        learnt = steps // self.envs - self.learning_starts // self.envs
        return self.gradient_steps * max(0, learnt)

    @property
    def planned_steps(self) -> int:
        """The steps a run takes: ``steps`` rounded up to whole rollouts."""
        return -(-self.steps // self.rollout) * self.rollout

    def identity(self) -> dict[str, Any]:
        """Every field that decides the run (JSON-able): a PPO run's without SAC's fields,
        as it was before SAC came (its checkpoints and policies keep their identity), a
        SAC run's without PPO's."""
        d = dataclasses.asdict(self)
        d["net"] = list(self.net)
        drop = {"ppo": ("algorithm", *_SAC_ONLY), "sac": _PPO_ONLY,
                "clone": (*_PPO_ONLY, *_SAC_ONLY, *_NOT_CLONE)}[self.algorithm]  # fmt: skip
        for key in drop:
            del d[key]
        if not self.imitate:  # as it was before the warm start came
            for key in _IMITATION:
                del d[key]
        if self.episodes == EPISODES_PER_FAMILY:  # as it was before the pool could be chosen
            del d["episodes"]
        if self.curriculum:
            d["curriculum"] = [list(stage) for stage in self.curriculum]
        else:  # as it was before curricula came
            del d["curriculum"]
        return d



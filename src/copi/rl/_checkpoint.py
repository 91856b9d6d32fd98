"""Checkpoints of a PPO or SAC training run (:mod:`copi.rl._train`): what resumes a run
exactly as it would have gone on (SAC's: its replay buffer and entropy coefficient too),
written whole (Ctrl-C held back meanwhile), and every field of one checked against the
run's own configuration before it is trusted."""

from __future__ import annotations

import hashlib
import json
import math
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import regular_file, write_text
from copi.errors import InvalidArgumentError
from copi.rl._config import TrainConfig

__all__ = ["CHECKPOINT_FILES", "check_apart"]


def _beside(out: Path) -> tuple[Path, Path]:
    """The learning curve and its figure written beside the policy ``out``."""
    return out.with_suffix(".json"), out.with_suffix(".png")


CHECKPOINT_FILES = ("last.pt", "last.json", "last.pt.tmp", "best.npz")
"""The files a checkpoints directory holds (``last.pt.tmp``: while ``last.pt`` is written;
``best.npz``: the policy of the best validation so far)."""


def check_apart(output: str | os.PathLike[str],
                checkpoints: str | os.PathLike[str] | None) -> None:  # fmt: skip
    """Refuse, before anything is trained or written, a policy ``output`` any of whose
    files (the ``.npz``, the learning curve's ``.json`` and ``.png`` beside it) would be
    one of the ``checkpoints`` directory's files: writing it would overwrite the
    checkpoint (``-o DIR/last.npz --checkpoints DIR`` writes the curve over
    ``DIR/last.json``)."""
    if checkpoints is None:
        return
    out = Path(output)
    # resolved, so that another spelling of the same directory (a symlink, "..") is seen
    ckpt = Path(os.path.realpath(checkpoints))
    taken = {ckpt / name for name in CHECKPOINT_FILES}
    for path in (out, *_beside(out)):
        if Path(os.path.realpath(path)) in taken:
            raise InvalidArgumentError(
                f"{path} would overwrite the checkpoint file {path.name} in {checkpoints}; "
                "give the policy another name or another --checkpoints directory"
            )


# -- checkpoints: what resumes a run exactly as it would have gone on --------------------


@contextmanager
def _whole() -> Iterator[None]:
    """Ctrl-C held back while the block runs, then raised: a checkpoint is two files, and
    one replaced without the other would resume a run that never was."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    before = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        # None: a handler not installed from Python, which cannot be put back
        signal.signal(signal.SIGINT, before if before is not None else signal.default_int_handler)
    if caught:
        raise KeyboardInterrupt


def _write_checkpoint(ckpt: Path, model: Any, vec: Any, config: TrainConfig,
                      curve: list[dict[str, float]], seconds: float,
                      norm: Any = None) -> None:  # fmt: skip
    """Everything the run's future depends on, between two rollouts: the weights and the
    optimiser's state, every random generator (torch's, numpy's, Python's), and each
    environment's state (:meth:`LocalPolicyEnv.state`), as tensors (``last.pt``, read
    with ``weights_only``) and JSON (``last.json``, which holds ``last.pt``'s digest);
    nothing pickled."""
    import io
    import random

    import torch

    envs = [e.state() for e in vec.envs]
    sac: dict[str, Any] = {}
    if config.algorithm == "sac":
        rb = model.replay_buffer
        n = rb.buffer_size if rb.full else rb.pos  # the rows written so far
        sac = {"log_ent_coef": model.log_ent_coef.detach().clone(),
               **{f"rb_{k}": torch.from_numpy(np.ascontiguousarray(getattr(rb, k)[:n]))
                  for k in _BUFFER}}  # fmt: skip
    tensors = {
        "params": model.get_parameters(),
        "torch_rng": torch.get_rng_state(),
        "last_obs": torch.from_numpy(np.asarray(model._last_obs, dtype=np.float32).copy()),
        "episode_starts": torch.from_numpy(np.asarray(model._last_episode_starts,
                                                      dtype=np.float32).copy()),  # fmt: skip
        **{f"actions{i}": torch.from_numpy(s["actions"]) for i, s in enumerate(envs)},
        **sac,
    }
    buffer = io.BytesIO()
    torch.save(tensors, buffer)
    data = buffer.getvalue()
    kind, key, pos, has_gauss, cached = np.random.get_state()
    meta = {
        "config": config.identity(), "steps": int(model.num_timesteps),
        "updates": int(model._n_updates), "curve": curve, "seconds": seconds,
        "numpy_rng": [kind, np.asarray(key).tolist(), int(pos), int(has_gauss), float(cached)],
        "python_rng": json.loads(json.dumps(random.getstate())),
        "envs": [{"drawn_from": s["drawn_from"], "ended": s["ended"],
                  "drawn_families": s["drawn_families"]} for s in envs],
        "last_pt_sha256": hashlib.sha256(data).hexdigest(),
    }
    if config.algorithm == "sac":  # where the buffer writes next; the warm-up's generator
        meta["buffer"] = {"pos": int(model.replay_buffer.pos),
                          "full": bool(model.replay_buffer.full)}  # fmt: skip
        meta["action_rng"] = _json_state(model.action_space.np_random.bit_generator.state)
    if norm is not None:  # the reward's running scale (VecNormalize), as plain numbers
        meta["reward_norm"] = {"mean": float(norm.ret_rms.mean), "var": float(norm.ret_rms.var),
                               "count": float(norm.ret_rms.count),
                               "returns": [float(r) for r in norm.returns]}  # fmt: skip
    (ckpt / "last.pt.tmp").write_bytes(data)
    os.replace(ckpt / "last.pt.tmp", ckpt / "last.pt")
    write_text(ckpt / "last.json", json.dumps(meta), "json")


_BUFFER = ("observations", "next_observations", "actions", "rewards", "dones", "timeouts")
"""SAC's replay buffer's arrays (Stable-Baselines3's ``ReplayBuffer``), checkpointed as
far as they are written."""


def _json_state(state: dict[str, Any]) -> dict[str, Any]:
    return json.loads(json.dumps(state))


def _is_pcg64(drawn: Any) -> bool:
    """Whether ``drawn`` is a PCG64 generator's state (``bit_generator.state``)."""
    state = drawn.get("state") if isinstance(drawn, dict) else None
    return (isinstance(drawn, dict)
            and set(drawn) == {"bit_generator", "state", "has_uint32", "uinteger"}
            and drawn["bit_generator"] == "PCG64" and isinstance(state, dict)
            and set(state) == {"state", "inc"}
            and all(_is_int(v, 0, 2**128 - 1) for v in state.values())
            and _is_int(drawn["has_uint32"], 0, 1)
            and _is_int(drawn["uinteger"], 0, 2**32 - 1))  # fmt: skip


def _bad(ckpt: Path, what: str) -> InvalidArgumentError:
    return InvalidArgumentError(f"{ckpt}: not a checkpoint of this training run ({what}); "
                                "use another --checkpoints directory")  # fmt: skip


YEAR = 365 * 24 * 3600
"""The longest wall time a checkpoint may claim, in seconds."""
_DIGITS = 40
"""The most digits of an integer in a checkpoint's JSON (a PCG64 state has 39)."""
_MISSING = object()


@dataclass(frozen=True)
class _Long:
    """An integer of ``digits`` digits in a checkpoint's JSON, longer than any of its
    fields: kept as this marker, so that the field it sits in can be named (``int()`` of
    it would fail, or take seconds, inside ``json.loads``)."""

    digits: int


def _parse_int(text: str) -> int | _Long:
    return _Long(len(text.lstrip("-"))) if len(text) > _DIGITS else int(text)


def _first_long(value: Any) -> tuple[str, _Long] | None:
    """Where in ``value`` (JSON) the first :class:`_Long` is, as a path like
    ``curve[2].steps``; iterative, since the JSON may nest as deep as its parser allows."""
    stack: list[tuple[str, Any]] = [("", value)]
    while stack:
        path, v = stack.pop()
        if isinstance(v, _Long):
            return path, v
        if isinstance(v, dict):
            stack.extend((f"{path}.{k}" if path else str(k), w) for k, w in
                         reversed(list(v.items())))  # fmt: skip
        elif isinstance(v, list):
            stack.extend((f"{path}[{k}]", w) for k, w in reversed(list(enumerate(v))))
    return None


def _show(value: Any) -> str:
    if value is _MISSING:
        return "missing"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _is_int(value: Any, low: int, high: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and low <= value <= high


def _is_real(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and \
        math.isfinite(value)  # fmt: skip


def _check_meta(ckpt: Path, meta: dict[str, Any], config: TrainConfig) -> None:
    """Every field of ``last.json`` against what the run's ``config`` implies; one line
    naming the field that is not."""

    def refuse(name: str, value: Any, expected: str) -> InvalidArgumentError:
        return _bad(ckpt, f"last.json's {name} is {_show(value)}; expected {expected}")

    rollout, planned = config.rollout, config.planned_steps
    steps = meta.get("steps", _MISSING)
    # PPO trains in whole rollouts: a checkpoint is taken between two
    if not (_is_int(steps, rollout, planned) and steps % rollout == 0):
        how = f"{config.envs} envs x {config.n_steps}" if config.algorithm == "ppo" \
            else f"a step of {config.envs} envs"  # fmt: skip
        raise refuse("steps", steps, f"a whole number of rollouts of {rollout:,} steps "
                     f"({how}), at most the run's {planned:,}")  # fmt: skip
    saved_steps = meta["config"].get("steps", _MISSING)
    if not _is_int(saved_steps, 1, 10**9):
        raise refuse("config.steps", saved_steps, "the steps of a run, 1 .. 1,000,000,000")
    updates = meta.get("updates", _MISSING)
    want = config.updates(steps)
    if not _is_int(updates, want, want):
        how = (f"{steps // rollout:,} rollouts of {config.n_epochs} epochs"
               if config.algorithm == "ppo" else
               f"{config.gradient_steps} a step of the environments past "
               f"{config.learning_starts:,}")  # fmt: skip
        raise refuse("updates", updates, f"{want:,} ({how})")
    if config.algorithm == "sac":
        buf = meta.get("buffer", _MISSING)
        rows = config.buffer_size // config.envs  # the buffer's rows of one step each
        written = steps // config.envs
        if not (isinstance(buf, dict) and set(buf) == {"pos", "full"}
                and isinstance(buf["full"], bool) and _is_int(buf["pos"], 0, rows - 1)
                and buf["full"] == (written >= rows) and buf["pos"] == written % rows):  # fmt: skip
            raise refuse("buffer", buf, f"where a buffer of {rows:,} rows writes after "
                         f"{written:,} steps of the environments")  # fmt: skip
        if not _is_pcg64(meta.get("action_rng", _MISSING)):
            raise refuse("action_rng", meta.get("action_rng", _MISSING),
                         "a PCG64 generator's state")  # fmt: skip
    seconds = meta.get("seconds", _MISSING)
    if not (_is_real(seconds) and 0 <= seconds <= YEAR):
        raise refuse("seconds", seconds, f"a wall time in 0 .. {YEAR:,} s (a year)")
    curve = meta.get("curve", _MISSING)
    # a warm-started run's first point is its clone's, before any step of PPO
    cloned = bool(config.imitate)
    if not (isinstance(curve, list) and 1 <= len(curve) <= steps // rollout + cloned):
        raise refuse("curve", curve, f"a learning curve of 1 to {steps // rollout + cloned:,} "
                     "points, one at most per rollout")  # fmt: skip
    last_steps, last_seconds = -1 if cloned else 0, 0.0
    for i, point in enumerate(curve):
        if not (isinstance(point, dict) and set(point) == {"steps", "seconds", "success"}):
            raise refuse(f"curve[{i}]", point, "a point of steps, seconds and success")
        at, spent, success = point["steps"], point["seconds"], point["success"]
        if not (_is_int(at, last_steps + 1, steps) and at % rollout == 0):
            raise refuse(f"curve[{i}].steps", at, f"a whole number of rollouts of {rollout:,} "
                         f"steps, more than the point before's {last_steps:,} and at most "
                         f"the checkpoint's {steps:,}")  # fmt: skip
        # rounded to 0.1 s when recorded, the wall time then unrounded
        if not (_is_real(spent) and last_seconds <= spent <= seconds + 0.1):
            raise refuse(f"curve[{i}].seconds", spent, f"a wall time in {last_seconds:,} .. "
                         f"{seconds:,.1f} s (the point before's to the checkpoint's)")  # fmt: skip
        # NaN: no validation episode could be drawn (validation_success)
        if not (isinstance(success, float) and math.isnan(success)) and not (
            _is_real(success) and 0 <= success <= 1
        ):
            raise refuse(f"curve[{i}].success", success, "a fraction of episodes in [0, 1]")
        last_steps, last_seconds = at, spent
    if last_steps != steps:
        raise refuse(f"curve[{len(curve) - 1}].steps", last_steps,
                     f"the checkpoint's steps, {steps:,}")  # fmt: skip
    envs = meta.get("envs", _MISSING)
    if not (isinstance(envs, list) and len(envs) == config.envs):
        raise refuse("envs", envs, f"the states of the run's {config.envs} environments")
    for i, env in enumerate(envs):
        drawn = env.get("drawn_from", _MISSING) if isinstance(env, dict) else _MISSING
        if not _is_pcg64(drawn):
            raise refuse(f"envs[{i}].drawn_from", drawn, "a PCG64 generator's state")
        ended = env.get("ended", _MISSING)
        if ended not in (None, "terminated", "truncated"):
            raise refuse(f"envs[{i}].ended", ended, "null, terminated or truncated")
    numpy_rng = meta.get("numpy_rng", _MISSING)
    if not (isinstance(numpy_rng, list) and len(numpy_rng) == 5
            and numpy_rng[0] == "MT19937" and isinstance(numpy_rng[1], list)
            and len(numpy_rng[1]) == 624
            and all(_is_int(v, 0, 2**32 - 1) for v in numpy_rng[1])
            and _is_int(numpy_rng[2], 0, 624) and _is_int(numpy_rng[3], 0, 1)
            and _is_real(numpy_rng[4])):  # fmt: skip
        raise refuse("numpy_rng", numpy_rng, "numpy's MT19937 state (numpy.random.get_state)")
    python_rng = meta.get("python_rng", _MISSING)
    if not (isinstance(python_rng, list) and len(python_rng) == 3 and _is_int(python_rng[0], 3, 3)
            and isinstance(python_rng[1], list) and len(python_rng[1]) == 625
            and all(_is_int(v, 0, 2**32 - 1) for v in python_rng[1][:-1])
            and _is_int(python_rng[1][-1], 0, 624)
            and (python_rng[2] is None or _is_real(python_rng[2]))):  # fmt: skip
        raise refuse("python_rng", python_rng, "Python's random state (random.getstate)")
    if config.normalize_reward:
        norm = meta.get("reward_norm", _MISSING)
        if not (isinstance(norm, dict) and set(norm) == {"mean", "var", "count", "returns"}
                and _is_real(norm["mean"]) and _is_real(norm["var"]) and norm["var"] >= 0
                and _is_real(norm["count"]) and norm["count"] > 0
                and isinstance(norm["returns"], list) and len(norm["returns"]) == config.envs
                and all(_is_real(r) for r in norm["returns"])):  # fmt: skip
            raise refuse("reward_norm", norm, "the reward's running mean, variance (>= 0), "
                         f"count (> 0) and the {config.envs} environments' returns")  # fmt: skip
    digest = meta.get("last_pt_sha256", _MISSING)
    # absent from the checkpoints of copi before it was recorded
    if digest is not _MISSING and not (
        isinstance(digest, str) and len(digest) == 64
        and all(c in "0123456789abcdef" for c in digest)
    ):  # fmt: skip
        raise refuse("last_pt_sha256", digest, "a SHA-256 digest of last.pt (64 hex digits)")


def _read_checkpoint(ckpt: Path, config: TrainConfig) -> dict[str, Any] | None:
    """The checkpoint in ``ckpt`` of this run (None when there is none), every part
    checked: one clear line for a file that is not one, or of another run."""
    import torch

    state, meta_path = ckpt / "last.pt", ckpt / "last.json"
    if not state.exists() and not meta_path.exists():
        return None
    for path in (state, meta_path):
        regular_file(path, "checkpoint file", InvalidArgumentError)
    if meta_path.stat().st_size > 1 << 26 or state.stat().st_size > 1 << 31:
        raise _bad(ckpt, "a file larger than a checkpoint holds")
    try:
        meta = json.loads(meta_path.read_text(encoding="utf-8"), parse_int=_parse_int)
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise _bad(ckpt, f"last.json is not JSON: {exc}") from None
    if not isinstance(meta, dict):
        raise _bad(ckpt, "last.json is not an object")
    long = _first_long(meta)
    if long is not None:
        raise _bad(ckpt, f"last.json's {long[0]} is an integer of {long[1].digits:,} digits; "
                   f"expected at most {_DIGITS}")  # fmt: skip
    same = {k: v for k, v in json.loads(json.dumps(config.identity())).items() if k != "steps"}
    saved = meta.get("config")
    if not isinstance(saved, dict) or {k: v for k, v in saved.items() if k != "steps"} != same:
        raise InvalidArgumentError(
            f"{ckpt} holds checkpoints of another training run; use another directory"
        )
    _check_meta(ckpt, meta, config)
    digest = meta.get("last_pt_sha256")
    if digest is not None:
        h = hashlib.sha256()
        with open(state, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
        if h.hexdigest() != digest:
            raise _bad(ckpt, "last.pt is not the file last.json was written with")
    try:
        tensors = torch.load(state, weights_only=True, map_location="cpu")
    except Exception as exc:  # torch raises many kinds for a file that is not one
        raise _bad(ckpt, f"last.pt cannot be read: {type(exc).__name__}") from None
    need = {"params", "torch_rng", "last_obs", "episode_starts",
            *(f"actions{i}" for i in range(config.envs))}  # fmt: skip
    if config.algorithm == "sac":
        need |= {"log_ent_coef", *(f"rb_{k}" for k in _BUFFER)}
    if not isinstance(tensors, dict) or not need <= set(tensors):
        raise _bad(ckpt, "last.pt lacks parts of a checkpoint")
    if config.algorithm == "sac":
        buf = meta["buffer"]
        n = config.buffer_size // config.envs if buf["full"] else buf["pos"]
        for k in _BUFFER:
            t = tensors[f"rb_{k}"]
            if not (isinstance(t, torch.Tensor) and t.ndim >= 2
                    and tuple(t.shape[:2]) == (n, config.envs)):  # fmt: skip
                raise _bad(ckpt, f"last.pt's replay buffer {k} is not {n:,} rows of "
                           f"{config.envs} environments")  # fmt: skip

    def finite(value: Any, name: str) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                finite(v, f"{name}.{k}")
        elif isinstance(value, list | tuple):
            for k, v in enumerate(value):
                finite(v, f"{name}[{k}]")
        elif isinstance(value, torch.Tensor) and value.is_floating_point() and \
                not bool(torch.isfinite(value).all()):  # fmt: skip
            raise _bad(ckpt, f"{name} holds NaN or infinity")

    finite(tensors, "last.pt")
    return {"meta": meta, "tensors": tensors}


def _restore(model: Any, vec: Any, saved: dict[str, Any], ckpt: Path,
             norm: Any = None) -> float:  # fmt: skip
    """The model, the random generators and the environments as ``saved`` (the
    checkpoint in ``ckpt``); returns the wall time already spent."""
    import random

    import torch

    meta, tensors = saved["meta"], saved["tensors"]
    try:
        model.set_parameters(tensors["params"], exact_match=True)
        obs = np.stack([
            env.restore({"drawn_from": meta["envs"][i]["drawn_from"],
                         "actions": tensors[f"actions{i}"].numpy(),
                         "ended": meta["envs"][i].get("ended"),
                         "drawn_families": meta["envs"][i].get("drawn_families")})
            for i, env in enumerate(vec.envs)
        ])  # fmt: skip
        kind, key, pos, has_gauss, cached = meta["numpy_rng"]
        np.random.set_state((kind, np.asarray(key, dtype=np.uint32), pos, has_gauss, cached))
        version, inner, gauss = meta["python_rng"]
        random.setstate((version, tuple(inner), gauss))
        torch.set_rng_state(tensors["torch_rng"])
        if "log_ent_coef" in tensors:  # SAC's: its coefficient and replay buffer
            model.log_ent_coef.data.copy_(tensors["log_ent_coef"])
            rb = model.replay_buffer
            for k in _BUFFER:
                part = tensors[f"rb_{k}"].numpy()
                getattr(rb, k)[: len(part)] = part
            rb.pos, rb.full = int(meta["buffer"]["pos"]), bool(meta["buffer"]["full"])
            model.action_space.np_random.bit_generator.state = meta["action_rng"]
        if norm is not None:
            saved_norm = meta["reward_norm"]
            norm.ret_rms.mean = np.float64(saved_norm["mean"])
            norm.ret_rms.var = np.float64(saved_norm["var"])
            norm.ret_rms.count = float(saved_norm["count"])
            norm.returns = np.asarray(saved_norm["returns"], dtype=np.float64)
    except Exception as exc:  # a part of another shape or kind than the run's
        first = " ".join(str(exc).split())[:160]
        raise InvalidArgumentError(f"{ckpt} does not fit this run ({type(exc).__name__}: "
                                   f"{first}); use another --checkpoints directory") from None
    model._last_obs = tensors["last_obs"].numpy().copy()
    if norm is not None:  # what SAC's buffer stores (the observation is left raw)
        model._last_original_obs = model._last_obs.copy()
    if not np.array_equal(obs, model._last_obs):
        raise InvalidArgumentError(f"{ckpt}: its environments do not replay to the state it "
                                   "recorded; use another --checkpoints directory")  # fmt: skip
    model._last_episode_starts = tensors["episode_starts"].numpy().astype(bool)
    model.num_timesteps = int(meta["steps"])
    model._n_updates = int(meta["updates"])
    return float(meta["seconds"])

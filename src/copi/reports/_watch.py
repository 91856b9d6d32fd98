"""Watch one navigation episode of any method: every step's picture with the rays, the
moving obstacles, and what the method decided there (``copi watch``)."""

from __future__ import annotations

import errno
import math
import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import atomic_path
from copi.baselines import Steered
from copi.core import (
    SENSING_LEVELS,
    Agent,
    Observation,
    Sensing,
    Task,
    check_sensing,
    check_strategy,
)
from copi.errors import InvalidArgumentError
from copi.learning import Capabilities
from copi.methods import make_agent, method_spec
from copi.online import CopiAgent, LearntAgent, PredictiveAgent
from copi.runs import EpisodeOutcome, draw_episode, run_episode
from copi.world import Simulator, rasterize

__all__ = ["FORMATS", "Step", "WatchedEpisode", "check_frames", "save_watch", "watch_episode"]

OUTCOME_COLORS = {"success": "#2ca02c", "collision": "#d62728", "timeout": "#666666"}

FORMATS = (".gif", ".mp4", ".png")
"""What :func:`save_watch` writes: an animation (GIF; MP4 with ffmpeg) or the last frame."""


@dataclass(frozen=True)
class Step:
    """What the method saw and decided at one time step."""

    ranges: NDArray[np.float64]
    """The reading it acted on, shape (n_rays,), agent steps."""
    action: NDArray[np.float64]
    """The velocity it sent, shape (2,)."""
    text: str
    """The decision in words: copi's chain (node, landmark, template and group element)
    and, on a second line, the chosen policy among the template's (named in the
    template's frame) with the heading it gives in the world; or the baseline's name and
    move."""
    candidates: NDArray[np.float64]
    """copi's candidate first moves in the world frame, shape (k, 2) (empty for
    baselines)."""
    futures: NDArray[np.float64] | None = None
    """What copi-predictive expected of the moving bodies it made out: a few of the
    futures it planned over, (samples, steps + 1, bodies, 2); None for the others."""


@dataclass(frozen=True)
class WatchedEpisode:
    """A recorded episode (``sim.path``, ``sim.traces``) and one :class:`Step` per step."""

    sim: Simulator
    method: str
    sensing: str
    episode: int
    seed: int
    steps: list[Step]
    outcome: EpisodeOutcome

    @property
    def n_frames(self) -> int:
        """Pictures of the episode: the start and one after each step."""
        return len(self.sim.path)


class _Explaining(Agent):
    """Wraps an agent, keeping each step's decision (copi's through ``explain=True``)."""

    def __init__(self, agent: Agent) -> None:
        self.agent = agent
        self.name = agent.name
        self.sensing = agent.sensing
        self.steers_itself = agent.steers_itself
        self.steps: list[Step] = []
        self.goal = np.zeros(2)
        """The goal in the world (copi-predictive plans in the goal's frame at sensor)."""

    def reset(self, task: Task) -> None:
        self.agent.reset(task)
        self.steps = []

    def act(self, obs: Observation) -> NDArray[np.float64]:
        agent = self.agent
        if isinstance(agent, CopiAgent):
            agent.explain = True
            action = agent.act(obs)
            d = agent.last_decision
            assert d is not None
            landmark = "a grown context" if d.landmark < 0 else f"landmark {d.landmark}"
            choice = {None: "none (no policy here)", "escape": "escape (none safe)"}.get(
                d.choice, d.choice
            )
            options = (
                " ".join(d.candidates) if len(d.candidates) <= 6 else f"{len(d.candidates)}"
            )
            where = ""
            if d.choice not in (None, "escape"):
                where = f", heading {_heading(action)} in the world"
            text = (
                f"node {d.node}{' (unfamiliar)' if d.unfamiliar else ''} -> {landmark} -> "
                f"template {d.template}, g = {d.element}\n"
                f"policy {choice} in the template's frame (of {options}){where}"
            )
            cands = d.candidate_actions
        elif isinstance(agent, PredictiveAgent):
            agent.explain = True
            action = np.asarray(agent.act(obs), dtype=np.float64)
            e = agent.last_explained
            assert e is not None
            costs = e["costs"]
            ok = np.isfinite(costs)
            moves = agent.planner.moves
            order = np.argsort(np.where(ok, costs, np.inf), kind="stable")[: min(3, int(ok.sum()))]
            best = ", ".join(("wait" if not moves[i].any() else
                              f"{_heading(moves[i])} x{np.hypot(*moves[i]):.1f}") +
                             f" {costs[i]:.1f}" for i in order)  # fmt: skip
            did = "waits" if e["waits"] else f"moves {_heading(action)}"
            text = (
                f"{len(e['bodies'])} bodies made out; {agent.samples} futures of "
                f"{agent.planner.horizon} steps drawn from the learnt model (pink); "
                f"{did}, {100 * e['risk']:.0f} % of futures in contact\n"
                f"expected cost (steps) of the best moves: {best}"
            )
            cands = moves[ok & np.any(moves != 0, axis=1)]
            futures = e["futures"] + (self.goal if agent.seen is not None else 0.0)
            self.steps.append(Step(obs.ranges.copy(), action, text, cands, futures))
            return action
        elif isinstance(agent, LearntAgent):
            agent.explain = True
            action = np.asarray(agent.act(obs), dtype=np.float64)
            e = agent.last_explained
            assert e is not None
            p = e["safety"]
            n_dir = len(p) - 1
            angles = 2 * np.pi * np.arange(n_dir) / n_dir
            seen = np.isfinite(p[:n_dir])
            choice = e["choice"]
            what = {-1: "nothing (no direction to go)", -2: "escape (the guard refused all)",
                    -4: "wait (safer than every move)"}.get(
                choice, (f"move {choice} ({_heading(action)}), P(safe) {p[choice]:.2f}"
                         if math.isfinite(p[choice]) else
                         f"move {choice} ({_heading(action)}), the guard's fallback (it "
                         "refused every move; this one runs into no hit)")
                if 0 <= choice < n_dir else str(choice))  # fmt: skip
            best = ", ".join(f"{_heading([math.cos(angles[d]), math.sin(angles[d])])} "
                             f"{p[d]:.2f}" for d in np.argsort(-np.nan_to_num(p[:n_dir], nan=-1))
                             [: min(3, int(seen.sum()))])  # fmt: skip
            text = (
                f"node {e['node']} -> template {e['template']}; global direction "
                f"{_heading(e['direction'])}; P(safe) scored for {int(seen.sum())} of {n_dir} "
                f"moves (best: {best})\nchoice: {what}"
            )
            cands = np.stack([np.cos(angles[seen]), np.sin(angles[seen])], axis=1)
        else:
            local = agent if isinstance(agent, Steered) else None
            if local is not None:  # a local method: its candidates, scored
                local.explain = True
            action = np.asarray(agent.act(obs), dtype=np.float64)
            speed = math.hypot(action[0], action[1])
            text = (
                f"{agent.name}: step {speed:.2f}, heading {_heading(action)}"
                if speed > 1e-9
                else f"{agent.name}: stays put"
            )
            direction = getattr(agent, "last_direction", None)
            if direction is not None and np.hypot(*direction[:2]) > 0:
                text += f"\nglobal direction {_heading(direction)}"
            cands = np.zeros((0, 2))
            explained = local.last_candidates if local is not None else None
            if explained is not None:
                cands, scores, what = explained
                text += f"\n{_scored(cands, scores, what)}"
                cands = cands[np.isfinite(scores)]
                if local is not None:
                    local.last_candidates = None
        self.steps.append(Step(obs.ranges.copy(), np.array(action, dtype=float), text, cands))
        return action

    def finish(self, outcome: str) -> None:
        self.agent.finish(outcome)

    def counters(self) -> dict[str, Any]:
        return self.agent.counters()


def _scored(cands: NDArray[np.float64], scores: NDArray[np.float64], what: str) -> str:
    """One line: how many candidates, how many refused, the best three with scores."""
    ok = np.isfinite(scores)
    best = np.argsort(-np.where(ok, scores, -np.inf), kind="stable")[: min(3, int(ok.sum()))]
    shown = ", ".join(f"{_heading(cands[i])} {scores[i]:.2f}" for i in best)
    refused = f", {int((~ok).sum())} refused" if (~ok).any() else ""
    return f"{len(scores)} candidates{refused}; score = {what}" + (
        f"; best: {shown}" if shown else "")


def _heading(v: Any) -> str:
    """A velocity's direction in degrees counter-clockwise from east (+x)."""
    return f"{math.degrees(math.atan2(v[1], v[0])) % 360:.0f} deg"


def watch_episode(
    method: str = "copi-faithful",
    capabilities: Capabilities | None = None,
    *,
    family: str = "star",
    world_file: str | os.PathLike[str] | None = None,
    episode: int = 0,
    seed: int = 0,
    sensing: Sensing | None = None,
    max_steps: int = 1000,
    agent_radius: float = 0.3,
    strategy: str = "greedy",
    params: dict[str, Any] | None = None,
) -> WatchedEpisode:
    """Run episode ``episode`` of seed ``seed`` (the same task ``copi evaluate`` runs as
    that episode) with ``method``, recording every step.

    Parameters
    ----------
    method : str
        A registered method (:func:`copi.methods.method_names`).
    capabilities : Capabilities, optional
        Needed by copi's methods.
    family, world_file :
        Where the episode is drawn (a file's world ``episode mod n``).
    sensing : str, optional
        Default: ``map``, or the least level the method needs when that is higher.
    strategy : str
        The global strategy at level ``sensor`` (greedy, mapping, causal).
    params : dict, optional
        Parameters over the method's registered ones (e.g. a guard).
    """
    spec = method_spec(method)
    if sensing is None:
        rank = max(SENSING_LEVELS.index("map"), SENSING_LEVELS.index(spec.sensing))
        sensing = SENSING_LEVELS[rank]
    check_sensing(sensing, spec.sensing, method=method)
    if episode < 0 or seed < 0:
        raise InvalidArgumentError(f"episode and seed must be >= 0; got {episode}, {seed}")
    n_rays, max_range = 32, 10.0
    if spec.capabilities is not None and capabilities is not None:
        n_rays, max_range = capabilities.n_rays, float(capabilities.params.get("max_range", 10.0))
    check_strategy(strategy)
    agent = _Explaining(make_agent(method, capabilities, **(params or {})))
    sim = draw_episode(
        family, episode, seed,
        world_file=None if world_file is None else str(world_file),
        agent_radius=agent_radius, n_rays=n_rays, max_range=max_range, record=True,
    )  # fmt: skip
    agent.goal = np.asarray(sim.goal, dtype=np.float64)
    out = run_episode(agent, sim, sensing=sensing, max_steps=max_steps, strategy=strategy)
    return WatchedEpisode(sim, method, sensing, episode, seed, agent.steps, out)


def frames(watched: WatchedEpisode, *, size: int = 480) -> list[NDArray[np.uint8]]:
    """The episode's pictures (one per :attr:`WatchedEpisode.n_frames`), each ``size``
    wide with a caption underneath: method, world and step, the decision taken from
    this state, and the outcome on the last one."""
    sim = watched.sim
    path = np.asarray(sim.path)
    traces = np.asarray(sim.traces)
    n = len(path)
    return [_frame(watched, t, path, traces, size) for t in range(n)]


def _font(size: int) -> Any:
    from PIL import ImageFont

    try:
        import matplotlib

        ttf = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
        return ImageFont.truetype(str(ttf), size)
    except (ImportError, OSError):
        return ImageFont.load_default(size)


def _frame(watched: WatchedEpisode, t: int, path: Any, traces: Any, size: int) -> NDArray[np.uint8]:
    from PIL import Image, ImageDraw

    sim = watched.sim
    last = t == len(path) - 1
    if t < len(watched.steps):
        ranges = watched.steps[t].ranges
    else:  # after the last step: what the sensor reads there
        ranges = sim.sensor.scan(sim.world, path[t], traces[t], sim.radii)
    moves = futures = None
    if t < len(watched.steps):
        moves = (watched.steps[t].candidates, watched.steps[t].action)
        futures = watched.steps[t].futures
    xmin, ymin, xmax, ymax = sim.world.bounds
    height = round(size * min(1.25, max(0.6, (ymax - ymin) / max(xmax - xmin, 1e-9))))
    picture = rasterize(
        sim.world, width=size, height=height, centers=traces[t], radii=sim.radii,
        traces=traces[: t + 1], path=path[: t + 1], agent_radius=sim.agent_radius,
        start=path[0], goal=sim.goal, rays=(path[t], ranges, sim.sensor.angles), moves=moves,
        futures=futures,
    )  # fmt: skip
    font_px = max(10, size // 36)
    line_h = int(font_px * 1.35)
    img = Image.new("RGB", (size, height + 4 * line_h + 8), "white")
    img.paste(Image.fromarray(picture), (0, 0))
    draw = ImageDraw.Draw(img)
    font = _font(font_px)
    x, y = 6, height + 4
    head = f"{watched.method} @ {watched.sensing}   {sim.world.name}   step {t}/{len(path) - 1}"
    draw.text((x, y), head, fill="#222222", font=font)
    if t < len(watched.steps):
        for k, text in enumerate(watched.steps[t].text.split("\n")[:2]):
            draw.text((x, y + (1 + k) * line_h), _fit(text, font, size - 12), fill="#222222",
                      font=font)  # fmt: skip
    if last:
        out = watched.outcome
        words = {
            "success": f"success: goal reached in {out.steps} steps",
            "collision": f"collision: touched a moving obstacle at step {out.steps}",
            "timeout": f"timeout: goal not reached in {out.steps} steps",
        }[out.outcome]
        draw.text((x, y + 3 * line_h), words, fill=OUTCOME_COLORS[out.outcome], font=font)
    else:
        legend = (
            "grey: the moves considered (copi-extended: the template's; copi-learnt: those "
            "scored); purple: the chosen one; orange: rays"
            if len(watched.steps[t].candidates)
            else "purple: the move made; orange: rays"
        )
        draw.text((x, y + 3 * line_h), _fit(legend, font, size - 12), fill="#777777", font=font)
    return np.asarray(img)


def _fit(text: str, font: Any, width: int) -> str:
    """``text`` cut with an ellipsis to fit ``width`` pixels."""
    if font.getlength(text) <= width:
        return text
    while text and font.getlength(text + "...") > width:
        text = text[:-1]
    return text + "..."


MOST_FRAME_BYTES = 2 << 30
"""Most bytes an animation's frames may hold in memory (size x size x 3 a frame)."""


def check_frames(size: int, frames: int) -> None:
    """Refuse an animation whose frames would not fit :data:`MOST_FRAME_BYTES`, saying
    how many steps fit at this size."""
    need = size * size * 3 * frames
    if need > MOST_FRAME_BYTES:
        fit = MOST_FRAME_BYTES // (size * size * 3)
        raise InvalidArgumentError(
            f"at {size} pixels, {frames:,} frames would hold {need / 2**30:.1f} GB in memory, "
            f"more than {MOST_FRAME_BYTES / 2**30:.0f} GB: lower the size, or the steps (at "
            f"most {fit:,} frames at this size)"
        )


def save_watch(
    watched: WatchedEpisode,
    path: str | os.PathLike[str],
    *,
    fps: int = 10,
    size: int = 480,
) -> Path:
    """Write the episode as a GIF (every step a frame), an MP4 (needs ``ffmpeg`` on the
    PATH) or, for ``.png``, its last frame."""
    from PIL import Image

    target = Path(path)
    suffix = target.suffix.lower()
    if suffix not in FORMATS:
        raise InvalidArgumentError(f"output must end in {', '.join(FORMATS)}; got {target.name!r}")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise InvalidArgumentError("writing .mp4 needs ffmpeg on the PATH; write a .gif instead")
    if fps < 1:
        raise InvalidArgumentError(f"fps must be >= 1; got {fps}")
    check_frames(size, len(watched.sim.path))
    if suffix == ".png":
        sim = watched.sim
        img = _frame(watched, len(sim.path) - 1, np.asarray(sim.path), np.asarray(sim.traces),
                     size)  # fmt: skip
        with atomic_path(target, "png") as tmp:
            Image.fromarray(img).save(tmp, format="PNG")
        return target
    pictures = frames(watched, size=size)
    if suffix == ".gif":
        first, *rest = (Image.fromarray(p) for p in pictures)
        durations = [round(1000 / fps)] * (len(pictures) - 1) + [2000]  # hold the outcome
        with atomic_path(target, "gif") as tmp:
            first.save(tmp, format="GIF", save_all=True, append_images=rest,
                       duration=durations, loop=0)  # fmt: skip
        return target
    h, w = pictures[0].shape[:2]
    cmd = [
        "ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
        "-s", f"{w}x{h}", "-r", str(fps), "-i", "-", "-pix_fmt", "yuv420p",
        "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-f", "mp4",
    ]  # fmt: skip
    with atomic_path(target, "mp4") as tmp:
        done = subprocess.run([*cmd, str(tmp)], input=b"".join(p.tobytes() for p in pictures),
                              capture_output=True)  # fmt: skip
        if done.returncode != 0:
            why = done.stderr.decode(errors="replace").strip().splitlines()
            raise OSError(errno.EIO, f"ffmpeg failed ({why[-1] if why else done.returncode})",
                          str(target))  # fmt: skip
    return target

"""The platform's entry points: copi's agent in the Gymnasium env, a benchmark of one's
own worlds, help that names what is registered, one reader for copi's npz files."""

from __future__ import annotations

import copy
import json
import zipfile
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import copi  # noqa: F401  (registers the environments)
from copi.learning import Capabilities
from copi.methods import make_agent
from copi.runs import run_episode, run_in_env
from copi.world import World, save_worlds
from tests.cli.test_faults import _one_line_error, run
from tests.common import U_TRAP


def test_copi_s_own_agent_runs_in_the_gymnasium_env(learnt_caps: Path) -> None:
    """The env and copi's runner agree: the same agent on the episode the env draws for
    a seed, run by copi.runs.run_episode at level sensor (what the env tells an agent),
    ends the same way, in the same number of steps, at the same place; and the env's
    rewards add up to what its docstring says they are."""
    caps = Capabilities.load(learnt_caps)
    agent = make_agent("copi-learnt", caps)
    env = gymnasium.make("copi/Navigation-v0", max_episode_steps=200)
    outcomes = []
    for s in range(4):
        _, info = env.reset(seed=s)
        start = copy.deepcopy(env.unwrapped.sim)  # the episode at t = 0
        out = run_in_env(agent, env, seed=s)
        outcomes.append(out)
        assert out.outcome in ("success", "collision", "timeout") and 1 <= out.steps <= 200
        assert out.outcome != "success" or out.info["is_success"]
        direct = run_episode(make_agent("copi-learnt", caps), start, sensing="sensor",
                             max_steps=200)  # fmt: skip
        assert (out.outcome, out.steps) == (direct.outcome, direct.steps), s
        # the env's actions are float32: the same path to a few 1e-7 a step
        np.testing.assert_allclose(env.unwrapped.sim.position, start.position, atol=1e-4)
        # progress, less 0.01 a step, +10 at the goal, -10 at a contact (which ends it)
        want = (info["distance"] - out.info["distance"] - 0.01 * out.steps
                + 10.0 * (out.outcome == "success") - 10.0 * (out.outcome == "collision"))  # fmt: skip
        assert out.reward == pytest.approx(want, abs=1e-9)
    again = run_in_env(make_agent("copi-learnt", Capabilities.load(learnt_caps)), env, seed=2)
    assert (again.steps, again.reward) == (outcomes[2].steps, outcomes[2].reward)
    # the env's radius and tolerance are what the agent is told, not guessed
    task = env.unwrapped.task()
    assert (task.agent_radius, task.goal_tolerance, task.sensing) == (0.3, 0.5, "sensor")
    with pytest.raises(ValueError, match="is not a copi.core.Agent"):
        run_in_env(object(), env)  # type: ignore[arg-type]


def test_the_benchmark_runs_a_user_s_world_file(tmp_path: Path, capsys) -> None:
    worlds = tmp_path / "mine.json"
    room = World(np.array([[0, 0], [30, 0], [30, 20], [0, 20]], dtype=float), name="hall")
    save_worlds([room, U_TRAP], worlds)
    out = tmp_path / "b"
    code, text, err = run(["benchmark", "-o", str(out), "--world-file", str(worlds),
                           "--methods", "straight@map,dwa@map", "--episodes", "4",
                           "--workers", "1"], capsys)  # fmt: skip
    assert code == 0, err
    assert "## worlds of mine.json (4 episodes)" in text
    from copi.results import ResultsStore

    with ResultsStore(out / "benchmark.sqlite", readonly=True) as store:
        rows = store.episodes()
        configs = [r.config for r in store.runs()]
    assert {r.family for r in rows} == {"file:mine.json"}
    assert {r.world for r in rows} == {"hall", "u-trap"}  # episode k in world k mod 2
    assert all(c["world_file_sha"] for c in configs)
    # the file changed: refused, nothing mixed
    save_worlds([room], worlds)
    code, _, err = run(["benchmark", "-o", str(out), "--world-file", str(worlds),
                        "--methods", "straight@map", "--episodes", "4", "--workers", "1"],
                       capsys)  # fmt: skip
    assert "the world file's content changed since" in _one_line_error(code, err)
    code, _, err = run(["benchmark", "-o", str(tmp_path / "c"), "--world-file", str(worlds),
                        "--families", "star"], capsys)  # fmt: skip
    assert "--world-file and --families do not go together" in _one_line_error(code, err)


def test_help_names_the_registered_methods_and_families(capsys) -> None:
    code, text, _ = run(["evaluate", "--help"], capsys)
    flat = " ".join(text.split())
    assert code == 0 and "Methods: copi-faithful, copi-extended, copi-learnt" in flat
    assert "Families: crowd, indoor, maps, polygon, star" in flat and "Presets: faithful" in flat
    code, text, _ = run(["list"], capsys)
    assert code == 0 and "navground-hl" in text and "two rooms" not in text


def test_a_causal_map_s_unknown_members_are_never_read(tmp_path: Path) -> None:
    from copi.online import CausalMap

    path = CausalMap().save(tmp_path / "m.npz", world="w")
    with zipfile.ZipFile(path, "a") as zf:  # a member whose stream is garbage: unread
        zf.writestr(zipfile.ZipInfo("huge.npy"), b"\x93NUMPY" + b"\x00" * 64)
    cmap, occ = CausalMap.load(path, world="w")
    assert cmap.n_options == 0 and occ is None
    # a known member claiming more than a map holds is refused before it is unpacked
    from copi.online import CausalMapFormatError
    from copi.online._causal_map import MAX_MEMBER_BYTES

    big = tmp_path / "big.npz"
    with zipfile.ZipFile(big, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        meta = {"format": "copi-causal-map", "version": 1, "params": {}, "world": "",
                "capabilities": ""}  # fmt: skip
        with zf.open("metadata.npy", "w") as fh:
            np.lib.format.write_array(fh, np.array(json.dumps(meta)))
        with zf.open("n.npy", "w", force_zip64=True) as fh:
            chunk = b"\x00" * (1 << 20)
            for _ in range(MAX_MEMBER_BYTES // len(chunk) + 2):
                fh.write(chunk)
    assert big.stat().st_size < 2_000_000
    with pytest.raises(CausalMapFormatError, match="member 'n' unpacks to .* bytes, more than"):
        CausalMap.load(big)


def test_rows_of_an_older_store_read_with_method_level_and_strategy_apart(tmp_path: Path) -> None:
    import sqlite3

    from copi.results import ResultsStore

    path = tmp_path / "old.sqlite"
    with ResultsStore(path) as store:  # written as copi 0.2 named things
        store.begin("r1", "lifelong", "dwa+mapping", {"family": "indoor", "sensing": "sensor"})
        store.begin("r2", "benchmark", "copi-learnt+priors",
                    {"family": "star", "sensing": "sensor", "strategy": "mapping"})  # fmt: skip
    with sqlite3.connect(path) as db:
        db.execute(
            "INSERT INTO lifelong (run_id, experiment, method, world, life, task, seed, family, "
            "sensing, outcome, success, steps) VALUES ('r1', 'lifelong', 'dwa+mapping', 'w', 0, "
            "0, 0, 'indoor', 'sensor', 'success', 1, 10)"
        )
        db.execute(
            "INSERT INTO episodes (run_id, experiment, method, world, episode, seed, success, "
            "reached, collided, timed_out, steps, contacts, family, sensing, outcome) VALUES "
            "('r2', 'benchmark', 'copi-learnt+priors', 'w', 0, 0, 1, 1, 0, 0, 10, 0, 'star', "
            "'sensor', 'success')"
        )
        db.execute("UPDATE lifelong SET strategy = NULL")
        db.execute("UPDATE episodes SET strategy = NULL")
    with ResultsStore(path, readonly=True) as store:
        (life,) = store.lifelong()
        (episode,) = store.episodes()
    assert (life.method, life.sensing, life.strategy) == ("dwa", "sensor", "mapping")
    assert (episode.method, episode.sensing, episode.strategy) == (
        "copi-learnt-priors", "sensor", "mapping")  # fmt: skip
    assert episode["success"] is True and episode.get("nothing", 3) == 3


def test_registered_parameters_are_the_classes_defaults() -> None:
    import inspect

    from copi.methods import method_spec

    # a method that is a class's own default configuration registers nothing over it
    for name in ("copi-faithful", "copi-learnt", "straight", "compass-guard", "vfh", "dwa",
                 "tangent-bug", "replan"):  # fmt: skip
        spec = method_spec(name)
        sig = inspect.signature(spec.factory)
        defaults = {k: p.default for k, p in sig.parameters.items() if k in spec.params}
        assert spec.params == defaults, name

from __future__ import annotations

import json
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from copi.cli import main
from copi.world import load_worlds
from tests.common import MAPS


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exit_:
        main(args)
    captured = capsys.readouterr()
    return int(exit_.value.code or 0), captured.out, captured.err


def test_sample_then_show(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    worlds = tmp_path / "sub" / "worlds.json"
    code, out, _ = run(["world", "sample", "--seed", "3", "-n", "2", "-o", str(worlds)], capsys)
    assert code == 0 and "000-" in out
    loaded = load_worlds(worlds)
    assert len(loaded) == 2
    code, out, _ = run(["world", "sample", "--seed", "3", "-n", "2", "-o", str(worlds)], capsys)
    assert load_worlds(worlds) == loaded  # same seed, same worlds
    pics = tmp_path / "pics"
    code, out, _ = run(
        ["world", "show", str(worlds), "-o", str(pics), "--steps", "20", "--gif"], capsys
    )
    assert code == 0
    names = sorted(p.name for p in pics.iterdir())
    stems = [w.name for w in loaded]
    assert names == sorted(
        [f"{s}.png" for s in stems] + [f"{s}.gif" for s in stems] + ["worlds.png"]
    )
    assert (pics / "worlds.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (pics / f"{stems[0]}.gif").read_bytes()[:6] == b"GIF89a"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["world", "sample", "-n", "0", "-o", "x.json"], "Invalid value for '-n'"),
        (["world", "sample", "--seed", "-1", "-o", "x.json"], "Invalid value for '--seed'"),
        (["world", "sample"], "Missing option '-o'"),
        (["world", "show", "nope.json", "-o", "d"], "nope.json: no such world file"),
        (["world", "frobnicate"], "No such command 'frobnicate'"),
    ],
)
def test_bad_arguments_exit_2_with_one_message(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args,
    message,
) -> None:
    monkeypatch.chdir(tmp_path)
    code, _, err = run(args, capsys)
    assert code == 2
    assert message in err
    assert "Traceback" not in err


def test_bad_world_file_exits_2_and_names_the_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('[\n{"boundary": [[0, 0], [4, 4], [4, 0], [0, 4]]}\n]')
    code, _, err = run(["world", "show", str(bad), "-o", str(tmp_path / "out")], capsys)
    assert code == 2
    assert f"{bad}:2:14: world 'world': boundary must be a simple polygon" in err.replace("\n", "")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_the_installed_command_runs_without_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "w.json"
    bad.write_text(json.dumps({"boundary": [[0, 0], [1, float("nan")], [2, 0]]}))
    proc = subprocess.run(
        [sys.executable, "-m", "copi.cli.main", "world", "show", str(bad), "-o", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "boundary must be" in proc.stderr


def test_import_movingai_then_plan(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = MAPS / "mapf"
    world_file = tmp_path / "room.json"
    code, out, _ = run(
        ["world", "import-movingai", str(data / "room-32-32-4.map"), "-o", str(world_file)], capsys
    )
    assert code == 0 and "27 holes" in out
    png = tmp_path / "plan.png"
    code, out, _ = run(
        [
            "plan",
            str(world_file),
            "--start",
            "3.5",
            "3.5",
            "--goal",
            "28.5",
            "29.5",
            "-o",
            str(png),
        ],
        capsys,
    )
    assert code == 0 and out.startswith("length ")
    length = float(out.split()[1])
    assert 25.0 * 2**0.5 <= length <= 43.0
    assert png.read_bytes()[:4] == b"\x89PNG"
    code, _, err = run(
        ["plan", str(world_file), "--start", "0.5", "31.5", "--goal", "1", "1"], capsys
    )
    assert code == 2 and "start (0.5, 31.5) must lie in the free space" in err
    code, _, err = run(["plan", str(world_file), "--start", "3.5", "3.5"], capsys)
    assert code == 2 and "has no goal; give --start and --goal" in err
    code, _, err = run(
        ["world", "import-movingai", str(world_file), "-o", str(tmp_path / "x.json")], capsys
    )
    assert code == 2 and "expected 'key value' header" in err and "Traceback" not in err


def test_learn_inspect_figures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    caps = tmp_path / "caps.npz"
    code, out, _ = run(
        ["learn", "-o", str(caps), "--worlds", "4", "--steps", "120", "--directions", "8"], capsys
    )
    assert code == 0 and "capability learning" in out and "policies" in out
    code, out, _ = run(["inspect", str(caps), "--json"], capsys)
    info = json.loads(out)
    assert info["summary"]["directions"] == 8 and info["params"]["worlds"] == 4
    code, out, _ = run(["inspect", str(caps)], capsys)
    assert code == 0 and "templates" in out
    figs = tmp_path / "figs"
    code, out, _ = run(["figures", str(caps), "-o", str(figs)], capsys)
    assert code == 0
    assert sorted(p.name for p in figs.iterdir()) == [
        "fig1_context_map.png",
        "fig1_landmarks.png",
        "fig1_policies.png",
        "fig1_skeleton_curve.png",
        "fig2_automaton.png",
    ]
    caps.write_bytes(caps.read_bytes()[:100])
    code, _, err = run(["inspect", str(caps)], capsys)
    assert code == 2 and "not a complete .npz archive" in err and "Traceback" not in err
    code, _, err = run(["learn", "-o", str(caps), "--directions", "5"], capsys)
    assert code == 2 and "directions must be 4, 8 or 16" in err


def test_evaluate_report_and_bad_inputs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    caps = tmp_path / "caps.npz"
    run(["learn", "-o", str(caps), "--worlds", "8", "--steps", "150", "--preset", "faithful"],
        capsys)  # fmt: skip
    results = tmp_path / "r.sqlite"
    code, out, err = run(
        ["evaluate", str(caps), "-o", str(results), "--worlds", "4", "--max-steps", "200"], capsys
    )
    assert code == 0 and "4 episodes" in out, err
    code, out, _ = run(["report", str(results), "-o", str(tmp_path / "rep")], capsys)
    assert code == 0 and (tmp_path / "rep" / "report.md").exists()
    before = results.read_bytes()
    code, _, err = run(
        ["evaluate", str(caps), "-o", str(results), "--worlds", "4", "--max-steps", "100"], capsys
    )
    assert code == 2 and "different configuration" in err and "Traceback" not in err
    assert results.read_bytes() == before
    code, _, err = run(
        ["evaluate", str(caps), "-o", str(tmp_path / "s.sqlite"), "--worlds", "2",
         "--scheduler", "tcp://127.0.0.1:9"],
        capsys,
    )  # fmt: skip
    assert code == 2 and "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err
    broken = tmp_path / "broken.npz"
    broken.write_bytes(caps.read_bytes()[:200])
    code, _, err = run(["evaluate", str(broken), "-o", str(tmp_path / "b.sqlite")], capsys)
    assert code == 2 and "not a complete .npz archive" in err
    assert not (tmp_path / "b.sqlite").exists()
    for bad, message in [
        (["--method", "astar"], "method must be one of copi-faithful, copi-extended, copi-learnt, copi-learnt-priors"),
        (
            ["--sensing", "psychic"],
            "--sensing must be sensor, map or oracle; got 'psychic'",
        ),
        (
            ["--method", "replan", "--sensing", "map"],
            "replan needs sensing level 'oracle' or above; asked to run at 'map'",
        ),
        (["--family", "moon"], "family must be one of"),
    ]:
        code, _, err = run(["evaluate", str(caps), "-o", str(tmp_path / "x.sqlite"), *bad], capsys)
        assert code == 2 and message in err and "Traceback" not in err, err
        assert not (tmp_path / "x.sqlite").exists()
    code, _, err = run(["evaluate", "-o", str(tmp_path / "y.sqlite")], capsys)
    assert code == 2 and "give a capabilities file (for copi's modes), --preset NAME" in err
    code, _, err = run(["evaluate", "-o", str(tmp_path / "y.sqlite"), "--preset", "faithful"],
                       capsys)  # fmt: skip
    assert code == 2 and "copi-faithful needs a capabilities file" in err
    code, out, err = run(
        ["evaluate", "--method", "dwa", "-o", str(tmp_path / "d.sqlite"), "--worlds", "2",
         "--max-steps", "100"],
        capsys,
    )  # fmt: skip
    assert code == 0 and "dwa (map, star): 2 episodes" in out, err
    code, _, err = run(
        ["report", str(tmp_path / "missing.sqlite"), "-o", str(tmp_path / "q")], capsys
    )
    assert code == 2 and "no such results file" in err


def test_pursuit_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    caps = tmp_path / "caps.npz"
    run(["learn", "-o", str(caps), "--worlds", "8", "--steps", "150", "--preset", "faithful"],
        capsys)  # fmt: skip
    results = tmp_path / "g.sqlite"
    code, out, err = run(
        ["pursuit", str(caps), "-o", str(results), "--games", "3", "--horizon", "60", "--static"],
        capsys,
    )
    assert code == 0 and "capability-static: 3 games" in out, err
    code, _, err = run(["pursuit", str(caps), "-o", str(results), "--evader", "ghost"], capsys)
    assert code == 2 and "Traceback" not in err
    assert ("evader must be one of capability, learnt, game or a registered method of level "
            "sensor; got 'ghost'") in err  # fmt: skip
    # a registered method plays as the study plays it (PursuitConfig's guard), the same games
    code, out, err = run(["pursuit", str(caps), "-o", str(results), "--games", "3",
                          "--horizon", "60", "--evader", "ppo-chauffeur-sensor"], capsys)  # fmt: skip
    assert code == 0 and "ppo-chauffeur-sensor-dynamic: 3 games" in out, err
    from copi.experiments import PursuitConfig, pursue, run_game
    from copi.results import ResultsStore

    config = PursuitConfig(capabilities=str(caps), evader="ppo-chauffeur-sensor", games=3,
                           horizon=60)  # fmt: skip
    with ResultsStore(results, readonly=True) as store:
        before = len(store.runs())
    run_id = pursue(config, results)  # the CLI's run: found whole, nothing played
    with ResultsStore(results, readonly=True) as store:
        assert len(store.runs()) == before
        rows = store.games(run_id)
    assert [r.survival for r in rows] == [run_game(config, k).survival for k in range(3)]
    for args, message in ((["--evader", "ppo-star-map"], "needs level map; the game gives sensor"),
                          (["--evader", "ppo", "--preset", "faithful"],
                           "--preset faithful plays the preset's evader")):  # fmt: skip
        code, _, err = run(["pursuit", str(caps), "-o", str(tmp_path / "h.sqlite"), *args],
                           capsys)  # fmt: skip
        assert code == 2 and message in err and "Traceback" not in err
    assert not (tmp_path / "h.sqlite").exists()


@pytest.mark.parametrize("name", ["learnt", "learnt-motion", "predictive"])
def test_learn_with_a_preset_learns_all_the_preset_learns(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``copi learn --preset P`` learns what P's method needs (the predictive preset: the
    model of what moves and the safety networks with the static reading); the learning
    itself is replaced by a recorder (the presets' own learning is tested elsewhere)."""
    import copi.learning
    from copi.methods import preset

    seen = []

    class Stop(Exception):
        pass

    def record(params, progress=None):  # type: ignore[no-untyped-def]
        seen.append(params)
        raise Stop

    monkeypatch.setattr(copi.learning, "learn", record)
    with pytest.raises(Stop):
        run(["learn", "-o", str(tmp_path / "c.npz"), "--preset", name], capsys)
    want = preset(name).learn
    (got,) = seen
    for key in ("directions", "safety", "safety_static", "motion", "predict"):
        assert getattr(got, key) == getattr(want, key), key


def test_presets_set_a_mode_whole(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    caps = tmp_path / "ext.npz"
    code, _, err = run(["learn", "-o", str(caps), "--worlds", "6", "--steps", "120",
                        "--preset", "extended"], capsys)  # fmt: skip
    assert code == 0, err
    code, out, _ = run(["inspect", str(caps), "--json"], capsys)
    assert json.loads(out)["params"]["directions"] == 16
    results = tmp_path / "r.sqlite"
    code, out, err = run(["evaluate", str(caps), "-o", str(results), "--worlds", "2",
                          "--max-steps", "80", "--preset", "extended"], capsys)  # fmt: skip
    assert code == 0 and "copi-extended (map, star): 2 episodes" in out, err
    with sqlite3.connect(results) as db:
        config = json.loads(db.execute("SELECT config FROM runs").fetchone()[0])
    assert config["method"] == "copi-extended" and config["guard"] is None  # the method's
    from copi.methods import method_spec

    assert method_spec("copi-extended").params["guard"] == 1.05
    code, out, err = run(["pursuit", str(caps), "-o", str(tmp_path / "g.sqlite"), "--games",
                          "1", "--horizon", "20", "--preset", "extended"], capsys)  # fmt: skip
    assert code == 0 and "1 games" in out, err
    faithful = tmp_path / "f.npz"
    run(["learn", "-o", str(faithful), "--worlds", "6", "--steps", "120", "--preset", "faithful"],
        capsys)  # fmt: skip
    for args, message in [
        (["learn", "-o", str(tmp_path / "z.npz"), "--preset", "extended", "--directions", "4"],
         "--directions 4 contradicts --preset extended (16 directions)"),
        (["learn", "-o", str(tmp_path / "z.npz"), "--preset", "fancy"],
         "preset must be one of faithful, extended, learnt"),
        (["evaluate", str(faithful), "-o", str(tmp_path / "z.sqlite"), "--preset", "extended"],
         f"{faithful} was learnt for preset faithful (4 directions, no safety priors); preset "
         "extended needs 16 directions, no safety priors: learn it with copi learn --preset "
         "extended, or run it with --preset faithful"),
        (["evaluate", str(caps), "-o", str(tmp_path / "z.sqlite"), "--preset", "extended",
          "--method", "dwa"], "--method dwa contradicts --preset extended (copi-extended)"),
        (["pursuit", str(caps), "-o", str(tmp_path / "z.sqlite"), "--preset", "faithful"],
         "was learnt for preset extended (16 directions, no safety priors); preset faithful "
         "needs 4 directions"),
        (["evaluate", str(caps), "-o", str(tmp_path / "z.sqlite"), "--preset", "learnt"],
         f"{caps} was learnt for preset extended (16 directions, no safety priors); preset "
         "learnt needs 16 directions, safety priors: learn it with copi learn --preset learnt"),
        (["evaluate", str(caps), "-o", str(tmp_path / "z.sqlite"), "--preset", "extended",
          "--guard", "3"], "--guard 3 contradicts --preset extended (guard 1.05)"),
        (["pursuit", str(caps), "-o", str(tmp_path / "z.sqlite"), "--preset", "learnt"],
         f"{caps} was learnt for preset extended"),
        (["pursuit", str(caps), "-o", str(tmp_path / "z.sqlite"), "--evader", "learnt"],
         f"--evader learnt plays the learnt preset's agent; {caps} was learnt for preset "
         "extended"),
        (["pursuit", str(caps), "-o", str(tmp_path / "z.sqlite"), "--evader", "learnt",
          "--preset", "extended"], "--evader learnt plays the learnt preset's agent"),
        (["pursuit", str(caps), "-o", str(tmp_path / "z.sqlite"), "--preset", "extended",
          "--guard", "2"], "--guard 2 contradicts --preset extended (guard 1.05)"),
    ]:  # fmt: skip
        code, _, err = run(args, capsys)
        assert code == 2 and message in " ".join(err.split()), err
        assert not (tmp_path / "z.npz").exists() and not (tmp_path / "z.sqlite").exists()


def test_reproduce_into_a_directory_of_another_run_says_what_to_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    import copi.experiments._reproduce as commands
    from copi.results import ResultsStore

    def clash(output: Path, quick: bool, workers: int, seed: int, tasks: object) -> None:
        from copi.results import EpisodeRow

        with ResultsStore(output / "experiment1.sqlite") as store:  # as a --quick run left it
            store.begin("a", "navigation", "copi-faithful", {"worlds": 100})
            store.add("a", "navigation", "copi-faithful", EpisodeRow(
                episode=0, world="w", seed=0, success=True, reached=True, collided=False,
                timed_out=False, steps=3, contacts=0, path_length=3.0, optimal_length=3.0,
                excess=0.0, decision_us=1.0, strategy_us=0.0, unfamiliar=0.0, no_policy=0))
            store.begin("b", "navigation", "copi-faithful", {"worlds": 1549})

    monkeypatch.setattr(commands, "_reproduce", clash)
    code, _, err = run(["reproduce", "-o", str(tmp_path / "res")], capsys)
    assert code == 2, err
    assert " ".join(err.split()) == (
        f"copi: error: {tmp_path / 'res'} holds results of a --quick run or of other settings; "
        f"reproduce into another directory, or delete {tmp_path / 'res'} to start over"
    )


def test_learn_with_static_aware_safety(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--safety-static learns safety networks that see the static reading: the file says
    so, its networks (and nothing else) differ from those learnt without it on the same
    probes, and they tell a hit the static map explains (a wall) from one it does not
    (something that moves)."""
    import numpy as np

    from copi.learning import Capabilities
    from copi.learning.kernels import kernel_net, safety_probabilities

    args = ["--preset", "learnt", "--worlds", "3", "--steps", "80", "--probe-worlds", "2",
            "--probe-steps", "20", "--probe-label", "escape"]  # fmt: skip
    caps, plain = tmp_path / "caps.npz", tmp_path / "plain.npz"
    for path, extra in ((caps, ["--safety-static"]), (plain, [])):
        code, out, err = run(["learn", "-o", str(path), *args, *extra], capsys)
        assert code == 0, err
    code, out, _ = run(["inspect", str(caps), "--json"], capsys)
    params = json.loads(out)["params"]
    assert params["safety_static"] is True and params["probe_label"] == "escape"
    aware, blind = Capabilities.load(caps), Capabilities.load(plain)
    assert aware.safety.static_aware is True and blind.safety.static_aware is False
    # the same seed, the same exploration and probes: only what the networks saw differs
    assert np.array_equal(aware.nodes, blind.nodes)
    assert np.array_equal(aware.safety.template_safe, blind.safety.template_safe)
    assert not np.array_equal(aware.safety.net, blind.safety.net)
    # a hit 1 ahead on ray 0 (everything else out of range), a wall or a moving thing
    s = np.full(32, 10.0)
    s[0] = 1.0

    def p_safe(static: np.ndarray) -> np.ndarray:
        out = np.empty(17)
        safety_probabilities(s, s, static, kernel_net(aware.safety.net), 16,
                             np.empty(8 * 32), out)  # fmt: skip
        return out

    wall, moving = p_safe(s.copy()), p_safe(np.full(32, np.inf))
    assert not np.allclose(wall, moving), (wall, moving)

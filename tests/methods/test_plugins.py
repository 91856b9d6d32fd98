"""Other people's methods and worlds: a package in the tests' tree (``tests/plugin``)
adds a method and a world family through copi's entry points, and the command line runs
them beside copi's own, with paired intervals, never an edit of copi."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from copi.methods import method_names, register_method, unregister_method
from copi.testing import check_agent
from copi.world import family_names, register_family, sample_world, unregister_family
from tests.cli.test_faults import _one_line_error, run

PLUGIN = Path(__file__).resolve().parents[1] / "plugin"


@pytest.fixture
def plugin(monkeypatch: pytest.MonkeyPatch):
    monkeypatch.syspath_prepend(str(PLUGIN))
    yield
    import copi._plugins

    monkeypatch.undo()  # the plugin off the path first, so that nothing loads it again
    assert str(PLUGIN) not in sys.path
    unregister_method("sidestep")
    unregister_family("two-rooms")
    sys.modules.pop("copi_example_plugin", None)
    copi._plugins._LOADED.clear()  # as a new process would: entry points called anew


def test_a_package_adds_a_method_and_a_family_the_benchmark_runs(
    plugin: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "bench"
    code, text, err = run(
        ["benchmark", "-o", str(out), "--methods", "sidestep@sensor,dwa@sensor",
         "--families", "two-rooms", "--episodes", "12", "--workers", "1",
         "--against", "dwa"], capsys,
    )  # fmt: skip
    assert code == 0, err
    assert "sidestep" in method_names() and "two-rooms" in family_names()
    assert "**Reference: dwa** (named with --against)" in text
    row = next(ln for ln in text.splitlines() if ln.startswith("| sidestep | sensor | greedy"))
    cells = [c.strip() for c in row.split("|")]
    assert cells[4] == "12"  # n
    assert "[" in cells[14] and "]" in cells[14]  # a paired interval of Δ success
    assert "## two-rooms (12 episodes)" in text
    report = (out / "benchmark.md").read_text()
    assert "| sidestep | sensor | follow the global direction, step aside" in report
    # the method passes the conformance check
    from copi_example_plugin import Sidestep

    check_agent(Sidestep)


def test_a_later_run_keeps_the_method_in_the_report(
    plugin: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "bench"
    base = ["benchmark", "-o", str(out), "--families", "star", "--episodes", "2", "--workers",
            "1"]  # fmt: skip
    assert run([*base, "--methods", "sidestep@map"], capsys)[0] == 0
    unregister_method("sidestep")  # as if its package were uninstalled, then run again
    sys.modules.pop("copi_example_plugin", None)
    monkey_path = [p for p in sys.path if p != str(PLUGIN)]
    sys.path[:] = monkey_path
    code, _, err = run([*base, "--methods", "straight@map"], capsys)
    assert code == 0, err
    report = (out / "benchmark.md").read_text()
    assert "| sidestep | map | route | 2 |" in report
    assert "| sidestep | ? | (not registered in this copi" in report


def test_registering_in_python_is_one_call(tmp_path: Path) -> None:
    from copi.core import Agent
    from copi.experiments import BenchmarkConfig, run_benchmark
    from copi.reports import write_benchmark_report
    from copi.world import World

    class Still(Agent):
        def reset(self, task): ...

        def act(self, obs):
            return np.zeros(2)

    def box(rng, *, name=None):
        s = float(rng.uniform(15, 25))
        return World(np.array([[0, 0], [s, 0], [s, s], [0, s]]), name=name or "box")

    register_method("still", Still, summary="stands still")
    register_family("box", box)
    try:
        cfg = BenchmarkConfig(methods=("still@map", "straight@map"), families=("box",),
                              episodes=3)  # fmt: skip
        run_benchmark(cfg, tmp_path / "b.sqlite")
        text = write_benchmark_report(tmp_path / "b.sqlite", tmp_path, against="straight")
        assert "| still | map | route | 3 | 0.0 % |" in text.read_text()
        assert sample_world("box", 0).name == "box"
    finally:
        unregister_method("still")
        unregister_family("box")


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: register_method("Bad Name", object), "a method's name must be lower-case"),
        (lambda: register_method("dwa", object), "a method named 'dwa' is registered already"),
        (lambda: register_method("x", 3), "the factory of x must be callable"),
        (lambda: register_method("x", object, sensing="psychic"), "sensing level must be one of"),
        (lambda: register_family("star", lambda rng, name=None: None),
         "a family named 'star' is registered already"),
        (lambda: unregister_method("dwa"), "dwa is one of copi's own methods"),
        (lambda: unregister_family("maps"), "maps is one of copi's own families"),
    ],
)
def test_bad_registrations_are_refused(call, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


@pytest.fixture
def broken_plugin(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """A package whose entry point names a module that is not there."""
    import copi._plugins

    info = tmp_path / "plugins" / "broken_plugin-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: broken-plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[copi.methods]\nbroken = no_such_module:register\n")
    monkeypatch.syspath_prepend(str(tmp_path / "plugins"))
    yield
    monkeypatch.undo()
    copi._plugins._LOADED.clear()
    copi._plugins._FAILED.clear()


BROKEN = "entry point 'broken' (no_such_module:register) of copi.methods cannot be loaded"


@pytest.mark.filterwarnings("default::copi.errors.PluginWarning")
@pytest.mark.parametrize("command", [
    ["list"],
    ["benchmark", "-o", "b", "--methods", "dwa@sensor", "--families", "star", "--episodes", "1",
     "--workers", "1"],
], ids=["list", "benchmark"])  # fmt: skip
def test_a_broken_entry_point_is_skipped_with_one_warning(
    broken_plugin: None, command: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    # copi's own commands run, saying once what was skipped
    monkeypatch.chdir(tmp_path)
    code, text, err = run(command, capsys)
    assert code == 0, err
    warnings = [ln for ln in err.splitlines() if ln.startswith("copi: warning:")]
    assert warnings == [f"copi: warning: {BROKEN} (ModuleNotFoundError: No module named "
                        "'no_such_module'); skipped"], err  # fmt: skip
    assert "dwa" in text if command == ["list"] else (tmp_path / "b" / "benchmark.sqlite").exists()


@pytest.mark.filterwarnings("default::copi.errors.PluginWarning")
def test_a_name_only_a_broken_entry_point_could_register_says_why(
    broken_plugin: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(["benchmark", "-o", str(tmp_path / "b"), "--methods", "ghost"], capsys)
    assert err.count("copi: warning:") == 1  # the skipped entry point, then the error
    line = _one_line_error(code, "\n".join(ln for ln in err.splitlines() if "warning" not in ln))
    assert "got 'ghost'" in line and BROKEN in line and "it may have registered 'ghost'" in line
    assert not (tmp_path / "b").exists()


def test_a_broken_entry_point_warns_in_python(broken_plugin: None) -> None:
    from copi.errors import PluginWarning

    with pytest.warns(PluginWarning, match="cannot be loaded"):
        names = method_names()
    assert "dwa" in names and "broken" not in names


def test_the_methods_table_shows_a_series_of_trained_methods_in_one_row() -> None:
    """Methods that differ only by the family they were trained on share a row, naming
    each family; a method alone keeps its own name and summary; every method is shown."""
    from copi.methods import method_spec, methods_markdown

    rows = methods_markdown().splitlines()[2:]
    names = [r.split("`")[1] for r in rows]
    row = rows[names.index("ppo-F-map")]
    assert "the F family at map" in row and row.endswith("(F: star, polygon, indoor, maps, crowd) |")
    assert "ppo-star-map" not in names and "compass-guard" in names
    assert method_spec("ppo-chauffeur").summary in rows[names.index("ppo-chauffeur")]
    shown = {n.replace("F", f) for n in names for f in ("star", "polygon", "indoor", "maps",
                                                         "crowd")}  # fmt: skip
    assert {n for n in method_names() if method_spec(n).factory.__module__.startswith("copi")} \
        <= shown  # fmt: skip

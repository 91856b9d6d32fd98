"""No run resumes into another's: a method or family registered over copi's own, or whose
code changed between a run and its resume, is another run, refused in one line with the
store left as it was (issue: "Nothing mixed")."""

from __future__ import annotations

import importlib
import sqlite3
import sys
from pathlib import Path

import numpy as np
import pytest

from copi.baselines import DWA
from copi.core import Agent
from copi.methods import method_replaced, method_spec, register_method, unregister_method
from copi.world import family_replaced, family_spec, register_family, unregister_family
from tests.cli.test_faults import _one_line_error, run


class Impostor(Agent):
    """Not copi's DWA: always east."""

    def reset(self, task: object) -> None:
        pass

    def act(self, obs: object) -> np.ndarray:
        return np.array([1.0, 0.0])


def _rows(store: Path) -> int:
    with sqlite3.connect(store) as db:
        return int(db.execute("SELECT COUNT(*) FROM episodes").fetchone()[0])


def _bench(out: Path, capsys: pytest.CaptureFixture[str], methods: str = "dwa@map",
           family: str = "star") -> tuple[int, str, str]:  # fmt: skip
    return run(["benchmark", "-o", str(out), "--methods", methods, "--families", family,
                "--episodes", "3", "--workers", "1", "--against", methods.split("@")[0]],
               capsys)  # fmt: skip


def test_a_method_registered_over_copi_s_own_never_resumes_its_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    code, _, err = _bench(tmp_path, capsys)
    assert code == 0, err
    store = tmp_path / "benchmark.sqlite"
    before = store.read_bytes()
    register_method("dwa", Impostor, summary="an impostor [/x]", replace=True)
    try:
        assert method_replaced("dwa") and method_spec("dwa").origin["method_code"]
        msg = _one_line_error(*_bench(tmp_path, capsys)[::2])
        assert "run of method 'dwa' from copi's own there, from tests.methods.test_mixing " \
               "now" in msg  # fmt: skip
        assert store.read_bytes() == before and _rows(store) == 3
        from copi.cli._common import out

        wide = out._width  # one table row a line
        out.width = 400
        try:
            code, text, _ = run(["list"], capsys)  # the impostor is shown as what it is
        finally:
            out._width = wide
        flat = " ".join(text.split())
        assert code == 0 and "an impostor [/x] [from tests.methods.test_mixing;" in flat
        assert "registered over copi's own]" in flat
    finally:
        unregister_method("dwa")  # puts copi's back
    assert not method_replaced("dwa") and method_spec("dwa").factory is DWA
    code, text, err = _bench(tmp_path, capsys)  # copi's own again: the stored run resumes
    assert code == 0 and _rows(store) == 3, err


VERSION = '''
import numpy as np
from copi.core import Agent


class Mine(Agent):
    """{doc}"""

    def reset(self, task):
        pass

    def act(self, obs):
        return np.array([{vx}, 0.0])
'''


def test_a_method_whose_code_changed_never_resumes_its_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    module = tmp_path / "mixing_plugin.py"
    module.write_text(VERSION.format(doc="v1", vx="1.0"))
    monkeypatch.syspath_prepend(str(tmp_path))
    plugin = importlib.import_module("mixing_plugin")
    register_method("mine", plugin.Mine, summary="v1")
    try:
        out = tmp_path / "run"
        code, _, err = _bench(out, capsys, "mine@sensor")
        assert code == 0, err
        first = method_spec("mine").origin["method_code"]
        module.write_text(VERSION.format(doc="v2, which goes slower", vx="0.5"))
        importlib.reload(plugin)
        register_method("mine", plugin.Mine, summary="v1", replace=True)  # same name, params
        assert method_spec("mine").origin["method_code"] != first
        msg = _one_line_error(*_bench(out, capsys, "mine@sensor")[::2])
        assert "run of method 'mine' from mixing_plugin, whose code changed since" in msg
        assert _rows(out / "benchmark.sqlite") == 3
    finally:
        unregister_method("mine")
        sys.modules.pop("mixing_plugin", None)


def _squares(rng: np.random.Generator, *, name: str | None = None):  # type: ignore[no-untyped-def]
    from copi.world import World

    side = float(rng.uniform(20, 30))
    return World([[0, 0], [side, 0], [side, side], [0, side]], name=name or "square")


def test_a_family_registered_over_copi_s_own_never_resumes_its_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = _bench(tmp_path, capsys, "straight@map")
    assert code == 0, err
    original = family_spec("star")
    register_family("star", _squares, summary="squares", replace=True)
    try:
        assert family_replaced("star")
        msg = _one_line_error(*_bench(tmp_path, capsys, "straight@map")[::2])
        assert "run of family 'star' from copi's own there, from tests.methods.test_mixing" in msg
        assert _rows(tmp_path / "benchmark.sqlite") == 3
    finally:
        unregister_family("star")
    assert family_spec("star") is original and not family_replaced("star")


TYPED = '''
import numpy as np
from copi.core import Agent
from {helper} import SPEED


def _reset(self, task):
    pass


def _act(self, obs):
    return np.array([SPEED, 0.0])


Typed = type("Typed", (Agent,), {{"reset": _reset, "act": _act}})
'''


@pytest.mark.parametrize("what", ["the class's module", "a module it imports"])
def test_a_class_made_with_type_and_its_helpers_are_part_of_its_identity(
    what: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    """A class made with ``type()`` under an ABC says it comes from ``abc``; its
    identity is its own module's, and every module beside it (a helper it imports)."""
    (tmp_path / "typed_helper.py").write_text("SPEED = 1.0\n")
    module = tmp_path / "typed_plugin.py"
    module.write_text(TYPED.format(helper="typed_helper"))
    monkeypatch.syspath_prepend(str(tmp_path))
    plugin = importlib.import_module("typed_plugin")
    try:
        assert plugin.Typed.__module__ == "abc"  # what type() under ABCMeta records
        register_method("typed", plugin.Typed, summary="typed")
        origin = method_spec("typed").origin
        assert origin["method_origin"] == "typed_plugin"
        out = tmp_path / "run"
        code, _, err = _bench(out, capsys, "typed@sensor")
        assert code == 0, err
        if what == "a module it imports":
            (tmp_path / "typed_helper.py").write_text("SPEED = 0.5\n")
        else:
            module.write_text(TYPED.format(helper="typed_helper") + "# v2\n")
        register_method("typed", plugin.Typed, summary="typed", replace=True)
        assert method_spec("typed").origin["method_code"] != origin["method_code"]
        msg = _one_line_error(*_bench(out, capsys, "typed@sensor")[::2])
        assert "run of method 'typed' from typed_plugin, whose code changed since" in msg
    finally:
        unregister_method("typed")
        for m in ("typed_plugin", "typed_helper"):
            sys.modules.pop(m, None)


def test_copi_s_own_code_under_another_of_its_names_is_another_run_and_said_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from copi.baselines import VFH
    from copi.cli._common import out as console

    code, _, err = _bench(tmp_path, capsys, "straight@map")
    assert code == 0, err
    polygon = family_spec("polygon").sampler
    register_family("star", polygon, summary="polygon as star", replace=True)
    register_method("dwa", VFH, summary="vfh as dwa", replace=True)
    try:
        msg = _one_line_error(*_bench(tmp_path, capsys, "straight@map")[::2])
        assert "run of family 'star' from copi's own there, from copi (registered over " \
               "copi's own) now" in msg  # fmt: skip
        wide = console._width
        console.width = 400
        try:
            code, text, _ = run(["list"], capsys)
        finally:
            console._width = wide
        flat = " ".join(text.split())
        assert "polygon as star [registered over copi's own]" in flat
        assert "vfh as dwa [registered over copi's own]" in flat
    finally:
        unregister_family("star")
        unregister_method("dwa")


def test_an_evaluation_and_a_pursuit_of_a_method_registered_again_are_other_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from copi.experiments.pursuit import PursuitConfig

    store = tmp_path / "e.sqlite"
    args = ["evaluate", "--method", "dwa", "--worlds", "2", "-o", str(store)]
    code, _, err = run(args, capsys)
    assert code == 0, err
    game = PursuitConfig(None, evader="dwa", games=2, horizon=30)
    before = game.identity()
    register_method("dwa", DWA, params={"margin": 0.1}, summary="dwa, closer",
                    replace=True)  # fmt: skip
    try:
        msg = _one_line_error(*run(args, capsys)[::2])
        assert "run of method 'dwa' from copi's own there, from copi (registered over " \
               "copi's own) now" in msg  # fmt: skip
        assert game.identity() != before
    finally:
        unregister_method("dwa")
    assert game.identity() == before


def test_a_replacement_by_entry_point_is_what_every_command_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An installed package registering over ``dwa``: even a command that only asks for
    ``dwa`` (never listing the methods) gets the package's, as ``copi list`` says."""
    import copi._plugins

    (tmp_path / "over_dwa.py").write_text(
        "from copi.methods import register_method\n"
        "from copi.baselines import Straight\n\n\n"
        "class Over(Straight):\n"
        "    pass\n\n\n"
        "def register():\n"
        "    register_method('dwa', Over, summary='over dwa', replace=True)\n")  # fmt: skip
    info = tmp_path / "over_dwa-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: over-dwa\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[copi.methods]\nover = over_dwa:register\n")
    (info / "top_level.txt").write_text("over_dwa\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = copi._plugins  # the registry scans entry points once, on its first question
    from copi.methods._registry import REGISTRY

    monkeypatch.setattr(REGISTRY, "_scanned", False)
    copi._plugins._LOADED.clear()
    try:
        spec = method_spec("dwa")
        assert spec.summary == "over dwa" and method_replaced("dwa")
        assert spec.input_hashes()["method_origin"] == "over-dwa 0.1"
    finally:
        unregister_method("dwa")
        sys.modules.pop("over_dwa", None)
        registry._LOADED.clear()
    assert method_spec("dwa").factory is DWA

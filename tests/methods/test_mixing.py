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

"""``make bench``'s page (benchmarks/run.py): a run of some benchmarks keeps the other
sections of the last page as they were, and a name it does not know is refused."""

from __future__ import annotations

import importlib.util
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _load() -> types.ModuleType:
    sys.path.insert(0, str(ROOT))
    try:
        spec = importlib.util.spec_from_file_location("bench_run", ROOT / "benchmarks" / "run.py")
        assert spec is not None and spec.loader is not None
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod
    finally:
        sys.path.remove(str(ROOT))


def test_a_partial_run_keeps_the_other_sections(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    run = _load()
    page = tmp_path / "docs" / "speed-run.md"
    page.parent.mkdir()
    page.write_text("# Speed\n\n## world\n\nold world table\n\n(1 s; goals met)\n\n"
                    "## online\n\nold online table\n\n(2 s; goals MISSED)\n\n"
                    "Goals missed in: online.\n")  # fmt: skip
    monkeypatch.setattr(run, "__file__", str(tmp_path / "benchmarks" / "run.py"))

    def fake_online() -> bool:
        run.RECORD.append("new online table")
        return True

    monkeypatch.setattr(run, "BENCHMARKS", {"world": types.SimpleNamespace(main=None),
                                            "online": types.SimpleNamespace(main=fake_online)})
    assert run.main(["--only", "online"]) == 0
    text = page.read_text()
    assert "old world table" in text and "new online table" in text
    assert "old online table" not in text and text.rstrip().endswith("All goals met.")
    assert text.count("## world") == 1 and text.count("## online") == 1
    with pytest.raises(SystemExit) as stop:
        run.main(["--only", "online,fast"])
    assert stop.value.code == 2 and "unknown benchmark fast" in capsys.readouterr().err

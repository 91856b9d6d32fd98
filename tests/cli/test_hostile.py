"""Hostile input against the newer features (benchmark, lifelong, causal maps, learnt
capabilities, presets, watch, import-movingai, the envs): every case one line, exit 2,
and nothing written or modified. One parametrised table per rule, not one test per case."""

from __future__ import annotations

import errno
import hashlib
import shutil
from pathlib import Path

import pytest

from copi.world import MOVINGAI_ENV, PACKAGED_MAPS
from tests.cli.test_faults import _one_line_error, run


def _snapshot(directory: Path) -> dict[str, str]:
    """Every file below ``directory`` with its content hash (to show nothing changed)."""
    return {
        p.relative_to(directory).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(directory.rglob("*"))
        if p.is_file()
    }


# -- outputs: a derived path never equals an input or the store; no kind replaces another


def _store(path: Path) -> Path:
    from copi.experiments.store import ResultsStore

    ResultsStore(path).close()
    return path


@pytest.mark.parametrize(
    ("args", "message"),
    [
        # the lifelong report and figure are the store's name with .md and .png
        (["lifelong", "{caps}", "-o", "{d}/results.md", "--worlds", "1", "--tasks", "1"],
         "would be both the results store and the report"),
        (["lifelong", "{caps}", "-o", "{d}/results.png", "--worlds", "1", "--tasks", "1"],
         "would be both the results store and the report's figure"),
        # capabilities, reports, worlds and pictures never replace a results store
        (["learn", "-o", "{d}/store.sqlite", "--worlds", "2", "--steps", "20"],
         "store.sqlite exists and holds a results store"),
        (["world", "sample", "-n", "1", "-o", "{d}/store.sqlite"],
         "store.sqlite exists and holds a results store"),
        (["watch", "--method", "straight", "-o", "{d}/store.gif"],
         "store.gif exists and holds a results store"),
        (["world", "import-movingai", str(PACKAGED_MAPS / "mapf" / "empty-32-32.map"),
          "-o", "{d}/store.sqlite"], "store.sqlite exists and holds a results store"),
        # an output that is an input
        (["evaluate", "{caps}", "-o", "{caps}", "--worlds", "1"], "is an input of this command"),
        (["pursuit", "{caps}", "-o", "{caps}", "--games", "1"], "is an input of this command"),
        (["watch", "{caps}", "--method", "copi-learnt", "-o", "{caps}"],
         "-o must end in .gif, .mp4, .png"),
        (["report", "{d}/store.sqlite", "-o", "{d}/store.sqlite"], "is an input of this command"),
        (["report", "{d}/store.sqlite", "-o", "{d}/store.gif"],
         "store.gif exists and is not a directory; expected a directory for the report's"),
        (["benchmark", "-o", "{caps}", "--methods", "straight", "--episodes", "1"],
         "caps.npz exists and is not a directory"),
        (["evaluate", "-o", "{caps}/r.sqlite", "--method", "straight", "--worlds", "1"],
         "caps.npz is a file, not a directory; the results store cannot be written in it"),
    ],
)  # fmt: skip
def test_no_output_destroys_a_store_or_an_input(
    args: list[str], message: str, learnt_caps: Path, tmp_path: Path, capsys
) -> None:
    d = tmp_path / "d"
    d.mkdir()
    caps = d / "caps.npz"
    shutil.copy(learnt_caps, caps)
    for name in ("store.sqlite", "store.gif"):
        _store(d / name)
    before = _snapshot(d)
    filled = [a.format(d=d, caps=caps) for a in args]
    code, _, err = run(filled, capsys)
    line = _one_line_error(code, err)
    assert message in line, line
    assert _snapshot(d) == before  # nothing written, nothing modified


def test_a_failed_write_keeps_the_old_file_and_names_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    # a full disk while the GIF is written: the old GIF stays whole, the error names it
    target = tmp_path / "w.gif"
    code, _, err = run(["watch", "--method", "straight", "--max-steps", "5", "-o", str(target)],
                       capsys)  # fmt: skip
    assert code == 0, err
    old = target.read_bytes()

    from PIL import Image

    def full(self, fp, *args, **kwargs):  # noqa: ANN001
        with open(fp, "wb") as fh:
            fh.write(b"GIF89a")  # half a file, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Image.Image, "save", full)
    code, _, err = run(["watch", "--method", "dwa", "--max-steps", "5", "-o", str(target)], capsys)
    line = _one_line_error(code, err)
    assert line == f"copi: error: {target}: No space left on device"
    assert target.read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.gif"]  # no temporary left


# -- identity: every input that shapes results is part of the run


def test_runs_of_the_maps_family_on_two_map_sets_never_mix(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    other = tmp_path / "other-maps"
    shutil.copytree(PACKAGED_MAPS / "mapf", other / "mapf")
    out = tmp_path / "bmm"
    args = ["benchmark", "-o", str(out), "--families", "maps", "--methods", "straight@map",
            "--workers", "1"]  # fmt: skip
    code, _, err = run([*args, "--episodes", "2"], capsys)
    assert code == 0, err
    before = _snapshot(out)
    monkeypatch.setenv(MOVINGAI_ENV, str(other))
    code, _, err = run([*args, "--episodes", "4"], capsys)
    line = _one_line_error(code, err)
    assert "made with other inputs: the maps family's map set changed since" in line, line
    assert _snapshot(out) == before
    monkeypatch.delenv(MOVINGAI_ENV)
    code, _, err = run([*args, "--episodes", "3"], capsys)  # the same map set resumes
    assert code == 0 and "resuming: 2/3" in err, err

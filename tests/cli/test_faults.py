"""Faults and hostile input at the command line (issue 14): one line and exit 2 for every
bad input, one line and exit 130 for Ctrl-C, no worker outliving its run."""

from __future__ import annotations

import os
import re
import signal
import sqlite3
import subprocess
import sys
import textwrap
import threading
import time
from contextlib import closing
from pathlib import Path

import pytest

import copi
from copi.cli import main
from tests.common import MAPS

# Subprocesses run this copi (also from another working directory) and print no warnings.
_HERE = str(Path(copi.__file__).parents[1])
ENV = {
    **os.environ,
    "PYTHONWARNINGS": "ignore",
    "PYTHONFAULTHANDLER": "1",  # a hung child shows its threads' stacks on SIGABRT
    "PYTHONPATH": os.pathsep.join([_HERE, *filter(None, [os.environ.get("PYTHONPATH")])]),
}


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exit_:
        main(args)
    captured = capsys.readouterr()
    return int(exit_.value.code or 0), captured.out, captured.err


# Progress lines (output not a terminal) may precede the error: "label: done/total (pct),
# ..., elapsed ...". They report work that finished; the error itself is one line.
_PROGRESS = re.compile(r"^.+?: [\d.]+(/[\d.]+ \(\d+ %\))?, .*elapsed [\d.hms ]+$")


def _one_line_error(code: int, err: str) -> str:
    assert code == 2, err
    lines = [ln for ln in err.strip().splitlines() if not _PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith("copi: error: "), err
    assert "Traceback" not in err and ".tmp" not in err
    return lines[0]


@pytest.mark.parametrize(
    "args",
    [
        ["evaluate", "--wrold", "3"],
        ["evaluate", "--worlds", "0", "-o", "x.sqlite"],
        ["evaluate", "--worlds", "many", "-o", "x.sqlite"],
        ["evaluate", "--seed", "-1", "-o", "x.sqlite"],
        ["evaluate", "--guard", "-1", "-o", "x.sqlite"],
        ["learn"],
        ["learn", "-o"],
        ["learn", "-o", "c.npz", "--directions", "four"],
        ["learn", "-o", "c.npz", "--probe-families", "star,nowhere"],
        ["learn", "-o", "c.npz", "--probe-steps", "0"],
        ["learn", "-o", "c.npz", "--probe-label", "held"],
        ["nosuch"],
        ["world", "nosuch"],
        ["world", "sample", "-n", "0", "-o", "w.json"],
        ["pursuit"],
        ["pursuit", "c.npz", "-o", "r.sqlite", "--games", "-3"],
        ["report"],
        ["benchmark"],
        ["reproduce", "-o", "d", "--workers", "0"],
        ["plan"],
    ],
)
def test_option_errors_are_one_line(
    args: list[str], capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)
    _one_line_error(*run(args, capsys)[::2])
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_learning_from_too_little_is_one_line(tmp_path: Path, capsys) -> None:
    out = tmp_path / "c.npz"
    code, _, err = run(["learn", "-o", str(out), "--worlds", "1", "--steps", "1"], capsys)
    assert "at least 2" in _one_line_error(code, err)
    assert not out.exists()


def test_an_unwritable_output_names_the_user_s_path(tmp_path: Path, capsys) -> None:
    target = tmp_path / "w.json"
    target.mkdir()
    code, _, err = run(["world", "sample", "-n", "1", "-o", str(target)], capsys)
    assert _one_line_error(code, err) == (
        f"copi: error: {target} is a directory; expected a file for the world file"
    )


def test_report_of_an_empty_or_foreign_file_changes_nothing(tmp_path: Path, capsys) -> None:
    empty = tmp_path / "empty.sqlite"
    empty.touch()
    code, _, err = run(["report", str(empty), "-o", str(tmp_path / "rep")], capsys)
    assert "empty file" in _one_line_error(code, err)
    assert empty.stat().st_size == 0
    foreign = tmp_path / "foreign.sqlite"
    with sqlite3.connect(foreign) as db:
        db.executescript("CREATE TABLE runs (a); CREATE TABLE episodes (b)")
    before = foreign.read_bytes()
    for args in (["report", str(foreign), "-o", str(tmp_path / "rep")],
                 ["evaluate", "--method", "straight", "--worlds", "1", "-o", str(foreign)]):  # fmt: skip
        code, _, err = run(args, capsys)
        assert "not a copi results store" in _one_line_error(code, err)
    assert foreign.read_bytes() == before


def _start(args: list[str], cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "copi.cli.main", *args],
        cwd=cwd, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=_ctrl_c_as_at_a_terminal,
    )  # fmt: skip


def _stopped(proc: subprocess.Popen[str], timeout: float = 60) -> str:
    """Ctrl-C ``proc`` and wait for it to end; its stderr. A child still running after
    ``timeout`` fails the test with every thread's stack (faulthandler, on SIGABRT)."""
    proc.send_signal(signal.SIGINT)
    try:
        return proc.communicate(timeout=timeout)[1]
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)
        _, err = proc.communicate()
        pytest.fail(f"no exit {timeout:g} s after Ctrl-C; its threads:\n{err}")


def _ctrl_c_as_at_a_terminal() -> None:
    # A job started in the background inherits SIGINT ignored; a terminal's does not.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _wait_for_rows(path: Path, n: int, proc: subprocess.Popen[str], timeout: float = 120) -> int:
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)
        if path.exists():
            try:
                with closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=1)) as db:
                    have = db.execute("SELECT COUNT(*) FROM episodes").fetchone()[0]
            except sqlite3.OperationalError:
                continue
            if have >= n:
                return int(have)
    proc.kill()
    _, err = proc.communicate()  # closes its pipes: no ResourceWarning in a later test
    pytest.fail(f"no {n} rows in time (exit {proc.returncode}): {err}")


@pytest.mark.parametrize("workers", ["1", "2"])
def test_ctrl_c_stops_cleanly_and_says_how_to_resume(tmp_path: Path, workers: str) -> None:
    # Far more episodes than run before the signal (400 take ~4 s on 2 workers, so the
    # resumed run could finish, or be shutting down, when the signal came).
    out = tmp_path / "run.sqlite"
    args = ["evaluate", "--method", "compass-guard", "--worlds", "20000", "--max-steps", "200",
            "-o", str(out), "--workers", workers]  # fmt: skip
    proc = _start(args, tmp_path)
    _wait_for_rows(out, 3, proc)
    err = _stopped(proc)
    assert proc.returncode == 130, err
    # Progress lines (one every 10 s off a terminal) may come first on a slow machine.
    lines = [ln for ln in err.strip().splitlines() if not _PROGRESS.match(ln)]
    assert len(lines) == 1 and "Traceback" not in err, err
    with closing(sqlite3.connect(out)) as db:
        saved = db.execute("SELECT COUNT(*) FROM episodes").fetchone()[0]
    assert lines[0] == (
        f"copi: interrupted: {saved}/20000 episodes saved in {out}; rerun the same command to resume"
    )
    again = _start(args, tmp_path)
    _wait_for_rows(out, saved + 1, again)
    err = _stopped(again)
    assert f"copi: resuming: {saved}/20000 episodes already done in {out}" in err
    assert again.returncode == 130, err


WORKERS_SCRIPT = textwrap.dedent(
    """
    import time
    from copi.runs import make_executor

    with make_executor(2) as pool:
        pids = pool.map(__import__("os").getpid, [None] * 0)  # start the pool
        futures = [pool.submit(time.sleep, 300) for _ in range(2)]
        time.sleep(1.0)
        print(" ".join(str(p) for p in pool._processes), flush=True)
        time.sleep(300)
    """
)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_an_interrupted_pool_stops_its_workers_at_once() -> None:
    from copi.runs import make_executor

    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt), make_executor(2) as pool:
        for _ in range(4):
            pool.submit(time.sleep, 300)
        time.sleep(1.0)  # the workers are in their tasks
        pids = list(pool._processes)  # type: ignore[attr-defined]
        raise KeyboardInterrupt
    assert time.monotonic() - t0 < 20
    assert len(pids) == 2 and not any(_alive(p) for p in pids)
    assert not any(t.is_alive() for t in threading.enumerate()
                   if type(t).__module__.startswith("concurrent.futures"))  # fmt: skip


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_workers_die_with_a_killed_parent(tmp_path: Path) -> None:
    with subprocess.Popen(
        [sys.executable, "-c", WORKERS_SCRIPT], env=ENV, stdout=subprocess.PIPE, text=True
    ) as proc:
        assert proc.stdout is not None
        pids = [int(p) for p in proc.stdout.readline().split()]
        assert len(pids) == 2 and all(_alive(p) for p in pids)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    deadline = time.time() + 10
    while time.time() < deadline and any(_alive(p) for p in pids):
        time.sleep(0.1)
    assert not any(_alive(p) for p in pids), "a worker outlived its killed parent"


def test_movingai_maps_with_diagonally_touching_cells_import(tmp_path: Path, capsys) -> None:
    data = MAPS / "mapf"
    out = tmp_path / "r.json"
    code, text, err = run(
        ["world", "import-movingai", str(data / "random-32-32-20.map"), "-o", str(out)], capsys
    )
    assert code == 0, err
    assert "world 'random-32-32-20'" in text and out.exists()

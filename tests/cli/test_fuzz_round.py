"""A hostile user's cases, each one line and exit 2 with nothing written or lost: another
package's method or family that breaks, inputs that are not files, arrays that claim
terabytes, worlds and maps too large for the planner, empty arguments, outputs that
cannot be written (issue: "Nothing mixed, nothing corrupt accepted, no traceback")."""

from __future__ import annotations

import json
import os
import sqlite3
import zipfile
from pathlib import Path

import numpy as np
import pytest

from copi.core import Agent
from copi.methods import register_method, unregister_method
from copi.world import register_family, unregister_family
from tests.cli.test_faults import _one_line_error, run


def _bad(kind: str) -> type[Agent]:
    class Bad(Agent):
        name = f"bad-{kind}"

        def reset(self, task: object) -> None:
            self.t = 0

        def act(self, obs: object) -> object:
            self.t += 1
            if kind == "raises":
                raise ValueError("boom")
            if kind == "exits":
                raise SystemExit(3)
            if kind == "memory":
                raise MemoryError
            return {"none": None, "scalar": 3.0, "three": np.array([0.5, 0.0, 1.0]),
                    "complex": np.array([0.5 + 1j, 0.0]),
                    "nan": np.array([np.nan, 0.0]) if self.t == 5 else np.array([0.5, 0.0]),
                    }[kind]  # fmt: skip

    return Bad


BROKEN = [
    ("raises", "act at step 1 raised ValueError: boom"),
    ("exits", "act at step 1 called sys.exit(3)"),
    ("memory", "act at step 1 raised MemoryError"),
    ("none", "act returned None at step 1; expected a velocity: 2 real numbers"),
    ("scalar", "act returned 3.0 at step 1; expected a velocity"),
    ("three", "act returned array([0.5, 0. , 1. ]) at step 1; expected a velocity"),
    ("complex", "act returned array([0.5+1.j, 0. +0.j]) at step 1"),
    ("nan", "act returned [nan, 0.0] at step 5; expected a velocity of finite numbers"),
]


@pytest.mark.parametrize(("kind", "message"), BROKEN, ids=[k for k, _ in BROKEN])
def test_a_method_that_breaks_is_named_with_its_step_and_episode(
    kind: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    learnt_caps: Path,
) -> None:  # fmt: skip
    register_method(f"bad-{kind}", _bad(kind), summary="breaks [/x]")
    try:
        commands = {
            "benchmark": ["benchmark", "-o", str(tmp_path / "b"), "--methods",
                          f"bad-{kind}@sensor", "--families", "star", "--episodes", "2",
                          "--workers", "1"],
            "evaluate": ["evaluate", "--method", f"bad-{kind}", "--worlds", "2", "-o",
                         str(tmp_path / "e.sqlite"), "--sensing", "sensor"],
            "lifelong": ["lifelong", str(learnt_caps), "-o", str(tmp_path / "l.sqlite"),
                         "--methods", f"bad-{kind}@sensor:greedy", "--worlds", "1",
                         "--tasks", "2"],
        }  # fmt: skip
        for where, args in commands.items():
            msg = _one_line_error(*run(args, capsys)[::2])
            assert f"method 'bad-{kind}': {message}" in msg, (where, msg)
            assert ("life 0, task 0" if where == "lifelong" else "episode 0 of star") in msg
    finally:
        unregister_method(f"bad-{kind}")


def test_a_family_whose_sampler_raises_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def broken(rng: np.random.Generator, *, name: str | None = None) -> None:
        raise RuntimeError("sampler broke")

    register_family("broken", broken)
    try:
        msg = _one_line_error(*run(["benchmark", "-o", str(tmp_path), "--families", "broken",
                                    "--methods", "dwa@map", "--episodes", "1", "--workers",
                                    "1"], capsys)[::2])  # fmt: skip
        assert "the sampler of family 'broken' raised RuntimeError: sampler broke" in msg
    finally:
        unregister_family("broken")


def test_inputs_that_are_not_regular_files_are_refused_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fifo = tmp_path / "fifo.gif"
    os.mkfifo(fifo)
    for args, what in (
        (["inspect", str(fifo)], "expected a capabilities file"),
        (["inspect", "/dev/zero"], "expected a capabilities file"),
        (["world", "show", str(fifo), "-o", str(tmp_path / "s")], "expected a world file"),
        (["world", "import-movingai", str(fifo), "-o", str(tmp_path / "w.json")],
         "expected a Moving AI map"),
        (["benchmark", "-o", str(tmp_path / "b"), "--world-file", "/dev/zero", "--methods",
          "dwa"], "expected a world file"),
        (["watch", "--method", "dwa", "--family", "star", "--episode", "0", "-o", str(fifo)],
         "holds a device, pipe or socket"),
    ):  # fmt: skip
        msg = _one_line_error(*run(args, capsys)[::2])
        assert ("not a regular file" in msg or "device, pipe or socket" in msg) and what in msg
    assert not (tmp_path / "b").exists()


def test_an_array_claiming_a_terabyte_is_refused_before_it_is_allocated(tmp_path: Path) -> None:
    from copi.baselines import PolicyFormatError, load_policy, packaged_policy

    src = packaged_policy("ppo-mix")
    bomb = tmp_path / "bomb.npz"
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(bomb, "w") as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename == "w0.npy":  # a header claiming 1 TiB of float64, little data
                header = {"descr": "<f8", "fortran_order": False, "shape": (1 << 37,)}
                import io

                buf = io.BytesIO()
                np.lib.format.write_array_header_1_0(buf, header)
                data = buf.getvalue() + b"\0" * 64
            zout.writestr(info.filename, data)
    with pytest.raises(PolicyFormatError, match=r"member 'w0' claims 1,099,511,627,776 bytes"):
        load_policy(bomb)


def test_worlds_and_maps_beyond_the_limits_are_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    huge = tmp_path / "huge.json"
    huge.write_text(json.dumps({"name": "huge", "boundary": [[0, 0], [1e300, 0], [1e300, 1e300],
                                                              [0, 1e300]]}))  # fmt: skip
    msg = _one_line_error(*run(["benchmark", "-o", str(tmp_path / "b1"), "--world-file",
                                str(huge), "--methods", "dwa@map"], capsys)[::2])  # fmt: skip
    assert "coordinates must be within +-1,000,000 agent steps" in msg
    n = 400  # a comb of 400 teeth: tens of thousands of corners for a disc agent
    xs = np.linspace(0, n, 2 * n + 1)
    top = np.column_stack([xs, 50 + 2 * (np.arange(2 * n + 1) % 2)])
    comb = tmp_path / "comb.json"
    ring = np.vstack([[[n, 0]], top[::-1], [[0, 0]]]).tolist()
    comb.write_text(json.dumps({"name": "comb", "boundary": ring, "start": [1, 10],
                                "goal": [n - 1, 10]}))  # fmt: skip
    msg = _one_line_error(*run(["benchmark", "-o", str(tmp_path / "b2"), "--world-file",
                                str(comb), "--methods", "dwa@map"], capsys)[::2])  # fmt: skip
    assert "its visibility graph would test" in msg and "more than the planner's" in msg
    assert not (tmp_path / "b1").exists() and not (tmp_path / "b2").exists()
    board = tmp_path / "checker.map"
    cells = np.where(np.add.outer(np.arange(400), np.arange(400)) % 2 == 0, ".", "@")
    board.write_text("type octile\nheight 400\nwidth 400\nmap\n"
                     + "\n".join("".join(r) for r in cells) + "\n")  # fmt: skip
    msg = _one_line_error(*run(["world", "import-movingai", str(board), "-o",
                                str(tmp_path / "c.json")], capsys)[::2])  # fmt: skip
    assert "its free space has 320,000 corners, more than the 100,000 vertices" in msg


@pytest.mark.parametrize("args", [
    ["benchmark", "-o", "", "--methods", "dwa"],
    ["benchmark", "--output=", "--methods", "dwa"],
    ["evaluate", "--method", "dwa", "-o", ""],
])  # fmt: skip
def test_an_empty_value_is_refused_not_read_as_here(
    args: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    monkeypatch.chdir(tmp_path)
    msg = _one_line_error(*run(args, capsys)[::2])
    assert "an empty value for" in msg and list(tmp_path.iterdir()) == []


def test_the_benchmark_s_figure_is_checked_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "benchmark_success_excess.png").mkdir()
    msg = _one_line_error(*run(["benchmark", "-o", str(tmp_path), "--methods", "dwa@map",
                                "--families", "star", "--episodes", "2"], capsys)[::2])  # fmt: skip
    assert "benchmark_success_excess.png is a directory" in msg
    assert not (tmp_path / "benchmark.sqlite").exists()


def test_rows_of_fewer_episodes_say_so_in_the_overview(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for methods, n in (("dwa@map", "6"), ("straight@map", "2")):
        code, _, err = run(["benchmark", "-o", str(tmp_path), "--methods", methods, "--families",
                            "star,polygon", "--episodes", n, "--workers", "1"], capsys)  # fmt: skip
        assert code == 0, err
    with sqlite3.connect(tmp_path / "benchmark.sqlite") as db:
        assert db.execute("SELECT COUNT(*) FROM episodes").fetchone()[0] == 16
    overview = (tmp_path / "benchmark.md").read_text().split("### Δ success")[0]
    row = next(ln for ln in overview.splitlines() if ln.startswith("| **straight** | map |"))
    assert "n = 2" in row
    assert "n = " not in next(ln for ln in overview.splitlines() if ln.startswith("| dwa | map |"))


def test_a_scheduler_that_never_answers_is_given_up_on_in_seconds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A server of another kind accepts the connection and then says nothing."""
    import socket
    import threading
    import time

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    held: list[socket.socket] = []
    threading.Thread(target=lambda: held.append(server.accept()[0]), daemon=True).start()
    port = server.getsockname()[1]
    t0 = time.monotonic()
    msg = _one_line_error(*run(["benchmark", "-o", str(tmp_path / "b"), "--methods", "dwa@map",
                                "--families", "star", "--episodes", "2", "--scheduler",
                                f"tcp://127.0.0.1:{port}"], capsys)[::2])  # fmt: skip
    for conn in held:
        conn.close()
    server.close()
    assert time.monotonic() - t0 < 10 and "none answered within 5 s" in msg
    assert not (tmp_path / "b").exists()  # refused while the command line was read


def _tampered(src: Path, dst: Path, change: object) -> Path:
    from copi._files import write_npz

    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["metadata"][()]))
    change(arrays, meta)  # type: ignore[operator]
    arrays["metadata"] = np.array(json.dumps(meta))
    return write_npz(dst, arrays)


def _no_templates(a: dict, m: dict) -> None:
    a["red_templates"] = a["red_templates"][:0]


def _long_family(a: dict, m: dict) -> None:
    m["params"]["family"] = "s" * 100_000


def _zero_directions(a: dict, m: dict) -> None:
    a["pol_directions"] = np.zeros_like(a["pol_directions"])


def _huge_directions(a: dict, m: dict) -> None:
    a["pol_directions"] = a["pol_directions"] * 1e300


@pytest.mark.parametrize(("change", "message"), [
    (_no_templates, "no template"),
    (_long_family, "hold text longer than 200 characters"),
    (_zero_directions, "policy directions are not unit vectors"),
    (_huge_directions, "policy directions are not unit vectors"),
])  # fmt: skip
def test_tampered_capabilities_are_refused(
    change: object, message: str, faithful_caps: Path, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    bad = _tampered(faithful_caps, tmp_path / "bad.npz", change)
    msg = _one_line_error(*run(["inspect", str(bad)], capsys)[::2])
    assert message in msg


@pytest.mark.parametrize(("args", "message"), [
    (["learn", "-o", "x.npz", "--worlds", "1000000000"], "worlds must be at most 100,000"),
    (["learn", "-o", "x.npz", "--probe-worlds", "1000000000"], "probe_worlds must be at most"),
    (["learn", "-o", "x.npz", "--epochs", "1000000000"], "epochs must be at most 1,000"),
    (["learn", "-o", "x.npz", "--probe-steps", "1000000000000"], "probe_steps must be at most"),
    (["world", "sample", "-n", "1000000000", "-o", "w.json"], "--count must be at most 20,000"),
    (["watch", "--method", "dwa", "--family", "star", "--episode", "0", "--size", "4096",
      "--max-steps", "400", "-o", "w.gif"], "401 frames would hold 18.8 GB in memory"),
    (["benchmark", "-o", "b", "--methods", "dwa@"], "dwa@: name a level after @"),
    (["benchmark", "-o", "b", "--methods", "dwa:mapping"], "write dwa@sensor:mapping"),
])  # fmt: skip
def test_a_typo_is_not_a_day_of_work(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    monkeypatch.chdir(tmp_path)
    msg = _one_line_error(*run(args, capsys)[::2])
    assert message in msg and list(tmp_path.iterdir()) == []


class _Suicide(Agent):
    """A method whose process dies (as a worker killed by the system would)."""

    def reset(self, task: object) -> None:
        pass

    def act(self, obs: object) -> np.ndarray:
        import signal

        os.kill(os.getpid(), signal.SIGKILL)
        return np.zeros(2)


def test_a_worker_that_dies_is_one_line_and_the_run_resumes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    register_method("dies", _Suicide, summary="kills its own process")
    try:  # forked workers inherit the registration; the parent stays alive
        msg = _one_line_error(*run(["benchmark", "-o", str(tmp_path), "--methods",
                                    "dies@sensor,dwa@map", "--families", "star",
                                    "--episodes", "8", "--workers", "2"], capsys)[::2])  # fmt: skip
        assert "a worker process died (killed, or out of memory)" in msg
        assert "saved in" in msg and "rerun the same command to resume" in msg
    finally:
        unregister_method("dies")

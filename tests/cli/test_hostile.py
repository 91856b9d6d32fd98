"""Hostile input against the newer features (benchmark, lifelong, causal maps, learnt
capabilities, presets, watch, import-movingai, the envs): every case one line, exit 2,
and nothing written or modified. One parametrised table per rule, not one test per case."""

from __future__ import annotations

import errno
import hashlib
import re
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
    from copi.results import ResultsStore

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


# -- files: every member's value within what its meaning allows ---------------------------


def _tampered(src: Path, dst: Path, change) -> Path:  # noqa: ANN001
    """A copy of the capabilities file ``src`` with ``change(arrays, meta)`` applied."""
    import json

    import numpy as np

    from copi._files import write_npz

    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("metadata")[()]))
    change(arrays, meta)
    arrays["metadata"] = np.array(json.dumps(meta))
    write_npz(dst, arrays)
    return dst


def _set(name: str, fn):  # noqa: ANN001, ANN202
    def change(a, meta):  # noqa: ANN001, ANN202
        a[name] = fn(a[name])

    return change


def _param(key: str, value):  # noqa: ANN001, ANN202
    def change(a, meta):  # noqa: ANN001, ANN202
        meta["params"][key] = value

    return change


CAPABILITY_TAMPERING = [
    ("safety net of 1e300", _set("safety_net", lambda x: x * 0 + 1e300), "beyond +-1000"),
    ("safety net of -1e300", _set("safety_net", lambda x: x * 0 - 1e300), "beyond +-1000"),
    ("safety net of zeros", _set("safety_net", lambda x: x * 0), "is all zero"),
    ("a huge safety net", _set("safety_net", lambda x: __import__("numpy").zeros((2, 1000, 129))),
     "training makes (2, 17, 129)"),
    ("safety priors of -1", _set("safety_template", lambda x: x * 0 - 1),
     "probabilities outside [0, 1]"),
    ("safety priors of 5", _set("safety_template", lambda x: x * 0 + 5),
     "probabilities outside [0, 1]"),
    ("negative safety counts", _set("safety_counts", lambda x: -x - 1),
     "counts that are not whole numbers"),
    ("fractional safety counts", _set("safety_counts", lambda x: x + 0.5),
     "counts that are not whole numbers"),
    ("action priors of 2", _set("prior_probabilities", lambda x: x * 0 + 2),
     "probabilities outside [0, 1]"),
    ("max_range 1e308", _param("max_range", 1e308), "max_range must be a number in (0, 1000]"),
    ("agent_radius 50", _param("agent_radius", 50), "agent_radius must be a number in (0, 10]"),
    ("n_rays 0", _param("n_rays", 0), "n_rays must be an int in 4 .. 1024"),
    ("a NaN node", _set("nodes", lambda x: x * float("nan")), "holds NaN or infinite values"),
    ("nodes beyond the range", _set("nodes", lambda x: x * 0 + 1e6), "beyond 10 x the sensor"),
]  # fmt: skip


@pytest.mark.parametrize(("what", "change", "message"), CAPABILITY_TAMPERING,
                         ids=[c[0] for c in CAPABILITY_TAMPERING])  # fmt: skip
@pytest.mark.parametrize("command", ["evaluate", "watch", "inspect", "pursuit"])
def test_tampered_capabilities_are_refused_by_every_command(
    what: str, change, message: str, command: str, learnt_caps: Path, tmp_path: Path, capsys
) -> None:
    bad = _tampered(learnt_caps, tmp_path / "bad.npz", change)
    out = tmp_path / ("out.gif" if command == "watch" else "out.sqlite")
    args = {
        "evaluate": ["evaluate", str(bad), "-o", str(out), "--worlds", "1"],
        "watch": ["watch", str(bad), "-o", str(out), "--max-steps", "3"],
        "inspect": ["inspect", str(bad)],
        "pursuit": ["pursuit", str(bad), "-o", str(out), "--games", "1"],
    }[command]
    line = _one_line_error(*run(args, capsys)[::2])
    assert message in line, line
    assert not out.exists()


# -- numeric options: checked against what a run can do, before anything is written -------

HUGE_SEED = str(2**65)
NUMERIC = [
    (["evaluate", "--method", "dwa", "--seed", HUGE_SEED], "--seed"),
    (["benchmark", "--methods", "dwa", "--seed", HUGE_SEED], "--seed"),
    (["lifelong", "{caps}", "--seed", HUGE_SEED], "--seed"),
    (["pursuit", "{caps}", "--seed", HUGE_SEED], "--seed"),
    (["watch", "--method", "dwa", "--seed", HUGE_SEED], "--seed"),
    (["reproduce", "--seed", HUGE_SEED], "--seed"),
    (["learn", "--seed", HUGE_SEED], "--seed"),
    (["benchmark", "--methods", "dwa", "--episodes", "300000000"],
     "episodes must be at most 100,000"),
    (["evaluate", "--method", "dwa", "--worlds", "1000000000"], "worlds must be at most 100,000"),
    (["evaluate", "--method", "dwa", "--max-steps", "1000000000"], "max_steps must be at most"),
    (["pursuit", "{caps}", "--games", "1000000000"], "games must be at most 100,000"),
    (["pursuit", "{caps}", "--horizon", "1000000000"], "horizon must be at most"),
    (["lifelong", "{caps}", "--tasks", "1000000000"], "tasks must be at most 10,000"),
    (["lifelong", "{caps}", "--worlds", "1000000000"], "worlds must be at most 10,000"),
    (["benchmark", "--methods", "dwa", "--workers", "100000"], "--workers"),
    (["watch", "--method", "dwa", "--size", "1000000"], "--size"),
    (["watch", "--method", "dwa", "--fps", "0"], "--fps"),
    (["evaluate", "--method", "dwa", "--guard", "nan"], "guard"),
    (["evaluate", "--method", "compass-guard", "--guard", "inf"], "guard"),
    (["world", "import-movingai", str(PACKAGED_MAPS / "mapf" / "room-32-32-4.map"),
      "--passage", "nan"], "passage"),
]  # fmt: skip


@pytest.mark.parametrize(("args", "message"), NUMERIC, ids=[" ".join(a[:3]) for a, _ in NUMERIC])
def test_numbers_beyond_what_a_run_can_do_are_refused_first(
    args: list[str], message: str, learnt_caps: Path, tmp_path: Path, capsys, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)
    out = {"watch": "w.gif", "learn": "c.npz", "benchmark": "b", "reproduce": "r",
           "world": "w.json"}.get(args[0], "r.sqlite")  # fmt: skip
    filled = [a.format(caps=learnt_caps) for a in args] + ["-o", out]
    line = _one_line_error(*run(filled, capsys)[::2])
    assert message in line, line
    assert list(tmp_path.iterdir()) == []


# -- presets: enforced wherever a mode is run ----------------------------------------------


@pytest.fixture(scope="module")
def moving_caps(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from copi.learning import LearnParams, learn

    path = tmp_path_factory.mktemp("caps") / "moving.npz"
    learn(LearnParams(worlds=4, steps=100, directions=16, safety=True, motion=True,
                      probe_worlds=4, probe_steps=40, seed=1)).save(path)  # fmt: skip
    return path


PRESET_CASES = [
    (["watch", "{moving}", "--method", "copi-learnt", "-o", "w.gif"],
     "copi-learnt needs 16 directions, safety priors"),
    (["evaluate", "{learnt}", "--preset", "learnt", "--guard", "3", "-o", "r.sqlite"],
     "--guard 3 contradicts --preset learnt (guard 1.05)"),
    (["watch", "{learnt}", "--preset", "learnt", "--guard", "3", "-o", "w.gif"],
     "--guard 3 contradicts --preset learnt"),
    (["pursuit", "{learnt}", "--preset", "learnt", "--guard", "2", "-o", "r.sqlite"],
     "--guard 2 contradicts --preset learnt"),
    (["evaluate", "{learnt}", "--method", "copi-extended", "-o", "r.sqlite"],
     "copi-extended needs 16 directions, no safety priors"),
    (["evaluate", "{learnt}", "--preset", "faithful", "-o", "r.sqlite"],
     "preset faithful needs 4 directions"),
    (["evaluate", "{moving}", "--preset", "learnt", "-o", "r.sqlite"],
     "was learnt for preset learnt-motion"),
    (["pursuit", "{moving}", "-o", "r.sqlite"], "was learnt for learnt-motion"),
    (["lifelong", "{moving}", "-o", "r.sqlite"], "was learnt for preset learnt-motion"),
    (["evaluate", "{learnt}", "--method", "dwa", "--guard", "1", "-o", "r.sqlite"],
     "dwa has no guard"),
    (["watch", "{learnt}", "--preset", "extended", "--method", "copi-learnt", "-o", "w.gif"],
     "--method copi-learnt contradicts --preset extended"),
]  # fmt: skip


@pytest.mark.parametrize(("args", "message"), PRESET_CASES,
                         ids=[" ".join(a[:4]) for a, _ in PRESET_CASES])  # fmt: skip
def test_presets_are_enforced_everywhere(
    args: list[str], message: str, learnt_caps: Path, moving_caps: Path, tmp_path: Path,
    capsys, monkeypatch,
) -> None:  # fmt: skip
    monkeypatch.chdir(tmp_path)
    filled = [a.format(learnt=learnt_caps, moving=moving_caps) for a in args]
    line = _one_line_error(*run(filled, capsys)[::2])
    assert message in line, line
    assert list(tmp_path.iterdir()) == []


# -- Moving AI maps: every header and body refused in one line ------------------------------

MAPS = [
    ("type octile\nheight 4\nwidth -1\nmap\n....\n....\n....\n....\n",
     "height and width must be in 1 .. 8192 cells; got height 4, width -1"),
    ("type octile\nheight 0\nwidth 0\nmap\n", "height and width must be in 1 .. 8192"),
    ("type octile\nheight 100000\nwidth 100000\nmap\n.\n", "height and width must be in"),
    ("type octile\nheight 2\nwidth 2\nmap\n@@\n@@\n", "no passable cell"),
    ("type octile\nheight 2\nwidth 2\nmap\n..\n", "expected 2 map rows; found 1"),
    ("type octile\nheight 2\nwidth 3\nmap\n...\n..\n", "expected 3 cells, as the header's width says; found 2"),
    ("type octile\nheight 1\nwidth 2\nmap\n.?\n", "unknown cell characters ['?']"),
    ("type octile\nheight two\nwidth 2\nmap\n..\n", "integer 'height' and 'width'"),
    ("type octile\nwidth 2\n", "no 'map' line"),
    ("P6\n3 3\n255\n\x00\x01", "bad.map:1: expected 'key value' header or 'map'; got 'P6'"),
    ("\xff\xfe binary", "cannot read a Moving AI map"),
]


@pytest.mark.parametrize(("text", "message"), MAPS, ids=[m for _, m in MAPS])
def test_bad_maps_are_refused_in_one_line(text: str, message: str, tmp_path: Path, capsys) -> None:
    import warnings

    bad = tmp_path / "bad.map"
    bad.write_bytes(text.encode("latin-1"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no stray RuntimeWarning either
        line = _one_line_error(*run(["world", "import-movingai", str(bad), "-o",
                                     str(tmp_path / "w.json")], capsys)[::2])  # fmt: skip
    assert message in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.map"]


# -- the environments: actions and options checked as their checkers expect ---------------


@pytest.mark.parametrize(
    ("actions", "message"),
    [
        ({"evader": [1.0, 0.0]}, "step needs an action for each of pursuer, evader"),
        ({"pursuer": [0.0]}, "step needs an action for each of pursuer, evader"),
        ({"pursuer": [0.0], "evader": [1.0, 0.0, 5.0]}, "the evader's action must be 2"),
        ({"pursuer": [0.0, 1.0], "evader": [1.0, 0.0]}, "the pursuer's action must be 1"),
        ({"pursuer": [float("nan")], "evader": [1.0, 0.0]}, "the pursuer's action must be 1"),
        ({"pursuer": [0.0], "evader": "north"}, "the evader's action must be 2"),
        ({"pursuer": [0.0], "evader": [1, 0], "referee": [0]}, "not among the agents"),
        ([1.0, 0.0], "step needs an action for each"),
    ],
)
def test_the_chauffeur_env_refuses_wrong_actions(actions, message: str) -> None:
    from copi.envs.chauffeur import parallel_env
    from copi.errors import InvalidArgumentError

    env = parallel_env()
    env.reset(seed=0)
    with pytest.raises(InvalidArgumentError, match=re.escape(message)):
        env.step(actions)
    for bad in ("referee", 3):
        with pytest.raises(InvalidArgumentError, match="agent must be one of pursuer, evader"):
            env.action_space(bad)
        with pytest.raises(InvalidArgumentError, match="agent must be one of pursuer, evader"):
            env.observation_space(bad)


# -- reports: the extent of each row shown ---------------------------------------------------


def test_a_row_over_fewer_episodes_says_so(tmp_path: Path, capsys) -> None:
    out = tmp_path / "b"
    base = ["benchmark", "-o", str(out), "--families", "star", "--workers", "1"]
    assert run([*base, "--methods", "straight@map", "--episodes", "6"], capsys)[0] == 0
    code, text, err = run([*base, "--methods", "dwa@map", "--episodes", "2"], capsys)
    assert code == 0, err
    assert "## star (up to 6 episodes; n per row)" in text
    assert "| **straight** | map | route | 6 |" in text and "| dwa | map | route | 2 |" in text


def test_a_lifelong_row_over_fewer_lives_says_so(learnt_caps: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "l.sqlite"
    base = ["lifelong", str(learnt_caps), "-o", str(out), "--tasks", "1", "--workers", "1"]
    assert run([*base, "--methods", "dwa", "--worlds", "3"], capsys)[0] == 0
    code, text, err = run([*base, "--methods", "compass-guard", "--worlds", "1"], capsys)
    assert code == 0, err
    assert "3 worlds (lives; fewer for some rows: see lives)" in text
    rows = [ln for ln in text.splitlines() if ln.startswith("| dwa") or ln.startswith("| compass")]
    assert rows[0].rstrip().endswith("| 3 |") or rows[1].rstrip().endswith("| 3 |")
    assert any(r.rstrip().endswith("| 1 |") for r in rows)

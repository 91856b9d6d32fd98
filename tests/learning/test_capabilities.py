from __future__ import annotations

import itertools
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from copi.errors import CapabilitiesFormatError, InvalidArgumentError
from copi.learning import (
    FORMAT_VERSION,
    Capabilities,
    LearnParams,
    PermutationAutomaton,
    learn,
)

SMALL = LearnParams(worlds=6, steps=150, seed=1)


@pytest.fixture(scope="module")
def caps() -> Capabilities:
    return learn(SMALL)


@settings(
    max_examples=6,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    directions=st.sampled_from([4, 8, 16]),
    learner=st.sampled_from(["astar", "value-iteration"]),
    landmarks=st.none() | st.integers(4, 12),
    seed=st.integers(0, 1000),
)
def test_round_trip(tmp_path: Path, directions, learner, landmarks, seed) -> None:
    params = LearnParams(
        worlds=6, steps=150, seed=seed, directions=directions, learner=learner, landmarks=landmarks
    )
    try:
        c = learn(params)
    except InvalidArgumentError:
        assume(False)  # more landmarks asked than this small map has nodes, or fewer than parts
        return
    path = c.save(tmp_path / f"c{seed}.npz")
    back = Capabilities.load(path)
    assert back.equals(c)
    assert back.summary() == c.summary()
    assert back.params["directions"] == directions


def test_summary_and_online_shortcuts(caps: Capabilities) -> None:
    s = caps.summary()
    assert s["nodes"] == len(caps.nodes) and s["reduced_landmarks"] <= s["landmarks"] <= s["nodes"]
    assert s["policies"] <= 4 * s["reduced_landmarks"]
    assert caps.node_template.shape == (len(caps.nodes),)


def test_every_assignment_is_one_the_papers_automaton_accepts(
    caps: Capabilities, tmp_path: Path
) -> None:
    """Read back from a file: each landmark's (template, g) is accepted by the automaton
    of §II-C with the stored tolerance, and no two templates accept each other."""
    c = Capabilities.load(caps.save(tmp_path / "caps.npz"))
    tol = c.stats["symmetry_tolerance"]
    assert tol == c.stats["stages"][3]["tolerance"] > 0
    fa = PermutationAutomaton.from_operators(c.group.operators)
    red, pts, g = c.reduction, c.landmarks.points, c.group
    merged = 0
    for j in range(c.landmarks.n_landmarks):
        template = pts[red.templates[red.template_of[j]]]
        # accept(chi1, chi2) lists the P with chi2 ~ P . chi1: here template ~ g . landmark
        accepted = {fa.permutation(lab).tobytes() for lab in fa.accept(pts[j], template, tol)}
        assert g.perms[red.element[j]].tobytes() in accepted
        moved = g.apply(int(red.element[j]), pts[j])
        assert np.abs(moved - template).max() == pytest.approx(red.residual[j], abs=1e-12)
        merged += red.templates[red.template_of[j]] != j
    assert merged > 0  # the test above is not vacuous
    for a, b in itertools.combinations(red.templates, 2):
        assert fa.accept(pts[a], pts[b], tol) == []


def _write_npz(path: Path, **arrays) -> Path:
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)
    return path


def test_bad_files_are_refused(caps: Capabilities, tmp_path: Path) -> None:
    good = caps.save(tmp_path / "good.npz")
    raw = good.read_bytes()
    (tmp_path / "trunc.npz").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(CapabilitiesFormatError, match="trunc.npz: not a complete .npz archive"):
        Capabilities.load(tmp_path / "trunc.npz")
    (tmp_path / "text.npz").write_text("hello")
    with pytest.raises(CapabilitiesFormatError, match="text.npz"):
        Capabilities.load(tmp_path / "text.npz")
    foreign = _write_npz(tmp_path / "foreign.npz", weights=np.ones(3))
    with pytest.raises(CapabilitiesFormatError, match="no metadata entry"):
        Capabilities.load(foreign)
    with pytest.raises(CapabilitiesFormatError, match="no such capabilities file"):
        Capabilities.load(tmp_path / "missing.npz")

    def doctored(name: str, change) -> Path:
        with np.load(good, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
        change(arrays)
        return _write_npz(tmp_path / name, **arrays)

    def newer(a):
        meta = json.loads(str(a["metadata"][()]))
        meta["version"] = FORMAT_VERSION + 1
        a["metadata"] = np.array(json.dumps(meta))

    with pytest.raises(CapabilitiesFormatError, match="written by a newer copi"):
        Capabilities.load(doctored("newer.npz", newer))

    def drop(a):
        del a["pol_actions"]

    with pytest.raises(CapabilitiesFormatError, match=r"missing arrays \['pol_actions'\]"):
        Capabilities.load(doctored("drop.npz", drop))

    def other_sensor(a):
        meta = json.loads(str(a["metadata"][()]))
        meta["params"]["n_rays"] = 16
        a["metadata"] = np.array(json.dumps(meta))

    with pytest.raises(CapabilitiesFormatError, match="readings have 32 rays but its sensor 16"):
        Capabilities.load(doctored("sensor.npz", other_sensor))

    def bad_index(a):
        a["lm_node_landmark"] = a["lm_node_landmark"] + 10_000

    with pytest.raises(CapabilitiesFormatError, match="landmark node_landmark must map"):
        Capabilities.load(doctored("index.npz", bad_index))


def test_pickled_objects_are_never_loaded(caps: Capabilities, tmp_path: Path) -> None:
    class Boom:
        def __reduce__(self):
            return (pytest.fail, ("unpickled!",))

    path = tmp_path / "pickle.npz"
    with open(path, "wb") as fh:
        np.savez(fh, metadata=np.array([Boom()], dtype=object))
    with pytest.raises(CapabilitiesFormatError, match="pickle.npz"):
        Capabilities.load(path)


def test_save_is_atomic(caps: Capabilities, tmp_path: Path) -> None:
    path = caps.save(tmp_path / "c.npz")
    before = path.read_bytes()
    with pytest.raises(FileNotFoundError):
        caps.save(tmp_path / "no-such-dir" / "c.npz")
    assert path.read_bytes() == before
    assert zipfile.is_zipfile(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.npz"]

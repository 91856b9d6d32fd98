"""A run's inputs, checked and hashed before anything is written: the one resolver of
every experiment's capabilities files, world file, family data and methods' files.

A run's identity holds the content of its inputs, never their paths, and copi's
version, so that a changed input never resumes into results made from the old one, and
moving a file does not start another run."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from copi._files import file_sha
from copi.errors import InvalidArgumentError, ResultsError
from copi.learning import Capabilities
from copi.methods import check_method_capabilities, make_agent, method_spec
from copi.runs._draw import check_world_file, load_capabilities
from copi.world import family_inputs

__all__ = ["Inputs", "check_family_inputs", "code_version", "resolve_inputs", "run_id"]


def code_version() -> str:
    """The version of copi that computes a run's results (part of every run's identity:
    results from another version are another run)."""
    from copi import __version__

    return __version__


def run_id(identity: Mapping[str, Any]) -> str:
    """A run's id: a hash of its identity (what decides its results)."""
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Inputs:
    """What :func:`resolve_inputs` found: the content hashes of a run's input files."""

    capabilities_sha: dict[str, str]
    """Each capabilities file's, under the name it was given by (a preset's)."""
    world_file_sha: str
    """The world file's ("" without one)."""
    families: dict[str, dict[str, str]]
    """Per family, the data it draws from (:func:`copi.world.family_inputs`)."""
    methods: dict[str, dict[str, str]]
    """Per method, the files it reads (its trained weights, :meth:`MethodSpec.input_hashes`)."""


def resolve_inputs(
    *,
    capabilities: Mapping[str, str] | None = None,
    methods: Iterable[str] = (),
    params: Mapping[str, Mapping[str, Any]] | None = None,
    families: Iterable[str] = (),
    world_file: str | None = None,
    agent_radius: float = 0.3,
) -> Inputs:
    """Check a run's inputs and hash their content, before anything is written.

    Each capabilities file (``capabilities``: path by preset) must load and fit every
    method in ``methods`` that runs on that preset; every method is built once (with
    ``params[method]`` over its registered parameters), so that a file it reads (trained
    weights) is checked; every world of ``world_file`` must
    hold a valid task for an agent of ``agent_radius``. Any failure is one clear error.
    """
    names = list(dict.fromkeys(methods))
    paths = dict(capabilities or {})
    shas: dict[str, str] = {}
    for preset, path in paths.items():
        loaded = Capabilities.load(path)
        for name in names:
            if method_spec(name).capabilities == preset:
                check_method_capabilities(name, loaded, path)
        shas[preset] = file_sha(path)
    for name in names:
        needs = method_spec(name).capabilities
        if needs is not None and needs not in paths:
            raise InvalidArgumentError(f"{name} needs the {needs!r} capabilities file")
        caps = None if needs is None else load_capabilities(paths[needs], shas[needs])
        make_agent(name, caps, **dict((params or {}).get(name, {})))
    world_sha = ""
    if world_file is not None:
        check_world_file(world_file, agent_radius=agent_radius)
        world_sha = file_sha(world_file)
    return Inputs(
        capabilities_sha=shas,
        world_file_sha=world_sha,
        families={f: family_inputs(f) for f in families},
        methods={name: method_spec(name).input_hashes() for name in names},
    )


def check_family_inputs(
    family: str, expected: dict[str, str], world_file: str | None = None
) -> None:
    """Refuse to draw an episode of ``family`` when the data it draws from is no longer
    what the run recorded (e.g. ``$COPI_MOVINGAI`` pointed elsewhere on a worker). A
    world file's content is checked as its worlds are read."""
    if world_file is None and expected and family_inputs(family) != expected:
        raise ResultsError(
            f"the data the {family} family draws from changed during the run "
            f"({', '.join(sorted(expected))} differs); rerun the same command to be told "
            "how it differs from the stored run"
        )

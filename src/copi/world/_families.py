"""World families (placeholder until the family generators land): only ``star``."""

from __future__ import annotations

from copi._rng import Seed
from copi.errors import InvalidArgumentError
from copi.world._generate import random_world
from copi.world._world import World

FAMILIES = ("star",)


def check_family(family: str) -> str:
    if family not in FAMILIES:
        raise InvalidArgumentError(
            f"family must be one of {', '.join(FAMILIES)}; got {family!r}"
        )
    return family


def sample_world(family: str, seed: Seed = None, *, name: str | None = None) -> World:
    check_family(family)
    return random_world(seed, name=name)

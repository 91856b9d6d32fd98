"""What stores written by an older copi call methods: their labels then and now."""

from __future__ import annotations

__all__ = ["LEGACY_NAMES", "split_legacy_name"]


LEGACY_NAMES = {
    "copi-learnt+priors": "copi-learnt-priors",
    "copi-learnt+motion": "copi-learnt-motion",
    "copi-learnt+persist": "copi-learnt-persist",
}
"""Method names of stores written by copi 0.2 and their names now."""


_LEGACY_LIFELONG = {
    "copi-learnt+causal": ("copi-learnt", "sensor", "causal"),
    "copi-learnt+causal+continual": ("copi-learnt-continual", "sensor", "causal"),
    "copi-learnt+mapping": ("copi-learnt", "sensor", "mapping"),
    "compass-guard+mapping": ("compass-guard", "sensor", "mapping"),
    "dwa+mapping": ("dwa", "sensor", "mapping"),
    "copi-learnt@map": ("copi-learnt", "map", "route"),
}


def split_legacy_name(name: str) -> tuple[str, str | None, str | None]:
    """(method, sensing, strategy) of a method label an older store holds, where the
    label carried them (``dwa+mapping``, ``copi-learnt@map``); None where it did not.

    Examples
    --------
    >>> split_legacy_name("dwa+mapping"), split_legacy_name("copi-learnt+priors")
    (('dwa', 'sensor', 'mapping'), ('copi-learnt-priors', None, None))
    """
    if name in _LEGACY_LIFELONG:
        return _LEGACY_LIFELONG[name]
    return LEGACY_NAMES.get(name, name), None, None

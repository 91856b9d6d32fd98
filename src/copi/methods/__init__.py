"""Every navigating method by name: the registry copi's modes, the baselines, the peers
and the bounds are in, and that a user's method joins with one call; arms (a method at a
sensing level with a global strategy); and copi's presets (what ``copi learn --preset``
learns and which method runs it).

A method is an :class:`~copi.core.Agent` class (or any callable returning one) plus one
:func:`register_method` call, in the manner of Gymnasium's ``register``::

    from copi.core import Agent
    from copi.methods import register_method

    class Eastward(Agent):
        name = "eastward"
        def reset(self, task): ...
        def act(self, obs): return np.array([1.0, 0.0])

    register_method("eastward", Eastward, summary="always east (hand-written)")

after which ``copi benchmark --methods eastward`` runs it on the same episodes as every
other method. A package makes its methods known to the command line through the entry
point group ``copi.methods`` (each entry point names a function that registers them;
see :data:`ENTRY_POINTS`). :func:`copi.testing.check_agent` checks a method keeps the
contract.

In an experiment a method runs at a sensing level with a global strategy: an *arm*,
written ``NAME[@LEVEL][:STRATEGY]`` on the command line (:func:`parse_methods`), whose
three fields are stored apart in every result row.
"""

from __future__ import annotations

from copi.methods import _catalogue  # noqa: F401 - registers copi's own methods
from copi.methods._arms import (
    ABLATIONS,
    LIFELONG_METHODS,
    LIFELONG_REFERENCE,
    MethodRun,
    as_arms,
    parse_lifelong_methods,
    parse_methods,
)
from copi.methods._presets import (
    DEFAULT_PRESET,
    PRESETS,
    Preset,
    Resolved,
    check_method_capabilities,
    check_preset_capabilities,
    preset,
    preset_of,
    resolve,
)
from copi.methods._registry import (
    ENTRY_POINTS,
    MethodSpec,
    default_methods,
    make_agent,
    method_names,
    method_replaced,
    method_spec,
    methods_markdown,
    register_method,
    unregister_method,
)

__all__ = [
    "ABLATIONS",
    "DEFAULT_PRESET",
    "ENTRY_POINTS",
    "LIFELONG_METHODS",
    "LIFELONG_REFERENCE",
    "MethodRun",
    "MethodSpec",
    "PRESETS",
    "Preset",
    "Resolved",
    "as_arms",
    "check_method_capabilities",
    "check_preset_capabilities",
    "default_methods",
    "make_agent",
    "method_names",
    "method_replaced",
    "method_spec",
    "methods_markdown",
    "parse_lifelong_methods",
    "parse_methods",
    "preset",
    "preset_of",
    "register_method",
    "resolve",
    "unregister_method",
]

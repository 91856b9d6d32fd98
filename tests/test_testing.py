"""copi.testing.check_agent: every built-in method passes it; broken agents are refused in
one line naming what broke."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from copi.core import Agent
from copi.learning import Capabilities, LearnParams, learn
from copi.methods import method_names, method_spec
from copi.testing import AgentCheckError, check_agent


@pytest.fixture(scope="module")
def caps(learnt_caps: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    small = {
        "faithful": LearnParams(worlds=6, steps=150, directions=4, seed=1),
        "extended": LearnParams(worlds=6, steps=150, directions=16, seed=1),
        "learnt-motion": LearnParams(worlds=6, steps=150, directions=16, safety=True,
                                     motion=True, probe_worlds=6, probe_steps=60, seed=1),
        "predictive": LearnParams(worlds=6, steps=150, directions=16, safety=True,
                                  safety_static=True, predict=True, probe_worlds=6,
                                  probe_steps=60, predict_worlds=4, predict_steps=60, seed=1),
    }  # fmt: skip
    out: dict[str, Any] = {name: learn(p) for name, p in small.items()}
    out["learnt"] = Capabilities.load(learnt_caps)
    return out


BUILT_IN = [n for n in method_names() if method_spec(n).factory.__module__.startswith("copi.")]


@pytest.mark.parametrize("name", [n for n in BUILT_IN if n != "copi-learnt-continual"])
def test_every_built_in_method_passes(name: str, caps: dict[str, Any]) -> None:
    spec = method_spec(name)
    if not spec.available():
        pytest.skip(f"{name} needs the optional extra {spec.requires} (not installed here)")
    check_agent(name, capabilities=caps.get(spec.capabilities or ""), episodes=2, max_steps=40)


def test_the_continual_method_passes_as_a_fresh_agent_per_run(caps: dict[str, Any]) -> None:
    # it grows contexts as it goes: two fresh agents act the same on the same episode
    from copi.methods import make_agent

    check_agent(lambda: make_agent("copi-learnt-continual", caps["learnt"]), episodes=2,
                max_steps=40)  # fmt: skip


class _East(Agent):
    name = "east"

    def reset(self, task: Any) -> None:
        self.t = 0

    def act(self, obs: Any) -> Any:
        self.t += 1
        return np.array([1.0, 0.0])


class _Shape(_East):
    def act(self, obs: Any) -> Any:
        return np.array([1.0, 0.0, 0.0])


class _NaN(_East):
    def act(self, obs: Any) -> Any:
        return np.array([np.nan, 0.0]) if super().act(obs) is not None and self.t > 3 else [0, 0]


class _Complex(_East):
    def act(self, obs: Any) -> Any:
        return np.array([0.5 + 0.5j, 0.0])


class _LateNaN(_East):
    """Goes east well until step 100, then returns NaN (the long hall reaches it)."""

    def act(self, obs: Any) -> Any:
        super().act(obs)
        return np.array([np.nan, 0.0]) if self.t >= 100 else np.array([1.0, 0.0])


class _Peeks(_East):
    """Declares ``sensor`` but reads the map's position."""

    def act(self, obs: Any) -> Any:
        return np.asarray(obs.position) * 0.0


class _Random(_East):
    """Draws from OS entropy: not the same twice."""

    def act(self, obs: Any) -> Any:
        return np.random.default_rng().uniform(-0.5, 0.5, 2)


class _Scribbles(_East):
    def act(self, obs: Any) -> Any:
        obs.ranges[0] = 0.0
        return np.zeros(2)


class _Counters(_East):
    def counters(self) -> Any:
        return {"x": object()}


class _NotAnAgent:
    name = "loose"
    sensing = "sensor"

    def reset(self, task: Any) -> None: ...

    def act(self, obs: Any) -> Any:
        return np.zeros(2)


class _BadLevel(_East):
    sensing = "telepathy"  # type: ignore[assignment]


@pytest.mark.parametrize(
    ("agent", "message"),
    [
        (_Shape, "agent 'east' at level sensor: act returned shape (3,), expected (2,), at step 1"),
        (_NaN, "act returned [nan, 0.0] at step 4 of episode 0: not finite"),
        (_Peeks, "act raised TypeError"),
        (_Complex, "act returned complex128 numbers at step 1 of episode 0, expected real ones"),
        (_Random, "two runs of episode 0 differ at step 1"),
        (_Scribbles, "act changed the observation's ranges in place at step 1"),
        (_Counters, "counters returned values that are not numbers"),
        (_NotAnAgent, "_NotAnAgent is not a copi.core.Agent: subclass it"),
        (_BadLevel, "sensing must be one of sensor, map, oracle, future; got 'telepathy'"),
        (42, "expected an Agent, an Agent factory or a method's name; got int"),
    ],
)
def test_a_broken_agent_is_refused_in_one_line(agent: Any, message: str) -> None:
    with pytest.raises(AgentCheckError) as err:
        check_agent(agent, episodes=2, max_steps=30)
    text = str(err.value)
    assert message in text and "\n" not in text, text


def test_a_velocity_gone_wrong_late_is_found_with_the_default_limit() -> None:
    with pytest.raises(AgentCheckError, match=r"act returned \[nan, 0.0\] at step 100 of "
                       "episode 0: not finite"):  # fmt: skip
        check_agent(_LateNaN)


@pytest.mark.parametrize(("kw", "message"), [
    ({"episodes": 0}, "episodes must be an int in 1 .. 10,000; got 0"),
    ({"max_steps": -5}, "max_steps must be an int in 1 .. 10,000; got -5"),
    ({"max_steps": 2.5}, "max_steps must be an int in 1 .. 10,000; got 2.5"),
])  # fmt: skip
def test_counts_of_the_check_itself_are_checked(kw: dict[str, Any], message: str) -> None:
    with pytest.raises(AgentCheckError, match=message):
        check_agent(_East, **kw)


def test_an_instance_is_checked_through_its_reset() -> None:
    check_agent(_East())  # its state is reset in reset: the same twice

    class Leaky(_East):
        def __init__(self) -> None:
            self.calls = 0

        def act(self, obs: Any) -> Any:
            self.calls += 1  # never reset: the second run differs
            return np.array([1.0, 0.0]) if self.calls < 5 else np.array([0.0, 1.0])

    with pytest.raises(AgentCheckError, match="two runs of episode 0 differ at step"):
        check_agent(Leaky())

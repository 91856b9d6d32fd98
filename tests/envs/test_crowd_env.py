"""Many agents among each other as a PettingZoo ParallelEnv: PettingZoo's own API and seed
tests, what an agent observes, how its episode ends, what is drawn."""

from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test, parallel_seed_test

from copi.envs import CrowdEnv
from copi.envs.crowd import parallel_env
from copi.errors import InvalidArgumentError
from copi.world import RangeSensor


def test_pettingzoo_parallel_api_test_passes() -> None:
    parallel_api_test(CrowdEnv(agents=12, density=0.2, max_steps=40), num_cycles=60)


def test_same_seed_same_episode() -> None:
    parallel_seed_test(lambda: CrowdEnv(agents=10, density=0.2, max_steps=30))


def test_observations_are_the_readings_and_the_goal() -> None:
    env = parallel_env(agents=15, density=0.3)
    obs, infos = env.reset(seed=4)
    crowd = env.crowd
    assert crowd is not None and set(obs) == set(env.possible_agents) and infos["agent_3"] == {}
    others = crowd.positions[1:]
    ranges = RangeSensor().scan(env.room, crowd.positions[0], others, np.full(14, 0.3))
    np.testing.assert_allclose(obs["agent_0"][:32], ranges, rtol=1e-6)
    np.testing.assert_allclose(obs["agent_0"][32:], crowd.goals[0] - crowd.positions[0], rtol=1e-6)
    assert obs["agent_0"].dtype == np.float32 and env.observation_space("agent_0").contains(obs["agent_0"])


def test_agents_end_at_their_goal_or_a_contact_and_the_rest_are_truncated() -> None:
    env = CrowdEnv(agents=30, density=0.4, max_steps=25)
    env.reset(seed=0)
    ended: dict[str, str] = {}
    while env.agents:
        crowd = env.crowd
        assert crowd is not None
        acts = {}
        for a in env.agents:
            i = int(a.split("_")[1])
            d = crowd.goals[i] - crowd.positions[i]
            acts[a] = (d / max(1.0, float(np.hypot(*d)))).astype(np.float32)
        _, rewards, terms, truncs, infos = env.step(acts)
        for a in terms:
            if terms[a]:
                ended[a] = "success" if infos[a]["is_success"] else "collision"
                assert rewards[a] > 5 if infos[a]["is_success"] else rewards[a] < -5
            elif truncs[a]:
                ended[a] = "timeout"
    assert set(ended) == set(env.possible_agents)
    assert {"success", "collision"} <= set(ended.values())
    assert env.crowd is not None and env.crowd.t <= 25


def test_render_draws_agent_0_and_its_goal() -> None:
    env = CrowdEnv(render_mode="rgb_array", agents=8)
    assert CrowdEnv(agents=8).render() is None
    env.reset(seed=2)
    img = env.render()
    assert img is not None and img.shape == (400, 400, 3)
    red = (img[..., 0] > 180) & (img[..., 1] < 80) & (img[..., 2] < 80)
    green = (img[..., 1] > 130) & (img[..., 0] < 90) & (img[..., 2] < 90)
    assert red.any() and green.any()


def test_bad_actions_and_agents_are_refused() -> None:
    env = CrowdEnv(agents=4)
    with pytest.raises(InvalidArgumentError, match="call reset"):
        env.step({})
    env.reset(seed=0)
    with pytest.raises(InvalidArgumentError, match="agent_2's is missing"):
        env.step({"agent_0": [0, 0], "agent_1": [0, 0], "agent_3": [0, 0]})
    with pytest.raises(InvalidArgumentError, match="2 finite numbers"):
        env.step({a: [np.nan, 0] for a in env.agents})
    with pytest.raises(InvalidArgumentError, match="not among the agents"):
        env.step({a: [0, 0] for a in [*env.agents, "agent_9"]})
    with pytest.raises(InvalidArgumentError, match="agent must be one of"):
        env.action_space("agent_4")
    with pytest.raises(InvalidArgumentError, match="render_mode"):
        CrowdEnv(render_mode="human")

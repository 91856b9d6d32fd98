from __future__ import annotations

import re

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import copi  # noqa: F401 - registers the environments
from copi.envs.navigation import NavigationEnv
from copi.errors import InvalidArgumentError
from tests.common import U_TRAP

IDS = sorted(i for i in gymnasium.registry if i.startswith("copi/"))


def test_ids_are_registered() -> None:
    assert "copi/Navigation-v0" in IDS and len(IDS) >= 2


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("render_mode", [None, "rgb_array"])
def test_check_env_passes_without_warnings(env_id: str, render_mode: str | None) -> None:
    # warnings are errors in the test suite (pyproject), so any checker warning fails here
    env = gymnasium.make(env_id, render_mode=render_mode)
    check_env(env.unwrapped)
    env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_same_seed_rollouts_are_identical(env_id: str) -> None:
    def rollout() -> list[tuple]:
        env = gymnasium.make(env_id)
        env.action_space.seed(3)
        obs, _ = env.reset(seed=42)
        out = [(obs.tobytes(),)]
        for _ in range(200):
            obs, r, term, trunc, _ = env.step(env.action_space.sample())
            out.append((obs.tobytes(), r, term, trunc))
            if term or trunc:
                obs, _ = env.reset()
                out.append((obs.tobytes(),))
        return out

    assert rollout() == rollout()


def test_reset_with_a_given_world_and_reward() -> None:
    env = NavigationEnv(obstacles=0)
    obs, info = env.reset(seed=0, options={"world": U_TRAP})
    assert obs.shape == (34,) and obs.dtype == np.float32
    assert obs[32:].tolist() == [0.0, 13.0]
    assert info["world"] == "u-trap"
    obs, reward, term, trunc, info = env.step(np.array([0, 1], dtype=np.float32))
    assert reward == pytest.approx(1.0 - 0.01)
    assert not term and not trunc and not info["contact"]
    obs2, _ = env.reset(seed=0, options={"world": U_TRAP.to_dict()})
    assert obs2[32:].tolist() == [0.0, 13.0]


def test_collision_terminates_or_not() -> None:
    world = U_TRAP.replace(start=[3, 3], goal=[37, 27])
    for terminate in (True, False):
        env = NavigationEnv(obstacles=1, terminate_on_collision=terminate)
        env.reset(seed=0, options={"world": world})
        assert env.sim is not None
        env.sim.centers[0] = [4.0, 3.0]  # put the obstacle right in the agent's way
        env.sim.speed = 0.0
        _, reward, term, _, info = env.step(np.array([1, 0], dtype=np.float32))
        assert info["contact"] and term == terminate and reward < -9


def test_truncation_at_the_step_limit() -> None:
    env = NavigationEnv(obstacles=0, max_steps=5)
    env.reset(seed=0)
    flags = [env.step(np.zeros(2, dtype=np.float32))[3] for _ in range(5)]
    assert flags == [False] * 4 + [True]


def test_bad_construction_and_options() -> None:
    with pytest.raises(InvalidArgumentError, match="render_mode must be one of"):
        NavigationEnv(render_mode="human")
    env = NavigationEnv()
    with pytest.raises(InvalidArgumentError, match="unknown reset options"):
        env.reset(options={"wrld": U_TRAP})
    with pytest.raises(gymnasium.error.ResetNeeded):
        NavigationEnv().step(np.zeros(2, dtype=np.float32))


def test_render_returns_an_image() -> None:
    env = NavigationEnv(render_mode="rgb_array")
    env.reset(seed=1)
    env.step(env.action_space.sample())
    img = env.render()
    assert img is not None and img.shape == (400, 400, 3) and img.dtype == np.uint8
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 5


def test_spec_states_the_step_limit() -> None:
    for env_id in IDS:
        assert gymnasium.spec(env_id).max_episode_steps == 500


@pytest.mark.parametrize("how", ["world", "world_file"])
def test_fixed_worlds_survive_vector_auto_resets(how: str, tmp_path) -> None:
    from copi.world import save_worlds

    worlds = [U_TRAP, U_TRAP.replace(name="u-trap-2", start=None, goal=None)]
    kwargs: dict = {"world": worlds}
    if how == "world_file":
        save_worlds(worlds, tmp_path / "w.json")
        kwargs = {"world_file": str(tmp_path / "w.json")}
    envs = gymnasium.make_vec(
        "copi/Navigation-v0", num_envs=2, vectorization_mode="sync", max_steps=5, **kwargs
    )
    _, info = envs.reset(seed=0)
    seen = set(info["world"])
    for _ in range(40):  # eight auto-resets per sub-environment
        _, _, _, _, info = envs.step(envs.action_space.sample())
        seen.update(w for w in info["world"] if w)
    envs.close()
    assert seen == {"u-trap", "u-trap-2"}


def test_one_fixed_world_and_bad_world_arguments() -> None:
    env = gymnasium.make("copi/NavigationStatic-v0", world=U_TRAP.to_dict())
    assert {env.reset(seed=s)[1]["world"] for s in range(3)} == {"u-trap"}
    with pytest.raises(InvalidArgumentError, match="not both"):
        NavigationEnv(world=U_TRAP, world_file="w.json")
    with pytest.raises(InvalidArgumentError, match="must be a World or its dict; got int"):
        NavigationEnv(world=[U_TRAP, 3])
    for size in (0, 10**6, 2.5, True):
        with pytest.raises(InvalidArgumentError, match=r"width must be an int in 1 \.\. 4096 pixels"):
            NavigationEnv(width=size)
    env = NavigationEnv(world=U_TRAP)
    env.reset(seed=0)
    for bad in ([1.0, 0.0, 3.0], [np.nan, 0.0], "east", [[1.0, 0.0]]):
        with pytest.raises(InvalidArgumentError, match="action must be"):
            env.step(bad)


def test_rgb_array_is_fast_and_sized() -> None:
    import time

    env = NavigationEnv(render_mode="rgb_array", width=64)
    env.reset(seed=2)
    frames = []
    t0 = time.perf_counter()
    for _ in range(30):
        *_, terminated, truncated, _ = env.step(env.action_space.sample())
        frames.append(env.render())
        if terminated or truncated:  # an episode that ended is not stepped on
            env.reset()
    elapsed = time.perf_counter() - t0
    assert all(f is not None and f.shape == (64, 64, 3) for f in frames)
    assert elapsed < 1.0  # >= 30 frames per second, steps included
    wide = NavigationEnv(render_mode="rgb_array", width=120, height=80)
    wide.reset(seed=2)
    img = wide.render()
    assert img is not None and img.shape == (80, 120, 3)


def test_record_video_writes_the_episode(tmp_path) -> None:
    # Gymnasium's RecordVideo needs moviepy to encode; without it, check the frames it
    # would encode (the wrapper's render path) by collecting them with RenderCollection.
    from gymnasium.wrappers import RenderCollection

    try:
        import moviepy  # noqa: F401
    except ImportError:
        env = RenderCollection(
            gymnasium.make("copi/Navigation-v0", render_mode="rgb_array", width=64)
        )
        env.reset(seed=0)
        for _ in range(10):
            env.step(env.action_space.sample())
        frames = env.render()
        assert len(frames) == 11 and frames[0].shape == (64, 64, 3)
        assert not np.array_equal(frames[0], frames[-1])
        return
    from gymnasium.wrappers import RecordVideo

    env = RecordVideo(
        gymnasium.make("copi/Navigation-v0", render_mode="rgb_array", width=64),
        str(tmp_path),
        episode_trigger=lambda _: True,
        disable_logger=True,
    )
    env.reset(seed=0)
    for _ in range(10):
        env.step(env.action_space.sample())
    env.close()
    assert list(tmp_path.glob("*.mp4"))


@pytest.mark.parametrize(("kw", "message"), [
    ({"goal_tolerance": float("nan")}, "goal_tolerance must be a finite number >= 0; got nan"),
    ({"max_steps": 0}, "max_steps must be a positive int; got 0"),
    ({"n_rays": 100_000_000}, "n_rays must be at most 4,096"),
    ({"agent_radius": -1.0}, "agent_radius must be a finite number > 0"),
])  # fmt: skip
def test_bad_settings_are_refused_in_one_line(kw: dict, message: str) -> None:
    import gymnasium

    with pytest.raises(InvalidArgumentError, match=re.escape(message)):
        gymnasium.make("copi/Navigation-v0", **kw)


def test_actions_of_other_kinds_and_steps_after_the_end_are_refused() -> None:
    import gymnasium

    env = gymnasium.make("copi/Navigation-v0", disable_env_checker=True, max_steps=3,
                         obstacles=0)  # fmt: skip
    env.reset(seed=0)
    for action, what in ((np.array([True, False]), "bool"), (np.array([1 + 1j, 0]), "complex")):
        with pytest.raises(InvalidArgumentError, match=f"2 real numbers .* got {what}"):
            env.step(action)
    for _ in range(3):
        *_, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
    assert truncated and not terminated
    with pytest.raises(gymnasium.error.ResetNeeded, match="the episode has ended"):
        env.unwrapped.step(np.zeros(2, dtype=np.float32))
    env.reset(seed=1)  # a new episode steps again
    env.step(np.zeros(2, dtype=np.float32))

"""softevo.env.SoftRobotEnv: the Gymnasium-style interface without gymnasium (spaces, reset,
step, termination) and its reward, whose episode return is the task's fitness."""

import numpy as np
import pytest

import softevo
import softevo.env
from conftest import block_robot


def test_spaces_and_reset():
    env = softevo.env.SoftRobotEnv(block_robot(), seconds=0.1)
    obs, info = env.reset(seed=1)
    assert env.action_space.shape == (2, 2)
    assert env.observation_space.shape == obs.shape == (2 + 0 + 5,)
    assert obs.dtype == np.float32
    assert info["frame"] == 0
    a = env.action_space.sample()
    assert env.action_space.contains(a)


@pytest.mark.parametrize("task,kwargs", [("gait", {}), ("rotate", {}), ("directed", {"direction": 20.0})])
def test_return_is_the_task_fitness(task, kwargs):
    robot = block_robot(directed=task == "directed")
    env = softevo.env.SoftRobotEnv(robot, task=task, seconds=0.25, **kwargs)
    env.reset(seed=0)
    controller = softevo.Controller(robot)
    total, done, steps = 0.0, False, 0
    sim = env.simulation
    obs = sim.observation()
    while not done:
        _, reward, terminated, truncated, info = env.step(controller.act(obs))
        obs = sim.observation()
        total += reward
        steps += 1
        done = terminated or truncated
    assert steps == 15 and truncated and not terminated
    expected = softevo.evaluate(robot, task=task, seconds=0.25, **kwargs).fitness
    assert info["fitness"] == expected
    assert total == pytest.approx(expected, abs=1e-9)


def test_actions_are_clipped_and_seeded_sampling_repeats():
    env = softevo.env.SoftRobotEnv(block_robot(), seconds=0.1)
    env.reset(seed=5)
    first = env.action_space.sample()
    env.reset(seed=5)
    assert np.array_equal(env.action_space.sample(), first)
    obs, reward, terminated, truncated, info = env.step(np.full((2, 2), 7.0))
    assert info["status"] == "ok" and np.isfinite(reward)


def test_is_a_gymnasium_env_when_gymnasium_is_installed():
    try:
        import gymnasium
    except ImportError:
        assert softevo.env.SoftRobotEnv.__mro__[1] is object
        return
    assert issubclass(softevo.env.SoftRobotEnv, gymnasium.Env)


def test_importable_as_documented_and_registered_with_gymnasium():
    """softevo.env after a plain `import softevo` (issue 39: an AttributeError), and the id
    registered with gymnasium (checked with a stand-in module: Debian 12 has no gymnasium)."""
    import subprocess
    import sys
    code = "import softevo; print(softevo.env.SoftRobotEnv.__name__, softevo.env.ENV_ID)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["SoftRobotEnv", "softevo/SoftRobot-v0"]

    class StandIn:
        class envs:
            registry = {}

        @staticmethod
        def register(id, entry_point):
            StandIn.envs.registry[id] = entry_point

    assert softevo.env._register_with_gymnasium(StandIn)
    assert StandIn.envs.registry == {"softevo/SoftRobot-v0": "softevo.env:SoftRobotEnv"}
    StandIn.envs.registry["softevo/SoftRobot-v0"] = "kept"
    softevo.env._register_with_gymnasium(StandIn)  # a second import registers nothing new
    assert StandIn.envs.registry["softevo/SoftRobot-v0"] == "kept"
    assert not softevo.env._register_with_gymnasium(None)


def test_rgb_array_frames_from_the_headless_renderer():
    env = softevo.env.SoftRobotEnv(block_robot(), seconds=0.2, render_mode="rgb_array",
                                   render_size=(160, 120))
    env.reset()
    first = env.render()
    assert first.shape == (120, 160, 3) and first.dtype == np.uint8
    assert len(np.unique(first.reshape(-1, 3), axis=0)) > 10  # a robot on a floor, not blank
    for _ in range(10):
        env.step(np.ones((2, 2), dtype=np.float32))
    assert env.render().shape == (120, 160, 3)
    assert softevo.env.SoftRobotEnv(block_robot(), seconds=0.1).render() is None
    with pytest.raises(ValueError, match="render_mode"):
        softevo.env.SoftRobotEnv(block_robot(), seconds=0.1, render_mode="human")

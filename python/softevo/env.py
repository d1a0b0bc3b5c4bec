"""A Gymnasium-style environment over softevo.Simulation.

    env = softevo.env.SoftRobotEnv(robot)          # config=None, task=None, seconds=None
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

It needs only numpy. When gymnasium is installed (it is not in Debian 12) the class is a real
gymnasium.Env and its spaces are gymnasium.spaces.Box; otherwise they are a small Box with the
same attributes (shape, low, high, dtype, sample()). With gymnasium the environment is also
registered as ENV_ID, so that gymnasium.make("softevo/SoftRobot-v0", robot=robot) works.

Frames for videos: SoftRobotEnv(robot, render_mode="rgb_array").render() gives the current
state as a (height, width, 3) uint8 image from the headless renderer (no display, no GPU).

Action: valve openings in [0, 1], shape (chambers, 2) (inlet, outlet of each chamber), one
60 Hz control frame per step. Observation (float32): the chamber pressures [bar absolute: the
scale of the controller's sensors, kept for learning; Simulation's observation dict gives them
in Pa], the task's
controller inputs (the direction sensor of the directed task), the centroid displacement
[m] (x, y, z), the heading [rad] and the simulated time [s].

Reward: from the task, shaped so that the episode's return is the task's fitness. Each step
gives the change of the task's score so far (the fitness the task would give if the episode
ended now: the observation's fitness_so_far, computed by the task itself); the last step gives
the fitness minus what was rewarded so far. A killed robot scores 0 (terminated); an
episode that runs every frame ends truncated.
"""

from __future__ import annotations


import numpy as np

from . import _softevo

try:
    import gymnasium as _gymnasium
except ImportError:  # gymnasium is optional
    _gymnasium = None


class Box:
    """A box of float32 values (the part of gymnasium.spaces.Box this environment needs)."""

    def __init__(self, low: float, high: float, shape: tuple[int, ...], seed: int | None = None):
        self.shape = tuple(shape)
        self.dtype = np.dtype(np.float32)
        self.low = np.full(self.shape, low, dtype=np.float32)
        self.high = np.full(self.shape, high, dtype=np.float32)
        self._rng = np.random.default_rng(seed)

    def seed(self, seed: int | None = None) -> None:
        """Restart the sampler from `seed`."""
        self._rng = np.random.default_rng(seed)

    def sample(self) -> np.ndarray:
        """A uniform sample (bounded dimensions; unbounded ones from a standard normal)."""
        bounded = np.isfinite(self.low) & np.isfinite(self.high)
        out = self._rng.standard_normal(self.shape).astype(np.float32)
        u = self._rng.uniform(size=self.shape).astype(np.float32)
        out[bounded] = (self.low + u * (self.high - self.low))[bounded]
        return out

    def contains(self, x) -> bool:
        """True if x has the box's shape and lies within its bounds."""
        a = np.asarray(x)
        return a.shape == self.shape and bool(np.all(a >= self.low) and np.all(a <= self.high))

    def __repr__(self) -> str:
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, float32)"


def _box(low: float, high: float, shape: tuple[int, ...]):
    if _gymnasium is not None:
        return _gymnasium.spaces.Box(low=low, high=high, shape=shape, dtype=np.float32)
    return Box(low, high, shape)


_Base = _gymnasium.Env if _gymnasium is not None else object


class SoftRobotEnv(_Base):
    """One robot on one work unit of a task, one control frame per step (see the module
    docstring for the observation, action and reward)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 60}

    def __init__(self, robot: _softevo.Robot, config: _softevo.Config | None = None,
                 task: str | None = None, seconds: float | None = None,
                 direction: float | None = None, unit: int = 0,
                 render_mode: str | None = None, render_size: tuple[int, int] = (480, 360),
                 render_view: str = "side"):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode {render_mode!r}: only None and 'rgb_array' "
                             f"(frames from the headless renderer of `softevo render`)")
        self.render_mode = render_mode
        self._render_size = (int(render_size[0]), int(render_size[1]))
        self._render_view = render_view
        self._sim = _softevo.Simulation(robot, config=config, task=task, seconds=seconds,
                                        direction=direction, unit=unit)
        self.task = self._sim.task
        self.chambers = self._sim.chambers
        obs = self._sim.observation()
        self._task_inputs = len(obs["task_inputs"])
        size = self.chambers + self._task_inputs + 5
        self.observation_space = _box(-np.inf, np.inf, (size,))
        self.action_space = _box(0.0, 1.0, (self.chambers, 2))
        self._rewarded = 0.0
        self._progress = 0.0

    def _vector(self, obs: dict) -> np.ndarray:
        return np.concatenate([
            np.asarray(obs["pressures"], dtype=np.float64) / 1e5,
            np.asarray(obs["task_inputs"], dtype=np.float64),
            obs["centroid"], [obs["heading"], obs["time"]],
        ]).astype(np.float32)

    @staticmethod
    def _progress_of(obs: dict) -> float:
        return float(obs["fitness_so_far"])

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start again from the initial state; returns (observation, info). `seed` reseeds the
        action space's sampler (the simulation itself is deterministic)."""
        if seed is not None:
            self.action_space.seed(seed)
        obs = self._sim.reset()
        self._rewarded = 0.0
        self._progress = self._progress_of(obs)
        return self._vector(obs), {"frame": 0, "status": self._sim.status}

    def step(self, action):
        """One control frame with valve openings `action` ((chambers, 2), clipped to [0, 1]);
        returns (observation, reward, terminated, truncated, info)."""
        valves = np.clip(np.asarray(action, dtype=np.float32), 0.0, 1.0)
        obs, info = self._sim.step(valves)
        terminated = info["status"] != "ok"
        truncated = not terminated and self._sim.done
        if terminated or truncated:
            fitness = self._sim.result().fitness
            reward = fitness - self._rewarded
            info["fitness"] = fitness
        else:
            progress = self._progress_of(obs)
            reward = progress - self._progress
            self._progress = progress
        self._rewarded += reward
        return self._vector(obs), float(reward), terminated, truncated, info

    def render(self):
        """With render_mode="rgb_array": the current state as an RGB frame, a uint8 array
        (height, width, 3) drawn by the headless renderer of `softevo render` (render_size =
        (width, height) pixels, render_view side, top or iso; terrain included). None without
        a render mode (the Gymnasium convention)."""
        if self.render_mode is None:
            return None
        width, height = self._render_size
        return self._sim.render(width, height, self._render_view)

    @property
    def simulation(self) -> _softevo.Simulation:
        """The underlying softevo.Simulation."""
        return self._sim

    def close(self) -> None:
        """Nothing to release (kept for the Gymnasium interface)."""


ENV_ID = "softevo/SoftRobot-v0"  # the id registered with gymnasium, where it is installed


def _register_with_gymnasium(gymnasium) -> bool:
    """Registers SoftRobotEnv as ENV_ID with `gymnasium` (once: an id already there is kept)."""
    if gymnasium is None:
        return False
    registry = getattr(getattr(gymnasium, "envs", None), "registry", {})
    if ENV_ID not in registry:
        gymnasium.register(id=ENV_ID, entry_point="softevo.env:SoftRobotEnv")
    return True


_register_with_gymnasium(_gymnasium)

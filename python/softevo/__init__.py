"""softevo from Python: evaluate, step, learn controllers on and analyse pneumatic soft robots.

The numbers are the C++ numbers, bit for bit: every function calls the same code as the
`softevo` command line (the compiled module softevo._softevo).

    import softevo
    robot = softevo.load_robot("gait-open-01.robot.json")
    result = softevo.evaluate(robot, seconds=2)          # = softevo eval --json --seconds 2
    sim = softevo.Simulation(robot)                      # one 60 Hz control frame per step
    controller = softevo.Controller(robot)
    obs = sim.reset()
    while not sim.done:
        obs, info = sim.step(controller.act(obs))
    run = softevo.open_run("runs/quickstart.h5")         # a run archive
    table = run.individuals()                            # pandas DataFrame (numpy without pandas)

Robots: load_robot, Robot.save, develop.  Configs: load_config, default_config, parse_config,
Config.
Evaluation: evaluate, evaluate_many, EvalResult.  Stepping: Simulation, Controller,
softevo.env.SoftRobotEnv.  Archives: open_run.  Errors: RobotFileError and ConfigError
(ValueError), ArchiveError and OutputFileError (OSError).
"""

from __future__ import annotations

import concurrent.futures
import os
from typing import Iterable, Mapping, Sequence

from . import _softevo
from ._softevo import (  # noqa: F401  (re-exported)
    ArchiveError,
    Config,
    ConfigError,
    Controller,
    EvalResult,
    OutputFileError,
    Robot,
    RobotFileError,
    Simulation,
    evaluate,
    status_name,
)
from ._run import Run, open_run  # noqa: F401

__all__ = [
    "ArchiveError", "Config", "ConfigError", "Controller", "EvalResult", "OutputFileError",
    "Robot", "RobotFileError", "Run", "Simulation", "TASKS", "default_config", "develop",
    "evaluate", "evaluate_many", "load_config", "load_robot", "open_run", "parse_config",
    "status_name",
]

TASKS = ("gait", "directed", "rotate")


def _existing_file(path: str | os.PathLike, what: str) -> str:
    """The path as a string; FileNotFoundError naming it when there is no such file."""
    text = os.fspath(path)
    if not os.path.exists(text):
        raise FileNotFoundError(2, f"{what} not found", text)
    if os.path.isdir(text):
        raise IsADirectoryError(21, f"{what} is a directory", text)
    return text


def load_robot(path: str | os.PathLike) -> Robot:
    """Read a robot file (softevo.robot/1 JSON, docs/model.md §10).

    The reader is strict: an unknown key, a wrong type or a wrong length raises
    RobotFileError (a ValueError) whose message names the file and the key. A missing file
    raises FileNotFoundError.
    """
    return Robot.load(_existing_file(path, "robot file"))


def _override_value(value) -> str:
    """A Python value in TOML value syntax."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_override_value(v) for v in value) + "]"
    raise TypeError(f"override value {value!r}: use a bool, number, string or list")


def _override_list(overrides: Mapping[str, object] | Iterable[str] | None) -> list[str]:
    """{"neat.pop_size": 20} or ["neat.pop_size=20"] as "section.key=value" strings."""
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        return [f"{key}={_override_value(value)}" for key, value in overrides.items()]
    if isinstance(overrides, str):
        return [overrides]
    return [str(o) for o in overrides]


def load_config(path: str | os.PathLike,
                overrides: Mapping[str, object] | Iterable[str] | None = None) -> Config:
    """Read a TOML config strictly, as `softevo config show` does, then apply overrides.

    overrides: {"section.key": value} (Python values) or ["section.key=value"] (TOML syntax).
    An unknown section or key, a wrong type or an out-of-range value raises ConfigError (a
    ValueError) naming the file, line, key and the allowed values; a missing file raises
    FileNotFoundError.
    """
    return _softevo._load_config(_existing_file(path, "config file"), _override_list(overrides))


def default_config(task: str = "gait",
                   overrides: Mapping[str, object] | Iterable[str] | None = None) -> Config:
    """The built-in thesis config for `task` ('gait', 'directed' or 'rotate'), with overrides
    as in load_config()."""
    if task not in TASKS:
        raise ValueError(f"task {task!r} is not one of {', '.join(TASKS)}")
    return _softevo._parse_config("", "<built-in defaults>",
                                  _override_list(overrides) + [f"task.kind={task}"])


def parse_config(text: str, source: str = "<text>",
                 overrides: Mapping[str, object] | Iterable[str] | None = None) -> Config:
    """A config from TOML text (keys not given take their thesis defaults), checked as strictly
    as load_config(); ConfigError messages name `source`."""
    return _softevo._parse_config(text, source, _override_list(overrides))


def develop(genome_or_robot: Robot | bytes, config: Config | None = None) -> Robot:
    """The body developed from a CPPN (docs/model.md §6), as a Robot.

    genome_or_robot: a Robot with a genome section (its CPPN; the robot's controller is kept),
    or an encoded genome as archived (bytes; config required). With a config, its [body]
    settings and materials are used; without, those the robot file's genome records (as
    `softevo develop`). A CPPN that gives no valid body gives a robot with 0 voxels.
    """
    if isinstance(genome_or_robot, (bytes, bytearray)):
        if config is None:
            raise ValueError("develop: an encoded genome needs a config")
        return _softevo._develop_genome(bytes(genome_or_robot), config)
    if not isinstance(genome_or_robot, Robot):
        raise TypeError(f"develop: expected a Robot or bytes, got {type(genome_or_robot).__name__}")
    return _softevo._develop_robot(genome_or_robot, config)


def evaluate_many(robots: Sequence[Robot], config: Config | None = None, task: str | None = None,
                  seconds: float | None = None, integrator: str | None = None,
                  ablate=None, direction: float | None = None,
                  workers: int | None = None) -> list[EvalResult]:
    """evaluate() for every robot, `workers` threads at a time (default: one per CPU).

    The results are in the order of `robots` and equal to evaluating them one by one; the
    threads run in parallel because evaluate() releases the GIL while it simulates.
    """
    robots = list(robots)
    if workers is None:
        workers = os.cpu_count() or 1
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")

    def one(robot: Robot) -> EvalResult:
        return evaluate(robot, config=config, task=task, seconds=seconds, integrator=integrator,
                        ablate=ablate, direction=direction)

    if workers == 1 or len(robots) <= 1:
        return [one(r) for r in robots]
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(one, robots))

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

    for gen in softevo.evolution("configs/quickstart.toml", workers=2):   # evolve robots
        print(gen.generation, gen.best, gen.fitness_unit)

Robots: load_robot, Robot.save, Robot.fabricate, develop.  Configs: load_config, default_config,
parse_config, Config (a read-only Mapping).
Evaluation: evaluate, evaluate_many, EvalResult.  Stepping: Simulation, Controller,
softevo.env.SoftRobotEnv.  Evolution: evolve, evolution, Generation.  Archives: open_run.
Errors: RobotFileError, ConfigError and FabricateError (ValueError), ArchiveError and
OutputFileError (OSError), RunError (RuntimeError).  softevo.__version__: the version.
"""

from __future__ import annotations

import collections.abc
import concurrent.futures
import os
import stat
import sys
from typing import Iterable, Mapping, Sequence

from . import _build_info


def _import_error(error: ImportError) -> ImportError:
    """The ImportError of a package loaded by an interpreter it was not built for (pyenv or
    conda first on PATH), naming both interpreters."""
    built = f"{_build_info.PYTHON_EXECUTABLE} (Python {_build_info.PYTHON_VERSION})"
    this = f"{sys.executable} (Python {sys.version_info.major}.{sys.version_info.minor})"
    if os.path.realpath(sys.executable) != os.path.realpath(_build_info.PYTHON_EXECUTABLE):
        return ImportError(
            f"softevo was built for {built}, but this is {this}: {error}. Run "
            f"{_build_info.PYTHON_EXECUTABLE}, or build the package for this interpreter "
            f"(cmake -DPython_EXECUTABLE={sys.executable}, or pip install . with it; "
            f"docs/guide.md, section Python)")
    return ImportError(f"softevo ({built}) cannot import what it needs: {error} "
                       f"(Debian: apt install python3-numpy)")


try:
    import numpy  # noqa: F401  (the compiled module needs it)
    from . import _softevo
except ImportError as _error:
    raise _import_error(_error) from _error

from ._softevo import (  # noqa: F401  (re-exported)
    ArchiveError,
    Config,
    ConfigError,
    Controller,
    EvalResult,
    FabricateError,
    OutputFileError,
    Robot,
    RobotFileError,
    RunError,
    Simulation,
    evaluate,
    status_name,
)
from ._run import ArchiveIntegrityWarning, Run, open_run  # noqa: F401
from ._evolve import Evolution, Generation, evolution, evolve  # noqa: F401
from . import env  # noqa: F401  (softevo.env.SoftRobotEnv after `import softevo`, as documented)

__version__ = _build_info.VERSION

__all__ = [
    "ArchiveError", "ArchiveIntegrityWarning", "Config", "ConfigError", "Controller", "EvalResult",
    "Evolution", "FabricateError", "Generation", "OutputFileError", "Robot", "RobotFileError",
    "Run", "RunError", "Simulation",
    "TASKS", "__version__", "default_config", "develop", "evaluate", "evaluate_many", "evolution",
    "evolve", "load_config", "load_robot", "open_run", "parse_config", "status_name",
]

TASKS = _softevo.TASKS  # the registered tasks, in registration order (tasks/registry.cpp)


def _existing_file(path: str | os.PathLike, what: str,
                   error: type[Exception] = ValueError) -> str:
    """The path as a string; FileNotFoundError naming it when there is no such file."""
    text = os.fspath(path)
    if not os.path.exists(text):
        raise FileNotFoundError(2, f"{what} not found", text)
    if os.path.isdir(text):
        raise IsADirectoryError(21, f"{what} is a directory", text)
    # A FIFO would block the open below forever, a device (/dev/zero) would be read without end.
    if not stat.S_ISREG(os.stat(text).st_mode):
        raise error(f"{text}: not a regular file (a FIFO, socket or device), not a {what}")
    return text


# The first bytes of files that are often opened by mistake, and what they are.
_FILE_KINDS = (
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file (a run archive or a trace), not a robot file: "
                             "softevo.open_run(path).genome(id) gives a robot of a run archive, "
                             "`softevo export RUN.h5 --best` writes one"),
    (b"\x89PNG", "a PNG image, not a robot file"),
    (b"PK\x03\x04", "a zip archive, not a robot file"),
    (b"\x1f\x8b", "a gzip file, not a robot file"),
)


def load_robot(path: str | os.PathLike) -> Robot:
    """Read a robot file (softevo.robot/1 JSON, docs/model.md §10).

    The reader is strict: an unknown key, a wrong type or a wrong length raises
    RobotFileError (a ValueError) whose message names the file and the key; a file of another
    kind (a run archive, an image) raises RobotFileError naming the file and what it is. A
    missing file raises FileNotFoundError.
    """
    text = _existing_file(path, "robot file", RobotFileError)
    with open(text, "rb") as f:
        head = f.read(16)
    for magic, what in _FILE_KINDS:
        if head.startswith(magic):
            raise RobotFileError(f"{text}: {what}")
    if head.lstrip()[:1] not in (b"{", b""):
        raise RobotFileError(f"{text}: not a robot file (softevo.robot/1 is JSON text that "
                             f"starts with '{{'; this file starts with {head[:8]!r})")
    try:
        return Robot.load(text)
    except RobotFileError as e:
        if str(e):
            raise
        raise RobotFileError(f"{text}: not a valid softevo.robot/1 file") from e


def _robot_save(self: Robot, path: str | os.PathLike, overwrite: bool = False) -> None:
    """Write the robot file atomically. An existing file is replaced only with overwrite=True
    (as the command line's --force); OutputFileError (an OSError) for an existing file without
    it, a symlink or a special file."""
    self._save(os.fspath(path), overwrite)


Robot._save = Robot.save
Robot.save = _robot_save


def _robot_fabricate(self: Robot, path: str | os.PathLike | None = None, *,
                     format: str = "", scale: float = 1.0, channel_diameter: float = 1.5,
                     slices: str | os.PathLike | None = None,
                     dpi: str | Sequence[float] = (600, 300),
                     layer_um: float = 30.0, mold: str | os.PathLike | None = None,
                     wall: float = 3.0, split: str | float | None = None,
                     force: bool = False) -> dict:
    """Export the robot for 3-D printing and silicone casting, as `softevo fabricate` does
    (docs/fabrication.md), with the same options in the same units:

    path: OUT.3mf (one object per material group) or OUT.stl (OUT-<group>.stl each), or None;
    format: "3mf" or "stl" (default: by the extension); scale: printed voxel edge = voxel_size
    x scale; channel_diameter: inlet channel side [mm]; slices: directory of material-per-pixel
    PNG layers, dpi (X, Y) and layer_um [um] their pitch; mold: directory of the two-part mold
    and its cores, wall [mm] of mold material, split: "z=HEIGHT" or HEIGHT [mm above the body's
    bottom] (default: the widest section); force: replace existing files.

    Returns a dict: files written, slices (count), voxels, chambers, groups (name, voxels,
    triangles, volume_mm3), channel_volume_mm3, split_z_mm, summary. FabricateError (a
    ValueError) names the keyword argument or chamber on bad input; nothing is written then.
    """
    if not isinstance(dpi, str):
        dpi = ",".join(repr(float(v)) for v in dpi)
    if split is not None and not isinstance(split, str):
        split = f"z={float(split)!r}"
    return self._fabricate(os.fspath(path) if path is not None else "", format, float(scale),
                           float(channel_diameter),
                           os.fspath(slices) if slices is not None else "", dpi,
                           float(layer_um), os.fspath(mold) if mold is not None else "",
                           float(wall), split or "", bool(force))


Robot.fabricate = _robot_fabricate


class _ConfigMapping(collections.abc.Mapping):
    """The Mapping methods of Config: its resolved keys as "section.key" -> value."""

    def _flat(self) -> dict:
        import tomllib

        flat = {}
        for section, keys in tomllib.loads(self.text).items():
            for key, value in keys.items():
                flat[f"{section}.{key}"] = value
        return flat

    def __getitem__(self, key: str):
        flat = self._flat()
        if key not in flat:
            raise KeyError(f"{key!r} is not a config key (section.key, e.g. 'neat.pop_size'; "
                           f"list(config) names them)")
        return flat[key]

    def __iter__(self):
        return iter(self._flat())

    def __len__(self) -> int:
        return len(self._flat())


# Config is a read-only Mapping of its resolved keys (every key, defaults included, as the
# canonical text gives them: pressures in bar as in config files, everything else SI).
for _name in ("__getitem__", "__iter__", "__len__", "__contains__", "keys", "items", "values",
              "get", "_flat"):
    setattr(Config, _name, getattr(_ConfigMapping, _name))
collections.abc.Mapping.register(Config)


def _eval_result_to_dict(self: EvalResult) -> dict:
    """The result as plain Python values (the fields of `softevo eval --json`'s result)."""
    return {
        "fitness": self.fitness, "status": self.status, "killed": self.killed,
        "message": self.message, "task": self.task, "config_source": self.config_source,
        "components": [dict(c) for c in self.components], "steps": self.steps,
        "voxels": self.voxels, "chambers": self.chambers, "sim_seconds": self.sim_seconds,
        "wall_seconds": self.wall_seconds,
    }


EvalResult.to_dict = _eval_result_to_dict


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
    kinds = 'a dict {"section.key": value} or a list of "section.key=value" strings'
    if isinstance(overrides, Mapping):
        for key in overrides:
            if not isinstance(key, str):
                raise TypeError(f"overrides: {kinds}; the key {key!r} "
                                f"({type(key).__name__}) is not a string")
        return [f"{key}={_override_value(value)}" for key, value in overrides.items()]
    if isinstance(overrides, str):
        return [overrides]
    if not isinstance(overrides, collections.abc.Iterable):
        raise TypeError(f"overrides: {kinds}, not {type(overrides).__name__}")
    items = list(overrides)
    for item in items:
        if not isinstance(item, str):
            raise TypeError(f"overrides: {kinds}; the item {item!r} "
                            f"({type(item).__name__}) is not a string")
    return items


def load_config(path: str | os.PathLike,
                overrides: Mapping[str, object] | Iterable[str] | None = None) -> Config:
    """Read a TOML config strictly, as `softevo config show` does, then apply overrides.

    overrides: {"section.key": value} (Python values) or ["section.key=value"] (TOML syntax).
    An unknown section or key, a wrong type or an out-of-range value raises ConfigError (a
    ValueError) naming the file, line, key and the allowed values; a missing file raises
    FileNotFoundError.
    """
    return _softevo._load_config(_existing_file(path, "config file", ConfigError),
                                 _override_list(overrides))


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

"""Read-only access to softevo run archives (HDF5, format "softevo.run/1", docs/archive.md).

Used by figures.py and lineage.py. Only h5py and numpy (Debian: python3-h5py, python3-numpy).
"""

from __future__ import annotations

import dataclasses
import pathlib
import tomllib
from typing import Iterator

import h5py
import numpy as np

ARCHIVE_FORMAT = "softevo.run/1"
EXPERIMENTS = ("gait-open", "gait-closed", "dir-open", "dir-closed")
STATUS_NAMES = {
    0: "ok",
    1: "killed: flipped",
    2: "killed: exploded",
    3: "diverged",
    4: "failed",
    5: "timeout",
    6: "invalid body",
}


class ArchiveError(Exception):
    """An archive that is missing, foreign or malformed; the message names the file."""


def _text(value) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray) and value.shape == ():
        return _text(value[()])
    return str(value)


def experiment_from_config(config_text: str) -> str:
    """"gait-open" etc. from the resolved TOML config (task.kind, task.control)."""
    task = tomllib.loads(config_text).get("task", {})
    kind = task.get("kind", "gait")
    control = task.get("control", "open")
    prefix = {"gait": "gait", "directed": "dir"}.get(kind)
    if prefix is None or control not in ("open", "closed"):
        raise ValueError(f"config task.kind={kind!r} task.control={control!r} is not an experiment")
    return f"{prefix}-{control}"


@dataclasses.dataclass
class Generation:
    """One generation's table: one row per individual, sorted by id."""

    number: int
    id: np.ndarray
    parent1: np.ndarray
    parent2: np.ndarray
    species: np.ndarray
    status: np.ndarray
    fitness: np.ndarray
    voxels: np.ndarray
    chambers: np.ndarray

    def row_of(self, individual: int) -> int | None:
        i = int(np.searchsorted(self.id, individual))
        return i if i < len(self.id) and self.id[i] == individual else None


class Run:
    """One run archive, opened read-only for the lifetime of the object."""

    def __init__(self, path: str | pathlib.Path):
        self.path = pathlib.Path(path)
        try:
            self._file = h5py.File(self.path, "r")
        except (OSError, ValueError) as e:
            raise ArchiveError(f"{self.path}: cannot open as HDF5: {e}") from e
        fmt = _text(self._file.attrs.get("format", ""))
        if fmt != ARCHIVE_FORMAT:
            self._file.close()
            raise ArchiveError(f"{self.path}: format {fmt!r} is not {ARCHIVE_FORMAT!r}")
        self.attrs = {k: (_text(v) if isinstance(v, (bytes, str)) else v)
                      for k, v in self._file.attrs.items()}
        self.config_text = _text(self._file["config"][()]) if "config" in self._file else ""
        experiment = _text(self.attrs.get("experiment", ""))
        if experiment not in EXPERIMENTS:
            if not self.config_text:
                raise ArchiveError(f"{self.path}: no experiment attribute and no /config")
            try:
                experiment = experiment_from_config(self.config_text)
            except (ValueError, tomllib.TOMLDecodeError) as e:
                raise ArchiveError(f"{self.path}: /config: {e}") from e
        self.experiment = experiment
        self.seed = int(self.attrs.get("seed", -1))
        self.state = _text(self.attrs.get("state", "unknown"))
        group = self._file.get("generations")
        self.generation_numbers = sorted(int(name) for name in group.keys()) if group else []

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def generation(self, number: int) -> Generation:
        name = f"generations/{number:06d}"
        if name not in self._file:
            raise ArchiveError(f"{self.path}: no generation {number}")
        g = self._file[name]

        def column(key: str, dtype) -> np.ndarray:
            if key not in g:
                raise ArchiveError(f"{self.path}: /{name} has no dataset {key!r}")
            return np.asarray(g[key][()], dtype=dtype)

        gen = Generation(
            number=number,
            id=column("id", np.int64),
            parent1=column("parent1", np.int64),
            parent2=column("parent2", np.int64),
            species=column("species", np.int64),
            status=column("status", np.uint8),
            fitness=column("fitness", np.float64),
            voxels=column("voxels", np.int64),
            chambers=column("chambers", np.int64),
        )
        n = len(gen.id)
        for key in ("parent1", "parent2", "species", "status", "fitness", "voxels", "chambers"):
            if len(getattr(gen, key)) != n:
                raise ArchiveError(f"{self.path}: /{name}/{key} has {len(getattr(gen, key))} rows, id has {n}")
        if n > 1 and np.any(np.diff(gen.id) <= 0):
            raise ArchiveError(f"{self.path}: /{name}/id is not strictly ascending")
        return gen

    def generations(self) -> Iterator[Generation]:
        for number in self.generation_numbers:
            yield self.generation(number)

    def fitness_curves(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(generation numbers, population mean fitness, best fitness) per generation."""
        gens, means, bests = [], [], []
        for gen in self.generations():
            if len(gen.fitness) == 0:
                continue
            gens.append(gen.number)
            means.append(float(np.mean(gen.fitness)))
            bests.append(float(np.max(gen.fitness)))
        return np.array(gens, dtype=np.int64), np.array(means), np.array(bests)


def find_runs(folder: str | pathlib.Path) -> tuple[list[Run], list[str]]:
    """Every run archive under `folder` (recursive, *.h5 / *.hdf5), sorted by path, plus a
    message for every HDF5 file that is not a run archive (traces, broken files)."""
    runs: list[Run] = []
    skipped: list[str] = []
    root = pathlib.Path(folder)
    # RUN.h5.d/ holds the per-generation segments of a run still writing (docs/archive.md): they
    # are read through RUN.h5's links, not as archives of their own.
    paths = sorted(p for p in root.rglob("*") if p.suffix.lower() in (".h5", ".hdf5") and p.is_file()
                   and not p.parent.name.endswith((".h5.d", ".hdf5.d")))
    for p in paths:
        try:
            runs.append(Run(p))
        except ArchiveError as e:
            skipped.append(str(e))
    return runs, skipped

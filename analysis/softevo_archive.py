"""The run archives of an experiment grid, read through the softevo package (softevo.open_run,
the C++ archive reader), in the shape figures.py works with: per-generation numpy columns."""

from __future__ import annotations

import dataclasses
import pathlib
from typing import Iterator

import numpy as np

import softevo

# The thesis grid's experiments, in table order; any other experiment name (gait-rough-open,
# rotate-open, ...) is accepted too and sorts after them.
EXPERIMENTS = ("gait-open", "gait-closed", "dir-open", "dir-closed", "gait-rough-open",
               "gait-rough-closed", "dir-rough-open", "dir-rough-closed")
ArchiveError = softevo.ArchiveError


def experiment_from_config(config_text: str) -> str:
    """"gait-open" etc. from a config text (task.kind, task.control; other keys default)."""
    return softevo.parse_config(config_text, "<config>").experiment


def status_name(code: int) -> str:
    """The name of an archived status code."""
    return softevo.status_name(int(code))


@dataclasses.dataclass
class Generation:
    """One generation's table: one row per individual, sorted by id."""

    number: int
    id: np.ndarray
    status: np.ndarray
    fitness: np.ndarray
    voxels: np.ndarray
    chambers: np.ndarray


class Run:
    """One run archive and its experiment (root attribute `experiment`, else from /config).
    `verify`: run `softevo info`'s integrity checks first and refuse an archive that fails them
    (ArchiveError naming every problem); False reads a damaged or hand-made archive anyway."""

    def __init__(self, path: str | pathlib.Path, verify: bool = True):
        self.path = pathlib.Path(path)
        try:
            self.run = softevo.open_run(self.path, verify=verify)
            self.experiment = self.run.info["experiment"] or self.run.config.experiment
        except (OSError, ValueError) as e:
            raise ArchiveError(f"{self.path}: {e}") from e
        if not self.experiment:
            raise ArchiveError(f"{self.path}: no experiment name (root attribute or /config)")
        # The config without run length and seed: runs with equal hashes are repetitions of
        # one experiment (computed from /config for archives that predate the attribute).
        self.experiment_hash = str(self.run.info.get("experiment_hash", ""))
        self.seed = int(self.run.info["seed"])
        self.state = self.run.info["state"]
        table = self.run.individuals()
        self._columns = {k: np.asarray(table[k]) for k in
                         ("generation", "id", "status_code", "fitness", "voxels", "chambers",
                          "reused_from")}
        # Controller learning (docs/model.md §8.11): fitness before learning, evaluations spent
        # per body and the learning curves; None for a run without learning.
        self.learning = None
        names = table.columns if hasattr(table, "columns") else table.dtype.names
        if "learn_evaluations" in names:
            self.learning = {k: np.asarray(table[k]) for k in
                             ("fitness_before", "learn_evaluations")}
            self.learning["learning_curve"] = list(table["learning_curve"])
        # work units per genome (directed: one per direction), for counting evaluations
        self.units = int(self.run._all_columns().get("units", 1)) or 1
        self.generation_numbers = self.run.generations

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        pass  # the package's reader holds nothing that needs closing early

    def generation(self, number: int) -> Generation:
        rows = self._columns["generation"] == number
        if not np.any(rows) and number not in self.generation_numbers:
            raise ArchiveError(f"{self.path}: no generation {number}")
        c = {k: v[rows] for k, v in self._columns.items()}
        return Generation(number, c["id"], c["status_code"], c["fitness"], c["voxels"],
                          c["chambers"])

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


def evaluations_per_generation(run: Run) -> tuple[np.ndarray, np.ndarray]:
    """(generation numbers, work units simulated in each generation): the rows evaluated in
    their generation (reused_from = -1), each the evaluations its body spent learning in a
    learning run, else one per work unit of the task."""
    c = run._columns
    gens = np.array(run.generation_numbers, dtype=np.int64)
    fresh = c["reused_from"] == -1
    if run.learning is not None:
        per_row = run.learning["learn_evaluations"] * fresh
    else:
        per_row = fresh.astype(np.int64) * run.units
    counts = np.array([int(per_row[c["generation"] == g].sum()) for g in gens], dtype=np.int64)
    return gens, counts


def find_runs(folder: str | pathlib.Path, verify: bool = True) -> tuple[list[Run], list[str]]:
    """Every run archive under `folder` (recursive, *.h5 / *.hdf5), sorted by path, plus a
    message for every HDF5 file that is not a run archive (traces, broken files) or, with
    `verify`, fails the integrity checks."""
    runs: list[Run] = []
    skipped: list[str] = []
    root = pathlib.Path(folder)
    # RUN.h5.d/ holds the per-generation segments of a run still writing (docs/archive.md): they
    # are read through RUN.h5's links, not as archives of their own.
    paths = sorted(p for p in root.rglob("*") if p.suffix.lower() in (".h5", ".hdf5") and p.is_file()
                   and not p.parent.name.endswith((".h5.d", ".hdf5.d")))
    for p in paths:
        try:
            runs.append(Run(p, verify=verify))
        except ArchiveError as e:
            skipped.append(str(e))
    return runs, skipped

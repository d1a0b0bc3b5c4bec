"""Run archives (softevo.run/1, docs/archive.md) through the C++ reader (io::Archive)."""

from __future__ import annotations

import numbers
import os
import warnings

import numpy as np

from . import _softevo

_FIXED_COLUMNS = ("generation", "id", "parent1", "parent2", "status_code",
                  "fitness", "voxels", "chambers", "wall_seconds", "worker_rank")


def _pandas():
    """The pandas module, or None when it does not import."""
    try:
        import pandas
    except ImportError:
        return None
    return pandas


def _whole_number(method: str, name: str, value, optional: bool = False) -> int | None:
    """`value` of argument `name` of Run.`method` as an int: TypeError naming both for anything
    but an integer (a float, a string, a bool; None too unless `optional`), ValueError beyond the
    archive's 64-bit ids and generations. int() alone would truncate 3.7 to 3 and take "3"."""
    if value is None and optional:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        kind = "an int or None" if optional else "an int"
        raise TypeError(f"Run.{method}: {name} must be {kind}, not {type(value).__name__} "
                        f"({value!r})")
    if not -2**63 <= int(value) < 2**63:
        raise ValueError(f"Run.{method}: {name} = {int(value)} is beyond 64 bits")
    return int(value)


def _table(columns: dict[str, np.ndarray], names: list[str]):
    """A pandas DataFrame of the columns in this order when pandas imports, else a numpy
    structured array."""
    pandas = _pandas()
    if pandas is not None:
        return pandas.DataFrame({n: columns[n] for n in names})
    n = len(columns[names[0]]) if names else 0
    dtype = [(name, columns[name].dtype) for name in names]
    out = np.empty(n, dtype=dtype)
    for name in names:
        out[name] = columns[name]
    return out


# The methods that read the archive (a closed Run refuses them).
_ARCHIVE_USERS = frozenset(("info", "config", "generations", "individuals", "stats", "genome",
                            "best", "lineage", "fitness_digest", "verify", "_all_columns"))


class ArchiveIntegrityWarning(UserWarning):
    """open_run(path, verify="warn") found an archive that fails its integrity checks."""


def _integrity_message(path: str, report: dict) -> str:
    n = len(report["problems"])
    return (f"{path}: integrity FAILED: {n} problem(s); generations 0.."
            f"{report['consistent_generations'] - 1} consistent (`softevo info` reports the "
            f"same; open_run(path, verify=False) reads it anyway)\n{report['description']}")


class Run:
    """One run archive, opened read-only (see softevo.open_run). A context manager: `with
    softevo.open_run(path) as run:` closes the file at the end of the block."""

    def __init__(self, path: str | os.PathLike, verify: bool | str = True):
        if verify not in (True, False, "warn"):
            raise ValueError(f"verify must be True, False or 'warn', not {verify!r}")
        text = os.fspath(path)
        if not os.path.exists(text):
            raise FileNotFoundError(2, "run archive not found", text)
        self.path = text
        self._archive = _softevo.Archive(text)
        self._columns = None
        if verify:
            report = self._archive.check()
            if not report["ok"]:
                if verify == "warn":
                    warnings.warn(_integrity_message(text, report), ArchiveIntegrityWarning,
                                  stacklevel=3)
                else:
                    self._archive = None
                    raise _softevo.ArchiveError(_integrity_message(text, report))

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Closes the archive file; any further use raises ValueError."""
        self._archive = None
        self._columns = None

    @property
    def closed(self) -> bool:
        """True once close() was called (or the with block ended)."""
        return self._archive is None

    def __getattribute__(self, name):
        if name in _ARCHIVE_USERS and object.__getattribute__(self, "_archive") is None:
            raise ValueError(f"{object.__getattribute__(self, 'path')}: the run archive is closed")
        return object.__getattribute__(self, name)

    def __repr__(self) -> str:
        if self._archive is None:
            return f"<softevo.Run {self.path!r}: closed>"
        info = self.info
        return (f"<softevo.Run {self.path!r}: {info['experiment']}, "
                f"{info['generations_done']} generations, {info['state']}>")

    @property
    def info(self) -> dict:
        """The root attributes: format, version, git_commit, seed, ranks, host, start_time,
        end_time, config_hash, experiment, state, generations_done, physics_revision,
        stop_reason ("" unless the run stopped on its own, e.g. every evaluation failed)."""
        return self._archive.info

    @property
    def config(self) -> _softevo.Config:
        """The archived config (/config), parsed strictly; ConfigError names the archive."""
        return _softevo._parse_config(self._archive.config_text, f"{self.path}:/config", [])

    @property
    def generations(self) -> list[int]:
        """The archived generation numbers, ascending."""
        return list(self._archive.generations)

    def _all_columns(self) -> dict:
        if self._columns is None:
            self._columns = self._archive.individual_columns()
        return self._columns

    def individuals(self):
        """One row per individual of every generation (generations ascending, ids ascending).

        Columns: generation, id, parent1, parent2 (-1: none), species (NEAT; another search
        strategy has its own columns there: MAP-Elites cell, placed and its descriptors, AFPO
        age, pareto_rank and survived, docs/model.md §8.12), status (name),
        status_code, fitness, voxels, chambers, wall_seconds, worker_rank, reused_from (-1:
        simulated in its generation, else the id whose result the row repeats), then the archived
        components (the task's named components of every work unit; for a task with several
        units, e.g. the directed task's directions, as name_<unit>). A run with controller
        learning (docs/model.md §8.11) has, before the components, fitness_before (the genome as
        born; `fitness` is the learned one), learn_evaluations (evaluations spent on the body)
        and learning_curve (per row an array: best fitness so far after the born evaluation and
        every strategy iteration). A pandas DataFrame when pandas imports, else a numpy
        structured array.
        """
        c = self._all_columns()
        columns = {k: c[k] for k in _FIXED_COLUMNS}
        codes = c["status_code"]
        names = {int(code): _softevo.status_name(int(code)) for code in np.unique(codes)}
        columns["status"] = np.array([names[int(x)] for x in codes], dtype=object)
        columns["reused_from"] = c["reused_from"]
        order = ["generation", "id", "parent1", "parent2"]
        if "species" in c:  # NEAT's own column (docs/model.md §8.4)
            columns["species"] = c["species"]
            order.append("species")
        # Another search strategy's columns in its place (docs/model.md §8.12): MAP-Elites cell,
        # placed and the descriptors, AFPO age, pareto_rank and survived.
        for name, values in c["strategy_columns"].items():
            columns[name] = values
            order.append(name)
        order += ["status", "status_code", "fitness", "voxels", "chambers", "wall_seconds",
                  "worker_rank", "reused_from"]
        if "fitness_before" in c:  # controller learning (docs/model.md §8.11)
            columns["fitness_before"] = c["fitness_before"]
            columns["learn_evaluations"] = c["learn_evaluations"]
            curves = np.empty(len(c["learning_curve"]), dtype=object)
            curves[:] = list(c["learning_curve"])
            columns["learning_curve"] = curves
            order += ["fitness_before", "learn_evaluations", "learning_curve"]
        for name, values in c["components"].items():
            if name in ("fitness", "status"):  # already columns of the row (one-unit tasks)
                continue
            columns[name] = values
            order.append(name)
        if _pandas() is None:  # a structured array needs fixed-width strings
            columns["status"] = columns["status"].astype("U20")
        return _table(columns, order)

    def stats(self):
        """Per-generation statistics (/stats): generation, best, mean, sd, species_count,
        evaluations_per_second. A DataFrame, or a numpy structured array without pandas."""
        c = self._archive.stats_columns()
        return _table(c, ["generation", "best", "mean", "sd", "species_count",
                          "evaluations_per_second"])

    @property
    def strategy(self) -> str:
        """The run's search strategy: 'neat', 'map_elites' or 'afpo' (docs/model.md §8.12)."""
        return dict(self.config).get("search.strategy", "neat")

    def map(self, generation: int | None = None):
        """The MAP-Elites map after `generation` (default: the last) as a table, one row per
        elite in ascending cell order: cell, one bin column per descriptor (bin_<name>, the
        cell's coordinates), id, fitness, generation (in which the elite was evaluated) and the
        descriptor values. `run.genome(id)` is the elite's robot. A DataFrame, or a numpy
        structured array without pandas. ValueError for a run of another strategy."""
        if self.strategy != "map_elites":
            raise ValueError(f"{self.path}: a run of search strategy {self.strategy!r} has no "
                             "map (search.strategy = 'map_elites' has one)")
        generation = _whole_number("map", "generation", generation, optional=True)
        m = self._archive.strategy_generation(generation)["map"]
        config = dict(self.config)
        names = list(config["map_elites.descriptors"])
        bins = [int(b) for b in config["map_elites.bins"]]
        cells = m["cell"].astype(np.int64)
        coordinates = np.unravel_index(cells, bins) if len(cells) else [cells] * len(bins)
        columns = {"cell": cells, "id": m["id"].astype(np.int64), "fitness": m["fitness"],
                   "generation": m["generation"].astype(np.int64)}
        order = ["cell"]
        for name, coordinate in zip(names, coordinates):
            columns[f"bin_{name}"] = np.asarray(coordinate, dtype=np.int64)
            order.append(f"bin_{name}")
        order += ["id", "fitness", "generation"]
        for name in names:
            columns[name] = m[name]
            order.append(name)
        return _table(columns, order)

    def strategy_stats(self):
        """Per-generation metrics of a strategy other than NEAT (docs/model.md §8.12):
        MAP-Elites num_elites, coverage, qd_score (offset map_elites.qd_offset), max_fitness,
        mean_fitness; AFPO max_fitness, mean_fitness, pareto_front, mean_age. A DataFrame, or a
        numpy structured array without pandas; no rows for NEAT."""
        c = self._archive.strategy_metric_columns()
        return _table(c, list(c.keys()))

    def genome(self, id: int, generation: int | None = None) -> _softevo.Robot:
        """Individual `id` as a Robot: its archived genome (in a run with controller learning
        the learned one, whose fitness is archived) developed with the archived config, as the
        run evaluated it (from `generation`, default the latest one it is in).
        KeyError when the archive has no such individual."""
        return self._archive.robot(_whole_number("genome", "id", id),
                                   _whole_number("genome", "generation", generation, True))

    def best(self, generation: int | None = None) -> tuple[int, int]:
        """(generation, id) of the fittest individual of `generation` (default: the last), the
        lowest id on ties."""
        generation = _whole_number("best", "generation", generation, optional=True)
        c = self._all_columns()
        if len(c["id"]) == 0:
            raise KeyError(f"{self.path}: the archive has no generation yet")
        g = int(c["generation"][-1]) if generation is None else generation
        rows = np.flatnonzero(c["generation"] == g)
        if len(rows) == 0:
            raise KeyError(f"{self.path}: no generation {g}")
        best = rows[int(np.argmax(c["fitness"][rows]))]
        return g, int(c["id"][best])

    def lineage(self, id: int, generation: int | None = None) -> list[dict]:
        """The line of ancestors of individual `id`, newest first, following parent1 (the
        fitter parent of a crossover, the only one after mutation) back to the initial
        population. Each entry: generation, id, fitness, status, voxels, chambers, species (NEAT),
        parent1, parent2, and a note where an id was carried over as an elite or a parent is
        not archived. `generation` defaults to the latest one the individual is in."""
        id = _whole_number("lineage", "id", id)
        generation = _whole_number("lineage", "generation", generation, optional=True)
        c = self._all_columns()
        gens, ids = c["generation"], c["id"]
        where: dict[int, list[int]] = {}
        for row, ind in enumerate(ids.tolist()):
            where.setdefault(int(ind), []).append(row)
        rows_of_id = where.get(int(id))
        if not rows_of_id:
            raise KeyError(f"{self.path}: no individual with id {id}")
        if generation is None:
            row = rows_of_id[-1]
        else:
            matching = [r for r in rows_of_id if int(gens[r]) == int(generation)]
            if not matching:
                raise KeyError(f"{self.path}: id {id} is not in generation {generation}")
            row = matching[0]
        line = []
        seen = set()
        while row not in seen:  # an archive is acyclic; never loop on a malformed one
            seen.add(row)
            g, ind = int(gens[row]), int(ids[row])
            entry = {
                "generation": g, "id": ind, "fitness": float(c["fitness"][row]),
                "status": _softevo.status_name(int(c["status_code"][row])),
                "voxels": int(c["voxels"][row]), "chambers": int(c["chambers"][row]),
                "parent1": int(c["parent1"][row]), "parent2": int(c["parent2"][row]),
            }
            if "species" in c:  # NEAT's
                entry["species"] = int(c["species"][row])
            first = int(gens[where[ind][0]])
            if first < g:
                entry["note"] = f"same id evaluated since generation {first} (carried over as an elite)"
            line.append(entry)
            parent = entry["parent1"]
            if parent < 0:
                break  # initial population
            earlier = [r for r in where.get(parent, []) if int(gens[r]) < g]
            if not earlier:
                entry["note"] = f"parent {parent} not archived before generation {g}"
                break
            row = earlier[-1]
        return line

    def fitness_digest(self) -> str:
        """The archive's fitness digest (16 hex digits, as `softevo info --json`)."""
        return self._archive.fitness_digest()

    def verify(self, raise_error: bool = True) -> dict:
        """Runs the integrity checks `softevo info` runs (docs/archive.md "Integrity checks"):
        every generation's stored digest against its data, ids, statistics, the checkpoint.
        Returns {"ok", "generations_checked", "generations_with_digest",
        "consistent_generations", "problems": [{"generation", "check", "message"}],
        "description"}; raises ArchiveError when a check fails, unless raise_error=False."""
        report = self._archive.check()
        if raise_error and not report["ok"]:
            raise _softevo.ArchiveError(_integrity_message(self.path, report))
        return report


def open_run(path: str | os.PathLike, verify: bool | str = True) -> Run:
    """Open a run archive (softevo.run/1) read-only with the C++ reader.

    run.config, run.info, run.individuals(), run.stats(), run.genome(id), run.lineage(id).
    A missing file raises FileNotFoundError; a file that is not a run archive, or a malformed
    one, ArchiveError (an OSError) naming the file and the object.

    verify: True (default) runs the integrity checks `softevo info` runs (run.verify()) before
    anything is read, and raises ArchiveError when one fails: a flipped bit or an edited value
    is never served as data. "warn" issues an ArchiveIntegrityWarning instead and reads on;
    False skips the checks (they read the whole archive once: large archives open faster).
    """
    return Run(path, verify)

"""softevo.evolve: a whole evolution from Python, on this machine's cores.

The run is softevo-mpi's (the same config, archive, checkpoints and fitness_digest; docs/archive.md,
"One process: softevo evolve"), its robots evaluated by worker threads of this process while the
GIL is released. Ctrl-C stops it like softevo-mpi's SIGINT: the generation in flight is
dropped, the archive keeps every finished generation, is marked interrupted, and
evolve(..., resume=True) continues it bit for bit.
"""

from __future__ import annotations

import dataclasses
import os
from typing import Callable, Iterable, Iterator, Mapping

from . import _softevo
from ._run import Run


@dataclasses.dataclass(frozen=True)
class Generation:
    """One archived generation of a run in progress (what evolution() yields and evolve()'s
    callback receives).

    generation: its number (0-based); generations: the run's total; best, mean, sd: fitness of
    its individuals [fitness_unit: cm for gait and directed, rad for rotate]; species: species
    count; strategy_metrics: {name: value} of a search strategy other than NEAT (MAP-Elites
    num_elites, coverage, qd_score, ...; docs/model.md §8.12), empty for NEAT; individuals: how
    many were archived; status_counts: {status name: count};
    eval_wall_seconds: wall time of its evaluation [s]; best_id: the id of
    the best individual; best_robot: it as a Robot (its archived genome developed with the
    run's config, as the run evaluated it, with the run's evaluation settings as `softevo
    export` writes them: softevo.evaluate(best_robot) gives its archived fitness); out: the
    archive's path.
    """

    generation: int
    generations: int
    best: float
    mean: float
    sd: float
    species: int
    strategy_metrics: dict
    individuals: int
    status_counts: dict
    eval_wall_seconds: float
    fitness_unit: str
    best_id: int
    best_robot: _softevo.Robot
    out: str

    def to_dict(self) -> dict:
        """Every field but best_robot as plain Python values (for JSON or a DataFrame row)."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
             if f.name != "best_robot"}
        d["status_counts"] = dict(self.status_counts)
        return d


# search.strategy's names (docs/model.md §8.12).
STRATEGIES = ("neat", "map_elites", "afpo")


def _resolve(config, overrides, generations, population, seed, strategy=None):
    """(Config, name for the default archive) from a path or a Config, with the shorthands."""
    from . import _override_list, _existing_file  # the package's helpers

    extra = _override_list(overrides)
    if strategy is not None:
        if strategy not in STRATEGIES:
            raise ValueError(f"strategy must be one of {', '.join(STRATEGIES)}, got {strategy!r}")
        extra.append(f"search.strategy={strategy}")
    shorthands = []  # (config key, argument name, value) given
    for key, argument, value in (("run.generations", "generations", generations),
                                 ("neat.pop_size", "population", population),
                                 ("run.seed", "seed", seed)):
        if value is not None:
            if isinstance(value, bool) or not isinstance(value, int):
                raise TypeError(f"{argument} must be an int, got {value!r}")
            extra.append(f"{key}={value}")
            shorthands.append((key, argument, value))
    try:
        if isinstance(config, _softevo.Config):
            name = config.experiment
            if extra:
                config = _softevo._parse_config(config.text, f"<Config {name}>", extra)
            return config, name
        if isinstance(config, (str, os.PathLike)):
            path = _existing_file(config, "config file")
            return (_softevo._load_config(path, extra),
                    os.path.splitext(os.path.basename(path))[0])
    except _softevo.ConfigError as e:
        # A shorthand out of range is named as it was passed ("generations=-1: ..."), not as
        # the override it becomes (overrides["run.generations"] = -1).
        text = str(e)
        for key, argument, value in shorthands:
            text = text.replace(f'overrides["{key}"] = {value}', f"{argument}={value}")
        if text == str(e):
            raise
        raise _softevo.ConfigError(text) from None
    raise TypeError(f"config: expected a path or a softevo.Config, got {type(config).__name__}")


class Evolution:
    """An evolution run generation by generation: iterate it for one Generation per archived
    generation (see softevo.evolution). A context manager; leaving it early (break, an
    exception) closes the run: the archive keeps every finished generation and is marked
    interrupted, so resume=True continues it."""

    def __init__(self, config, workers: int | None = None, out: str | os.PathLike | None = None,
                 *, generations: int | None = None, population: int | None = None,
                 seed: int | None = None,
                 overrides: Mapping[str, object] | Iterable[str] | None = None,
                 resume: bool = False, overwrite: bool = False, progress: bool = True,
                 strategy: str | None = None):
        if not isinstance(progress, bool):
            raise TypeError(f"progress must be True or False, got {progress!r}")
        self.progress = progress
        self.config, name = _resolve(config, overrides, generations, population, seed, strategy)
        if workers is None:
            workers = _softevo._available_cores()
        if (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
                or workers > _softevo._max_workers):
            raise ValueError(f"workers must be an int from 1 to {_softevo._max_workers} "
                             f"(as softevo evolve --workers), got {workers!r}")
        if out is None:
            out = os.path.join("runs", f"{name}-{self.config.seed:02d}.h5")
        self.out = os.fspath(out)
        self._run = _softevo._Evolution(self.config, self.out, workers, resume, overwrite)
        self.workers = workers

    def __repr__(self) -> str:
        return (f"<softevo.Evolution {self.out!r}: {self.config.experiment}, {self.workers} "
                f"workers, {self._run.generations} generations, {self._run.state}>")

    @property
    def state(self) -> str:
        """'running', 'complete' or 'interrupted'."""
        return self._run.state

    def __iter__(self) -> Iterator[Generation]:
        try:
            while True:
                g = self._run.step()
                self._print_progress()
                if g is None:
                    return
                yield self._generation(g)
        finally:
            self._run.close()

    def close(self) -> None:
        """Ends the run where it is (state interrupted unless every generation is archived)."""
        self._run.close()
        self._print_progress()

    def _print_progress(self) -> None:
        # The command line's line per generation (fitness, statuses, ETA) and its warnings,
        # through sys.stdout so that a notebook shows them too; progress=False drops them.
        for line in self._run.take_lines():
            if self.progress:
                print(line, flush=True)

    def __enter__(self) -> "Evolution":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def run(self) -> Run:
        """The archive, opened read-only (softevo.Run)."""
        return Run(self.out)

    def _generation(self, g: int) -> Generation:
        d = self._run.summary(g)
        return Generation(generations=self._run.generations, out=self.out, **d)


def evolution(config, workers: int | None = None, out: str | os.PathLike | None = None,
              **options) -> Evolution:
    """An evolution to iterate: one softevo.Generation per archived generation.

        for gen in softevo.evolution("configs/quickstart.toml", workers=2, out="runs/q.h5"):
            print(gen.generation, gen.best, gen.fitness_unit)

    Arguments as for evolve() (without callback)."""
    return Evolution(config, workers, out, **options)


def evolve(config, workers: int | None = None, out: str | os.PathLike | None = None, *,
           callback: Callable[[Generation], object] | None = None,
           generations: int | None = None, population: int | None = None,
           seed: int | None = None,
           overrides: Mapping[str, object] | Iterable[str] | None = None,
           resume: bool = False, overwrite: bool = False, progress: bool = True,
           strategy: str | None = None) -> Run:
    """Evolve robots: the run softevo-mpi and `softevo evolve` make of the same config, in this
    process on `workers` threads (default: every core this process may use).

    config: a config file path or a softevo.Config. out: the run archive (default
    runs/<config name>-<seed, 2 digits>.h5, as the command line; its folder is created).
    generations, population, seed: shorthands for run.generations, neat.pop_size, run.seed;
    overrides: further keys as for load_config. strategy: the search strategy, "neat" (the
    config's default), "map_elites" or "afpo" (search.strategy; their keys go in overrides,
    e.g. {"map_elites.bins": [5, 5]}). resume: continue `out` from its last
    checkpoint (a finished run may be extended with a larger `generations`); overwrite:
    replace an existing `out`. callback(generation) is called after each archived generation
    with a softevo.Generation; returning False stops the run there (interrupted, resumable).
    progress: print the command line's line per generation (best, mean, statuses, ETA) and its
    warnings; False runs silently.

    Returns the archive as a softevo.Run. Raises RunError (a RuntimeError) if the run cannot
    start (the archive exists without resume/overwrite, another run holds it, or it belongs to
    another experiment) or fails; ConfigError for a bad config; KeyboardInterrupt after Ctrl-C,
    with the archive checkpointed and marked interrupted.
    """
    with Evolution(config, workers, out, generations=generations, population=population,
                   seed=seed, overrides=overrides, resume=resume, overwrite=overwrite,
                   progress=progress, strategy=strategy) as evo:
        for gen in evo:
            if callback is not None and callback(gen) is False:
                break
        return evo.run()

#!/usr/bin/python3
"""Discrete-event model of softevo-mpi's master-worker schedule (docs/scaling.md).

Rank 0 is the master, ranks 1..N-1 are workers (N = 1: the master evaluates alone). The master
is one serial timeline: each unit it hands out and each result it takes in costs it
`--message-seconds`; after a generation's last result it spends `--barrier-seconds`
(reproduction, archive write) before that run's next generation can start. Idle workers get
the next unit of the oldest generation in flight (master/run.cpp execute_runs), within a
generation in hand-out order: member (= id) order, or longest first by predicted cost (voxels,
master/unit_cost.hpp). Unit times are taken from real archives (/generations/G/wall_seconds
and voxels), so the model replays measured generations.

  schedule_model.py check RUN.h5 [--ranks N]     model vs. the archived eval_wall_seconds
  schedule_model.py table RUN.h5 [...]           parallel efficiency at 1..512 ranks, also of
                                                 a controller-learning run (--learning L,T)

Efficiency = simulated unit seconds / (ranks x wall seconds): the master rank counts as a rank.
Reads archives with h5py (Debian python3-h5py); a finished (packed) or running archive.
"""

from __future__ import annotations

import argparse
import heapq
import sys
from dataclasses import dataclass, field

import h5py
import numpy as np


@dataclass
class Unit:
    seconds: float  # [s] measured evaluation time of the unit
    cost: float  # predicted cost (voxels of the developed body)


@dataclass
class Generation:
    units: list[Unit]
    measured_wall: float  # [s] eval_wall_seconds of the archive
    # [s] master time after its last result, None = --barrier-seconds; a learning round of a
    # generation (docs/model.md §8.11) costs only the strategies' update, not an archive write.
    barrier: float | None = None
    archived: int = 0  # the archived generation this is (a learning generation has rounds)


def read_generations(path: str, include_reused: bool = False,
                     round_seconds: float = 0.01) -> list[Generation]:
    """The simulated units of every generation, id order. A reused row has no unit (wall 0)
    unless `include_reused` (then it costs what its origin cost: the schedule without reuse).
    A generation of a learning run (docs/model.md §8.11) is its rounds: the new bodies as born,
    then lambda candidates of each per iteration, every unit of a body costing its archived
    wall_seconds / learn_evaluations; rounds end in a `round_seconds` barrier, the last in the
    generation's."""
    out = []
    with h5py.File(path, "r") as f:
        names = sorted(f["generations"].keys())
        by_id: dict[int, float] = {}
        for name in names:
            g = f["generations"][name]
            wall = np.asarray(g["wall_seconds"], dtype=float)
            voxels = np.asarray(g["voxels"], dtype=float)
            ids = np.asarray(g["id"])
            units = int(g["components"].shape[1])
            reused = np.asarray(g["reused_from"]) if "reused_from" in g else np.full(len(ids), -1)
            if "learn_evaluations" in g:  # a learning run: round 0, then T rounds of lambda
                evals = np.asarray(g["learn_evaluations"])
                rounds = int(g["learning_curve"].shape[1])
                fresh = [i for i in range(len(ids)) if reused[i] < 0]
                walls = [Generation([], 0.0, round_seconds, len(names)) for _ in range(rounds)]
                for i in fresh:
                    unit = Unit(wall[i] / evals[i] / units, voxels[i])
                    walls[0].units += [unit] * units
                    lam = (int(evals[i]) - 1) // (rounds - 1) if rounds > 1 else 0
                    for r in range(1, rounds):
                        walls[r].units += [unit] * (lam * units)
                walls[-1].barrier = None
                walls[0].measured_wall = float(g.attrs["eval_wall_seconds"])
                for w in walls:
                    w.archived = int(name)
                out += walls
                continue
            gen_units = []
            for i in range(len(ids)):
                if reused[i] >= 0:
                    if not include_reused:
                        continue
                    seconds = by_id.get(int(reused[i]), 0.0)
                else:
                    seconds = wall[i]
                    by_id[int(ids[i])] = seconds
                gen_units += [Unit(seconds / units, voxels[i])] * units
            out.append(Generation(gen_units, float(g.attrs["eval_wall_seconds"]), None, int(name)))
    return out


@dataclass
class _Active:
    run: int
    index: int
    remaining: list[Unit]
    outstanding: int = 0
    barrier: float = 0.0


@dataclass
class Result:
    wall: float  # [s] makespan
    work: float  # [s] unit seconds simulated
    generation_walls: list[float] = field(default_factory=list)  # [s] per generation, run 0

    def efficiency(self, ranks: int) -> float:
        return self.work / (ranks * self.wall) if self.wall > 0 else 0.0


def simulate(runs: list[list[Generation]], ranks: int, message_seconds: float,
             barrier_seconds: float, longest_first: bool, latency_seconds: float = 0.0) -> Result:
    """The schedule of `runs` (each a list of generations) on `ranks` ranks. `latency_seconds`:
    added to each unit on its worker (the sleeping polls of both sides: 1-10 ms back-off)."""
    def ordered(units: list[Unit]) -> list[Unit]:
        # Python's sort is stable: equal costs keep member order, as GenerationScheduler does.
        return sorted(units, key=lambda u: -u.cost) if longest_first else list(units)

    def barrier_of(g: Generation) -> float:
        return barrier_seconds if g.barrier is None else g.barrier

    work = sum(u.seconds for run in runs for g in run for u in g.units)
    if ranks == 1:  # the master evaluates alone, one generation after another
        walls = [sum(u.seconds for u in g.units) + barrier_of(g) for g in runs[0]]
        total = sum(sum(u.seconds for u in g.units) + barrier_of(g) for run in runs for g in run)
        return Result(total, work, walls)
    master = 0.0
    idle = list(range(ranks - 1))
    running: list[tuple[float, int, int, _Active]] = []  # (finish, seq, worker, generation)
    active: list[_Active] = []
    started: dict[int, float] = {}
    walls: list[float] = []
    seq = 0

    def start(run: int, index: int) -> None:
        if index < len(runs[run]):
            g = runs[run][index]
            active.append(_Active(run, index, ordered(g.units), 0, barrier_of(g)))
            if run == 0:
                started[index] = master

    def dispatch() -> None:
        nonlocal master, seq
        while idle:
            g = next((a for a in active if a.remaining), None)
            if g is None:
                return
            unit = g.remaining.pop(0)
            master += message_seconds
            seq += 1
            heapq.heappush(running, (master + unit.seconds + latency_seconds, seq, idle.pop(), g))
            g.outstanding += 1

    def finish_empty() -> None:  # generations without a unit (every result reused)
        nonlocal master
        for g in [a for a in active if not a.remaining and a.outstanding == 0]:
            active.remove(g)
            master += g.barrier
            if g.run == 0:
                walls.append(master - started[g.index])
            start(g.run, g.index + 1)

    for r in range(len(runs)):
        start(r, 0)
    finish_empty()
    dispatch()
    while running:
        t, _, worker, g = heapq.heappop(running)
        master = max(master, t) + message_seconds
        g.outstanding -= 1
        idle.append(worker)
        if not g.remaining and g.outstanding == 0:
            active.remove(g)
            master += g.barrier
            if g.run == 0:
                walls.append(master - started[g.index])
            start(g.run, g.index + 1)
            finish_empty()
        dispatch()
    return Result(master, work, walls)


def directed_from_gait(gens: list[Generation], directions: int = 5) -> list[Generation]:
    """A directed run from gait unit times: each genome's body runs `directions` units of the
    same simulated seconds (same body, same time step), so each costs the gait unit's time."""
    return [Generation([u for u in g.units for _ in range(directions)], 0.0) for g in gens]


def learning_from_gait(gens: list[Generation], lam: int, iterations: int,
                       round_seconds: float) -> list[Generation]:
    """A run with controller learning (docs/model.md §8.11) from a run's unit times: each
    generation is its round 0 (the new bodies as born, the archive's simulated units) and then
    `iterations` rounds of `lam` candidates per new body, each candidate costing its body's unit
    time (the same body and seconds; the controller does not change the step count). Rounds are
    barriers of the generation: the master updates the strategies (`round_seconds`) before it
    hands out the next round; the generation's own barrier (archive) follows the last round."""
    out = []
    for g in gens:
        out.append(Generation(list(g.units), 0.0, round_seconds))
        for r in range(iterations):
            last = r == iterations - 1
            out.append(Generation([u for u in g.units for _ in range(lam)], 0.0,
                                  None if last else round_seconds))
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("mode", choices=["check", "table"])
    p.add_argument("archive", nargs="+", help="run archive(s) whose unit times drive the model")
    p.add_argument("--ranks", type=int, default=3, help="check: ranks of the real run")
    p.add_argument("--message-seconds", type=float, default=2e-4,
                   help="[s] master time per message (hand-out or result)")
    p.add_argument("--latency-seconds", type=float, default=0.01,
                   help="[s] per unit on its worker: poll back-off of master and worker")
    p.add_argument("--barrier-seconds", type=float, default=0.05,
                   help="[s] master time between a generation's last result and the next")
    p.add_argument("--fixed-order", action="store_true", help="check: member order, not longest first")
    p.add_argument("--scale", type=float, default=1.0,
                   help="multiply every measured unit time (e.g. CPU/wall of a loaded machine)")
    p.add_argument("--without-reuse", action="store_true",
                   help="reused rows cost their origin's time (the schedule of older builds)")
    p.add_argument("--learning", default="10,10", metavar="LAMBDA,ITERATIONS",
                   help="table: the learning run's candidates per iteration and iterations")
    p.add_argument("--population", type=int, default=0,
                   help="table: resample every generation's units to this many bodies (fixed "
                        "seed; e.g. the thesis's 50 from a smaller run's unit times)")
    p.add_argument("--round-seconds", type=float, default=0.01,
                   help="[s] master time between two learning rounds (strategy update)")
    a = p.parse_args()
    gens_of = [read_generations(x, a.without_reuse, a.round_seconds) for x in a.archive]
    for gens in gens_of:
        for g in gens:
            for u in g.units:
                u.seconds *= a.scale
    if a.mode == "check":
        for path, gens in zip(a.archive, gens_of):
            model = simulate([gens], a.ranks, a.message_seconds, a.barrier_seconds,
                             not a.fixed_order, a.latency_seconds)
            print(f"# {path}: np={a.ranks}, {'fixed' if a.fixed_order else 'longest-first'} order")
            print("generation\tunits\tmeasured_s\tmodel_s\tmodel/measured\tmodel_efficiency")
            # The rounds of a learning generation add up to the archived generation.
            by_gen: dict[int, list[float]] = {}
            for g, w in zip(gens, model.generation_walls):
                e = by_gen.setdefault(g.archived, [0, 0.0, 0.0, 0.0])
                e[0] += len(g.units)
                e[1] += g.measured_wall
                e[2] += w - (a.barrier_seconds if g.barrier is None else g.barrier)
                e[2] += 0.0 if g.barrier is None else g.barrier
                e[3] += sum(u.seconds for u in g.units)
            for i, (n, measured, w, work) in by_gen.items():
                ratio = w / measured if measured > 0 else float("nan")
                print(f"{i}\t{n}\t{measured:.1f}\t{w:.1f}\t{ratio:.3f}\t{work / (a.ranks * w):.3f}")
        return 0
    gait = gens_of[0]
    if a.population > 0:
        rng = np.random.default_rng(1)
        gait = [Generation([g.units[k] for k in rng.integers(0, len(g.units), a.population)],
                           g.measured_wall) for g in gait if g.units]
    directed = directed_from_gait(gait)
    grid = [gait] * 20 + [directed] * 20
    lam, iterations = (int(x) for x in a.learning.split(","))
    learning = learning_from_gait(gait, lam, iterations, a.round_seconds)
    print("ranks\tgait_fixed\tgait_longest\tdirected_longest\tpacked_grid_longest\t"
          f"gait_learning_{lam}x{iterations}")
    for ranks in [1, 2, 3, 4, 8, 16, 32, 51, 64, 128, 251, 256, 512]:
        args = (a.message_seconds, a.barrier_seconds)
        row = [simulate([gait], ranks, *args, False, a.latency_seconds),
               simulate([gait], ranks, *args, True, a.latency_seconds),
               simulate([directed], ranks, *args, True, a.latency_seconds),
               simulate(grid, ranks, *args, True, a.latency_seconds),
               simulate([learning], ranks, *args, True, a.latency_seconds)]
        print(f"{ranks}\t" + "\t".join(f"{r.efficiency(ranks):.3f}" for r in row))
    return 0


if __name__ == "__main__":
    sys.exit(main())

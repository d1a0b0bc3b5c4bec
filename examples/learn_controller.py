#!/usr/bin/env python3
"""Controller learning (thesis 5.3.6): a new controller for a fixed champion body, learned by
an evolution strategy written in numpy.

    python3 examples/learn_controller.py [--robot FILE] [--iterations N] [--population L]
                                         [--sigma S] [--seconds T] [--seed K] [--workers W]

The body stays the robot's; the controller's parameters (the 9 vectors of docs/model.md §4.4,
softevo.Robot.controller_parameters) start from random values and are improved by a
(1+lambda) evolution strategy with the 1/5 success rule: every iteration samples `population`
Gaussian perturbations of the parent, evaluates them in parallel threads (softevo.evaluate_many
releases the GIL), keeps the best if it beats the parent (the evaluation is deterministic, so
the parent's fitness never falls) and widens or narrows the step size with the share of
offspring that beat the parent. Genes stay in the genome's range (+-5; frequency 1..5 Hz, as
the run's). Prints one line per iteration (mean and best of the offspring, the parent's
fitness, the step size) and the time taken. Default robot: the sample gait walker of the
repository (robots/gait-open-walker.robot.json, robots/README.md).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np

import softevo

DEFAULT_ROBOT = pathlib.Path(__file__).resolve().parents[1] / "robots" / "gait-open-walker.robot.json"
GENE_LIMIT = 5.0
FREQ_RANGE = (1.0, 5.0)  # [Hz]


def clip(theta: np.ndarray) -> np.ndarray:
    """Genes within the genome's limits; the last parameter is the oscillator frequency."""
    out = np.clip(theta, -GENE_LIMIT, GENE_LIMIT)
    out[-1] = np.clip(theta[-1], *FREQ_RANGE)
    return out


def learn(robot: softevo.Robot, iterations: int, population: int, sigma: float, seconds: float,
          seed: int, workers: int | None, log=print) -> list[tuple[int, float, float, float]]:
    """Runs the strategy; returns one (iteration, mean, best, parent) row per iteration."""
    rng = np.random.default_rng(seed)
    n = robot.controller_parameters.size
    parent = clip(rng.normal(0.0, 1.0, n))
    parent[-1] = rng.uniform(*FREQ_RANGE)
    parent_fitness = softevo.evaluate(robot.with_controller_parameters(parent), seconds=seconds).fitness
    scale = np.full(n, 1.0)
    scale[-1] = 0.25  # the frequency lives on a narrower range than the weights
    curve = []
    for it in range(iterations):
        noise = rng.standard_normal((population, n))
        candidates = np.array([clip(parent + sigma * scale * e) for e in noise])
        robots = [robot.with_controller_parameters(c) for c in candidates]
        fitness = np.array([r.fitness for r in
                            softevo.evaluate_many(robots, seconds=seconds, workers=workers)])
        best = int(np.argmax(fitness))
        # 1/5 success rule: widen the search while offspring beat the parent, narrow it after.
        success = float(np.mean(fitness > parent_fitness))
        sigma *= np.exp((success - 0.2) / 0.8)
        if fitness[best] > parent_fitness:  # elitist: the evaluation is deterministic
            parent, parent_fitness = candidates[best], float(fitness[best])
        row = (it, float(fitness.mean()), float(fitness[best]), parent_fitness)
        curve.append(row)
        log(f"iteration {it:3d}  mean {row[1]:9.4f}  best {row[2]:9.4f}  parent {row[3]:9.4f}"
            f"  sigma {sigma:.3f}")
    return curve


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", type=pathlib.Path, default=None, help="robot file (the body)")
    ap.add_argument("--iterations", type=int, default=30)
    ap.add_argument("--population", type=int, default=16)
    ap.add_argument("--sigma", type=float, default=0.5, help="initial step size")
    ap.add_argument("--seconds", type=float, default=3.0, help="simulated seconds per evaluation")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args(argv)
    path = args.robot or DEFAULT_ROBOT
    if args.robot is None and not path.exists():
        print(f"learn_controller: {path} not found; give --robot FILE")
        return 0
    robot = softevo.load_robot(path)
    print(f"learning a controller for the body of {robot.name} ({robot.voxels} voxels, "
          f"{robot.chambers} chambers, {robot.controller_parameters.size} parameters)")
    start = time.perf_counter()
    curve = learn(robot, args.iterations, args.population, args.sigma, args.seconds, args.seed,
                  args.workers)
    wall = time.perf_counter() - start
    print(f"{args.iterations} iterations x {args.population} evaluations of {args.seconds} s in "
          f"{wall:.1f} s; fitness {curve[-1][3]:.4f} (first iteration {curve[0][3]:.4f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Controller learning (thesis 5.3.6): a new controller for a fixed champion body, learned by
an evolution strategy written in numpy.

    python3 examples/learn_controller.py [--robot FILE] [--iterations N] [--population L]
                                         [--sigma S] [--seconds T] [--seed K] [--workers W]

The body stays the robot's; the controller's parameters (the 9 vectors of docs/model.md §4.4,
softevo.Robot.controller_parameters) start from random values and are improved by a
(mu/mu_w, lambda) evolution strategy with rank weights: every iteration samples `population`
Gaussian perturbations of the mean, evaluates them in parallel threads (softevo.evaluate_many
releases the GIL) and moves the mean to the weighted mean of the best half. Genes stay in the
genome's range (+-5; frequency 1..5 Hz, as the run's). Prints one line per iteration (mean,
best of the iteration, best so far) and the time taken. Default robot: the body of the
gait-open-01 champion from ../shared/reference (give --robot FILE without it).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np

import softevo

DEFAULT_ROBOT = (pathlib.Path(__file__).resolve().parents[1] / ".." / "shared" / "reference"
                 / "bestbots" / "gait-open-01.robot.json")
GENE_LIMIT = 5.0
FREQ_RANGE = (1.0, 5.0)  # [Hz]


def clip(theta: np.ndarray) -> np.ndarray:
    """Genes within the genome's limits; the last parameter is the oscillator frequency."""
    out = np.clip(theta, -GENE_LIMIT, GENE_LIMIT)
    out[-1] = np.clip(theta[-1], *FREQ_RANGE)
    return out


def learn(robot: softevo.Robot, iterations: int, population: int, sigma: float, seconds: float,
          seed: int, workers: int | None, log=print) -> list[tuple[int, float, float, float]]:
    """Runs the strategy; returns one (iteration, mean, best, best so far) row per iteration."""
    rng = np.random.default_rng(seed)
    n = robot.controller_parameters.size
    mean = clip(rng.normal(0.0, 1.0, n))
    mean[-1] = rng.uniform(*FREQ_RANGE)
    mu = max(1, population // 2)
    weights = np.log(mu + 0.5) - np.log(np.arange(1, mu + 1))
    weights /= weights.sum()
    scale = np.full(n, sigma)
    scale[-1] = sigma * 0.25  # the frequency lives on a narrower range
    best_so_far = -np.inf
    curve = []
    for it in range(iterations):
        noise = rng.standard_normal((population, n))
        candidates = np.array([clip(mean + scale * e) for e in noise])
        robots = [robot.with_controller_parameters(c) for c in candidates]
        fitness = np.array([r.fitness for r in
                            softevo.evaluate_many(robots, seconds=seconds, workers=workers)])
        order = np.argsort(-fitness, kind="stable")[:mu]
        mean = clip(weights @ candidates[order])
        best_so_far = max(best_so_far, float(fitness[order[0]]))
        row = (it, float(fitness.mean()), float(fitness[order[0]]), best_so_far)
        curve.append(row)
        log(f"iteration {it:3d}  mean {row[1]:9.4f}  best {row[2]:9.4f}  best so far {row[3]:9.4f}")
    return curve


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", type=pathlib.Path, default=None, help="robot file (the body)")
    ap.add_argument("--iterations", type=int, default=30)
    ap.add_argument("--population", type=int, default=16)
    ap.add_argument("--sigma", type=float, default=0.5)
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
          f"{wall:.1f} s; best {curve[-1][3]:.4f} (first iteration {curve[0][2]:.4f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

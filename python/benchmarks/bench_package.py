#!/usr/bin/env python3
"""Benchmarks of the softevo Python package against the C++ paths (figures printed, nothing
asserted: timing is no test).

    python3 python/benchmarks/bench_package.py [--runs N] [--seconds S] [--robots DIR]

1. softevo.evaluate against `softevo eval --json` on the same robot (the first gait robot of
   DIR): CPU seconds of the evaluation, the fastest of N runs each (goal: within 2%).
2. Simulation.step frames per second for that robot: a Python loop feeding
   softevo.Controller(robot).act(obs) to sim.step, against the built-in controller (evaluate):
   frames per CPU second, fastest of N (goal: Python-driven >= 0.9x built-in).
3. softevo.evaluate_many with 2 threads against 1 on up to 4 robots of DIR: wall time (goal
   >= 1.8x on 2 idle cores; another load on the machine lowers it).
DIR defaults to the sample robots that ship with the repository (robots/); any folder of robot
files works, e.g. the thesis champions. Needs the built `softevo` (SOFTEVO_BINARY_DIR, default
build/).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

import softevo

ROOT = pathlib.Path(__file__).resolve().parents[2]


def fastest(n: int, fn) -> float:
    return min(fn() for _ in range(n))


def cpu_of(fn) -> float:
    start = time.process_time()
    fn()
    return time.process_time() - start


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=10.0, help="simulated seconds per evaluation")
    ap.add_argument("--robots", type=pathlib.Path, default=ROOT / "robots",
                    help="folder of robot files (default: the sample robots, robots/)")
    args = ap.parse_args(argv)
    exe = pathlib.Path(os.environ.get("SOFTEVO_BINARY_DIR", ROOT / "build")) / "bin" / "softevo"
    if not exe.exists():
        print(f"bench_package: {exe} not built (set SOFTEVO_BINARY_DIR)", file=sys.stderr)
        return 2
    paths = sorted(args.robots.glob("*.robot.json"))
    gait = [p for p in paths if "gait" in p.name]
    if not paths:
        print(f"bench_package: no *.robot.json in {args.robots}", file=sys.stderr)
        return 2
    champion = (gait or paths)[0]
    robot = softevo.load_robot(champion)
    print(f"robot {robot.name}: {robot.voxels} voxels, {robot.chambers} chambers, "
          f"{args.seconds} s simulated, fastest of {args.runs}")

    # 1. evaluate vs softevo eval
    def cli_cpu() -> float:
        out = subprocess.run([str(exe), "eval", str(champion), "--json", "--seconds", str(args.seconds)],
                             capture_output=True, text=True, check=True).stdout
        return json.loads(out)["cpu_seconds"]

    py = fastest(args.runs, lambda: cpu_of(lambda: softevo.evaluate(robot, seconds=args.seconds)))
    cli = fastest(args.runs, cli_cpu)
    print(f"1. evaluate {py:.3f} s CPU, softevo eval {cli:.3f} s CPU: overhead {100 * (py / cli - 1):+.2f}%")

    # 2. Simulation.step driven from Python vs the built-in controller
    def python_loop() -> None:
        sim = softevo.Simulation(robot, seconds=args.seconds)
        controller = softevo.Controller(robot)
        obs = sim.reset()
        while not sim.done:
            obs, _ = sim.step(controller.act(obs))

    frames = round(60 * args.seconds)
    loop = fastest(args.runs, lambda: cpu_of(python_loop))
    print(f"2. Simulation.step from Python {frames / loop:.1f} frames/s, built-in {frames / py:.1f} "
          f"frames/s: {py / loop:.3f}x")

    # 3. evaluate_many, 2 threads vs 1
    robots = [softevo.load_robot(p) for p in (gait or paths)[:4]]
    seconds = min(args.seconds, 3.0)

    def timed(workers: int) -> tuple[float, float]:
        wall0, cpu0 = time.perf_counter(), time.process_time()
        softevo.evaluate_many(robots, seconds=seconds, workers=workers)
        return time.perf_counter() - wall0, time.process_time() - cpu0

    one = min((timed(1) for _ in range(args.runs)), key=lambda t: t[0])
    two = min((timed(2) for _ in range(args.runs)), key=lambda t: t[0])
    # CPU / wall of the 2-thread run: about 2 when both threads simulate at once (the GIL is
    # released), at most 1 if they were serialised; the load of other processes lowers both.
    print(f"3. evaluate_many of {len(robots)} robots x {seconds} s: 1 thread {one[0]:.2f} s, "
          f"2 threads {two[0]:.2f} s wall: {one[0] / two[0]:.2f}x (2 threads used "
          f"{two[1] / two[0]:.2f} CPUs; load average {os.getloadavg()[0]:.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

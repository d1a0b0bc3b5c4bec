#!/usr/bin/env python3
"""Evaluate a folder of robot files from Python (default: the sample robots in robots/).

    python3 examples/evaluate_champions.py [--reference DIR] [--seconds S] [--workers N] [NAME ...]

Prints each robot's fitness, status and distance with full double precision; at their full
length the fitness bits equal `softevo champions` and `softevo eval` (a sample robot gives the
fitness robots/README.md lists, which is the one its run archived). The robots are evaluated
in parallel threads (softevo.evaluate_many). A folder that does not exist is reported and the
example exits 0.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import softevo

DEFAULT_REFERENCE = pathlib.Path(__file__).resolve().parents[1] / "robots"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help="robot names, e.g. gait-open-walker (default: all)")
    ap.add_argument("--reference", type=pathlib.Path, default=DEFAULT_REFERENCE,
                    help="folder of *.robot.json files (default: the sample robots, robots/)")
    ap.add_argument("--seconds", type=float, default=None, help="simulated seconds (default 10)")
    ap.add_argument("--workers", type=int, default=None, help="threads (default: one per CPU)")
    args = ap.parse_args(argv)
    if not args.reference.is_dir():
        print(f"evaluate_champions: robot folder not found ({args.reference}); nothing to do")
        return 0
    paths = ([args.reference / f"{n}.robot.json" for n in args.names] if args.names
             else sorted(args.reference.glob("*.robot.json")))
    robots = [softevo.load_robot(p) for p in paths]
    start = time.perf_counter()
    results = softevo.evaluate_many(robots, seconds=args.seconds, workers=args.workers)
    wall = time.perf_counter() - start
    for robot, r in zip(robots, results):
        distances = [u.get("distance", 0.0) for u in r.components]
        print(f"{robot.name:16} {r.task:9} fitness {r.fitness!r:>20}  {r.status:16} "
              f"distance {sum(distances):9.3f} cm  {robot.voxels:4d} voxels")
    print(f"{len(robots)} robots in {wall:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Evaluate the thesis champions from Python (the robot files in ../shared/reference/bestbots).

    python3 examples/evaluate_champions.py [--seconds S] [--workers N] [NAME ...]

Prints each champion's fitness, status and distance with full double precision; at 10 s the
fitness bits equal `softevo champions` and `softevo eval` (e.g. gait-open-01 =
109.2838868090218). The champions are evaluated in parallel threads (softevo.evaluate_many).
Without the reference data the example says so and exits 0.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import softevo

DEFAULT_REFERENCE = pathlib.Path(__file__).resolve().parents[1] / ".." / "shared" / "reference" / "bestbots"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help="champion names, e.g. gait-open-01 (default: all)")
    ap.add_argument("--reference", type=pathlib.Path, default=DEFAULT_REFERENCE,
                    help="folder of *.robot.json champions")
    ap.add_argument("--seconds", type=float, default=None, help="simulated seconds (default 10)")
    ap.add_argument("--workers", type=int, default=None, help="threads (default: one per CPU)")
    args = ap.parse_args(argv)
    if not args.reference.is_dir():
        print(f"evaluate_champions: reference data not found ({args.reference}); nothing to do")
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
    print(f"{len(robots)} champions in {wall:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Summarise the 4x10 grid: one row per archive, then final best fitness per experiment.

Reads every archive through `softevo info --json` (no HDF5 module needed). The array spec
("0-39", "0,10,20,30", "0-3,10") says which tasks were run, hence which archives must exist.
"""
import argparse
import json
import math
import subprocess
import sys

EXPERIMENTS = ["gait-open", "gait-closed", "dir-open", "dir-closed"]


def tasks_of(spec):
    out = []
    for part in spec.split(","):
        part = part.split("%")[0]  # "0-39%4": the throttle is not a task
        if "-" in part:
            lo, hi = part.split("-")
            out.extend(range(int(lo), int(hi) + 1))
        elif part:
            out.append(int(part))
    return sorted(set(out))


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--softevo", required=True)
    ap.add_argument("--runs", required=True)
    ap.add_argument("--array", default="0-39")
    ap.add_argument("--reps", type=int, default=10)
    ap.add_argument("--experiments", default=",".join(EXPERIMENTS),
                    help="comma-separated experiments of the grid, in array order")
    ap.add_argument("--seed-first", type=int, default=1, help="seed of each experiment's first task")
    a = ap.parse_args(argv)
    experiments = [e for e in a.experiments.split(",") if e]
    # Checked before any archive is read: a typo in --array or --reps would otherwise end in a
    # Python traceback, or in a grid of other experiments than the job ran.
    try:
        tasks = tasks_of(a.array)
    except ValueError:
        ap.error("--array %r: give task ranges such as 0-39, 0,10,20,30 or 0-3,10" % a.array)
    if a.reps < 1:
        ap.error("--reps %d: must be >= 1" % a.reps)
    if not experiments:
        ap.error("--experiments: give at least one experiment")
    beyond = [t for t in tasks if t < 0 or t // a.reps >= len(experiments)]
    if beyond:
        ap.error("--array %s: task %d is outside the grid of %d experiments x %d repetitions "
                 "(tasks 0-%d)" % (a.array, beyond[0], len(experiments), a.reps,
                                   len(experiments) * a.reps - 1))

    rows, problems = [], []
    for t in tasks:
        exp, seed = experiments[t // a.reps], t % a.reps + a.seed_first
        path = "%s/%s-%02d.h5" % (a.runs, exp, seed)
        r = subprocess.run([a.softevo, "info", path, "--json"], capture_output=True, text=True)
        if r.returncode != 0:
            problems.append("%s: %s" % (path, r.stderr.strip()))
            continue
        info = json.loads(r.stdout)
        gens = info["generations"]
        if info["state"] != "complete" or not gens:
            problems.append("%s: state %s, %d generations" % (path, info["state"], len(gens)))
            continue
        rows.append((exp, seed, info["state"], info["generations_done"], gens[-1]["best"],
                     gens[-1]["mean"], info["fitness_digest"]))

    with open("%s/grid-summary.tsv" % a.runs, "w") as f:
        f.write("experiment\tseed\tstate\tgenerations\tfinal_best\tfinal_mean\tfitness_digest\n")
        for r in rows:
            f.write("%s\t%d\t%s\t%d\t%.6g\t%.6g\t%s\n" % r)
    print("# per run (%s/grid-summary.tsv)" % a.runs)
    print("%-12s %4s %11s %12s %12s  %s" % ("experiment", "seed", "generations", "final_best",
                                           "final_mean", "fitness_digest"))
    for r in rows:
        print("%-12s %4d %11d %12.6g %12.6g  %s" % (r[0], r[1], r[3], r[4], r[5], r[6]))
    print("\n# final best fitness per experiment")
    print("%-12s %3s %12s %12s %12s %12s" % ("experiment", "n", "mean", "sd", "min", "max"))
    for exp in experiments:
        v = [r[4] for r in rows if r[0] == exp]
        if not v:
            continue
        m = sum(v) / len(v)
        sd = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else 0.0
        print("%-12s %3d %12.6g %12.6g %12.6g %12.6g" % (exp, len(v), m, sd, min(v), max(v)))
    for p in problems:
        print("PROBLEM: " + p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())

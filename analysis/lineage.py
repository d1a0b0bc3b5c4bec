#!/usr/bin/env python3
"""Ancestry of an individual of a softevo run archive.

    python3 analysis/lineage.py RUN.h5 [--generation G] [--id ID | --best] [--csv] [--no-verify]

Starts at the individual (default: the best of the last generation) and follows parent1 (the
first parent: the fitter one in a crossover, or the only one after mutation) back to the initial
population, one line per ancestor with its generation, fitness, status, voxel and chamber
counts, species and both parent ids. An ancestor is shown in the latest generation before its
child in which it was evaluated (elites are evaluated again in later generations under the
same id). The chamber count along the line shows when the body plan changed.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from requirements import require  # noqa: E402

require("lineage.py", group=None)
import softevo  # noqa: E402


def lineage(run, generation: int, individual: int) -> list[dict]:
    """The line of ancestors of `individual` of `generation`, newest first (softevo.Run.lineage;
    `run` is a softevo.Run or an analysis/softevo_archive.py Run)."""
    return getattr(run, "run", run).lineage(individual, generation=generation)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("archive")
    ap.add_argument("--generation", type=int, default=None, help="default: the last")
    sel = ap.add_mutually_exclusive_group()
    sel.add_argument("--id", type=int, default=None)
    sel.add_argument("--best", action="store_true", help="the generation's best (default)")
    ap.add_argument("--csv", action="store_true", help="comma-separated output")
    ap.add_argument("--no-verify", action="store_true",
                    help="read an archive that fails softevo info's integrity checks")
    args = ap.parse_args(argv)
    try:
        run = softevo.open_run(args.archive, verify=not args.no_verify)
        if not run.generations:
            print(f"lineage: {args.archive} has no generation yet", file=sys.stderr)
            return 2
        g = args.generation if args.generation is not None else run.generations[-1]
        if g not in run.generations:
            print(f"lineage: {args.archive} has no generation {g}", file=sys.stderr)
            return 2
        ind = run.best(g)[1] if args.id is None else args.id
        line = lineage(run, g, ind)
        experiment = run.info["experiment"] or run.config.experiment
    except (OSError, ValueError, KeyError) as e:
        print(f"lineage: {e}", file=sys.stderr)
        return 2
    cols = ["generation", "id", "fitness", "status", "voxels", "chambers", "species", "parent1",
            "parent2"]
    if args.csv:
        print(",".join(cols))
        for e in line:
            print(",".join(f"{e[c]:.10g}" if isinstance(e.get(c), float) else str(e.get(c, ""))
                           for c in cols))
    else:
        me = line[0]
        print(f"lineage of id {ind} (generation {g}, fitness {me['fitness']:.4f}, status "
              f"{me['status']}) in {args.archive} [{experiment}]: "
              f"{len(line)} ancestors incl. itself")
        if me["status"] != "ok":
            print(f"lineage: warning: id {ind} was not evaluated ok ({me['status']}): its "
                  f"fitness is 0 by rule", file=sys.stderr)
        print(f"{'gen':>6} {'id':>8} {'fitness':>12} {'status':<17} {'voxels':>6} {'chambers':>8}"
              f" {'species':>7} {'parents':>15}")
        prev_chambers = None
        for e in line:
            change = "" if prev_chambers is None or e["chambers"] == prev_chambers else \
                f"  <- chambers {e['chambers']} -> {prev_chambers}"
            parents = f"{e['parent1']},{e['parent2']}"
            print(f"{e['generation']:>6} {e['id']:>8} {e['fitness']:>12.4f} {e['status']:<17}"
                  f" {e['voxels']:>6} {e['chambers']:>8} {e.get('species', '-'):>7} {parents:>15}{change}")
            if "note" in e:
                print(f"       ({e['note']})")
            prev_chambers = e["chambers"]
    return 0


if __name__ == "__main__":
    sys.exit(main())

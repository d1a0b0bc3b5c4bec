#!/usr/bin/env python3
"""Search strategies compared (docs/model.md §8.12, thesis 5.3.4-5.3.5), from run archives.

    python3 analysis/strategies.py RUN.h5 [RUN.h5 | DIR ...] -o OUT_DIR [--qd-offset CM]
                                   [--walk-cm 5] [--grid chamber_count,actuated_fraction]

Every run, whatever its strategy, is placed in one grid afterwards: every individual it
evaluated with status ok, developed from its archived genome, lands in the cell of its
descriptors (the formulas of evo/map_elites.cpp, §8.12.2), and each cell keeps the fittest
(the lowest id on ties, as MAP-Elites' incumbent). For a MAP-Elites run on the same grid this
is its own map, which the script checks against the archived metrics. The grid is that of the
first MAP-Elites run given, else chamber_count x actuated_fraction as in
configs/gait-open-map-elites.toml (--grid names two of chamber_count, actuated_fraction,
void_fraction, voxels, height, elongation with those defaults' ranges).

Writes:
  strategies.csv           one row per run: strategy, seed, evaluations (ok robots), best
                           fitness, distinct chamber counts among robots walking more than
                           --walk-cm, coverage, QD score (sum of fitness - offset over cells)
  qd_curves.png/.pdf       QD score and coverage over generations, one line per run, coloured
                           by strategy
  heatmap_<run>.png/.pdf   each run's grid: best fitness per cell, descriptors on the axes,
                           empty cells grey and hatched
"""

from __future__ import annotations

import argparse
import csv
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from requirements import require  # noqa: E402

require("strategies.py")
import matplotlib  # noqa: E402

matplotlib.use("Agg")  # headless
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

import softevo  # noqa: E402

# Ranges of the descriptors when no MAP-Elites run gives the grid: (min, max, bins, label).
DEFAULTS = {
    "chamber_count": (0.5, 10.5, 10, "chambers"),
    "actuated_fraction": (0.0, 1.0, 10, "chamber voxels / voxels"),
    "void_fraction": (0.0, 1.0, 10, "empty lattice cells / cells"),
    "voxels": (0.0, 1000.0, 10, "voxels"),
    "height": (0.0, 0.1, 10, "height [m]"),
    "elongation": (1.0, 10.0, 9, "longest / shortest extent"),
}
COLOURS = {"neat": "tab:blue", "map_elites": "tab:orange", "afpo": "tab:green"}


def descriptors(robot, lattice_cells: int) -> dict:
    """The body descriptors of §8.12.2 of a developed robot (evo/map_elites.cpp)."""
    cells = np.asarray(robot.cells)
    voxels = int(np.count_nonzero(cells))
    chamber_voxels = int(np.count_nonzero(cells >= 11))
    box = list(robot.lattice)
    return {
        "chamber_count": float(robot.chambers),
        "actuated_fraction": chamber_voxels / voxels if voxels else 0.0,
        "void_fraction": 1.0 - voxels / lattice_cells,
        "voxels": float(voxels),
        "height": box[2] * robot.voxel_size,
        "elongation": max(box) / min(box) if min(box) > 0 else 0.0,
    }


def bin_of(value: float, lo: float, hi: float, bins: int) -> int:
    """common/map_grid.cpp MapGrid::bin: floor((v - min) / (max - min) * bins), clamped."""
    position = (value - lo) / (hi - lo) * bins
    if not position >= 0.0:
        return 0
    return bins - 1 if position >= bins else int(np.floor(position))


class Grid:
    def __init__(self, names, lo, hi, bins):
        self.names, self.lo, self.hi, self.bins = list(names), list(lo), list(hi), list(bins)

    @classmethod
    def of_run(cls, run):
        c = dict(run.config)
        return cls(c["map_elites.descriptors"], c["map_elites.min"], c["map_elites.max"],
                   c["map_elites.bins"])

    @classmethod
    def named(cls, names):
        return cls(names, [DEFAULTS[n][0] for n in names], [DEFAULTS[n][1] for n in names],
                   [DEFAULTS[n][2] for n in names])

    def cell(self, d: dict) -> tuple:
        return tuple(bin_of(d[n], lo, hi, b)
                     for n, lo, hi, b in zip(self.names, self.lo, self.hi, self.bins))

    @property
    def cells(self) -> int:
        return int(np.prod(self.bins))


def analyse(path: pathlib.Path, grid: Grid | None, qd_offset: float, walk_cm: float):
    run = softevo.open_run(path)
    config = dict(run.config)
    lattice_cells = int(np.prod(config["body.lattice"]))
    ind = run.individuals()
    gens, ids = np.asarray(ind["generation"]), np.asarray(ind["id"])
    fitness, status = np.asarray(ind["fitness"]), np.asarray(ind["status"])
    seen: set[int] = set()
    found = []  # (generation first evaluated, id, fitness, descriptors) of each ok individual
    for row in np.argsort(gens * (ids.max() + 1) + ids, kind="stable"):
        i = int(ids[row])
        if i in seen:
            continue
        seen.add(i)
        if status[row] != "ok":
            continue
        d = descriptors(run.genome(i, int(gens[row])), lattice_cells)
        found.append((int(gens[row]), i, float(fitness[row]), d))
    cells: dict[tuple, tuple[float, int]] = {}
    curve = []
    generations = list(run.generations)
    k = 0
    for g in generations:  # individuals in order of (generation, id): MAP-Elites' order
        while k < len(found) and found[k][0] <= g:
            _, i, f, d = found[k]
            c = grid.cell(d)
            if c not in cells or f > cells[c][0]:
                cells[c] = (f, i)
            k += 1
        qd = sum(f - qd_offset for f, _ in cells.values())
        curve.append((g, len(cells) / grid.cells, qd))
    walkers = {int(d["chamber_count"]) for _, _, f, d in found if f > walk_cm}
    summary = {
        "run": path.name, "strategy": run.strategy, "seed": int(run.info["seed"]),
        "generations": len(generations), "ok_robots": len(found),
        "best_fitness": max((f for _, _, f, _ in found), default=float("nan")),
        "chamber_counts_walking": len(walkers),
        "chamber_counts_walking_list": " ".join(str(c) for c in sorted(walkers)),
        "coverage": curve[-1][1] if curve else 0.0, "qd_score": curve[-1][2] if curve else 0.0,
    }
    if run.strategy == "map_elites" and Grid.of_run(run).__dict__ == grid.__dict__:
        # The archived map is this grid's best-per-cell of the ok robots: the same figures.
        last = run.strategy_stats()
        archived = int(np.asarray(last["num_elites"])[-1])
        if archived != len(cells):
            print(f"warning: {path}: {archived} archived elites, {len(cells)} cells found here",
                  file=sys.stderr)
    return summary, curve, cells


def heatmap(cells, grid: Grid, title: str, out: pathlib.Path):
    if len(grid.bins) != 2:
        return
    values = np.full(grid.bins, np.nan)
    for (i, j), (f, _) in cells.items():
        values[i, j] = f
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    ax.set_facecolor("0.85")
    ax.add_patch(matplotlib.patches.Rectangle((grid.lo[0], grid.lo[1]), grid.hi[0] - grid.lo[0],
                                              grid.hi[1] - grid.lo[1], hatch="//", fill=False,
                                              edgecolor="0.6", linewidth=0, zorder=0))
    mesh = ax.pcolormesh(np.linspace(grid.lo[0], grid.hi[0], grid.bins[0] + 1),
                         np.linspace(grid.lo[1], grid.hi[1], grid.bins[1] + 1),
                         np.ma.masked_invalid(values).T, cmap="viridis", shading="flat",
                         edgecolors="white", linewidth=0.5, zorder=1)
    fig.colorbar(mesh, ax=ax, label="best fitness in the cell [cm]")
    ax.set_xlabel(DEFAULTS.get(grid.names[0], (0, 0, 0, grid.names[0]))[3]
                  + f" ({grid.names[0]})")
    ax.set_ylabel(DEFAULTS.get(grid.names[1], (0, 0, 0, grid.names[1]))[3]
                  + f" ({grid.names[1]})")
    ax.set_title(title + "\ngrey, hatched: empty cell", fontsize=9)
    fig.tight_layout()
    for ext in ("png", "pdf"):
        fig.savefig(out.with_suffix("." + ext), dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="run archives or folders of them")
    parser.add_argument("-o", "--out", required=True, help="output folder")
    parser.add_argument("--qd-offset", type=float, default=-10.0,
                        help="QD score = sum over cells of (fitness - offset) [cm], default -10")
    parser.add_argument("--walk-cm", type=float, default=5.0,
                        help="a robot walks when its fitness exceeds this [cm], default 5")
    parser.add_argument("--grid", help="two descriptors, e.g. chamber_count,actuated_fraction")
    args = parser.parse_args(argv)
    for option, value in (("--qd-offset", args.qd_offset), ("--walk-cm", args.walk_cm)):
        if not math.isfinite(value):
            parser.error(f"{option} {value}: give a finite number [cm]")
    named, found = [], []  # archives given by name; .h5 files found in the folders given
    for r in args.runs:
        p = pathlib.Path(r)
        if not p.exists():
            parser.error(f"{r}: no such file or folder")
        if p.is_dir():
            # Segments of a run still writing (RUN.h5.d/) are read through RUN.h5.
            found += sorted(q for q in p.rglob("*.h5") if not q.parent.name.endswith(".h5.d"))
        else:
            named.append(p)
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        parser.error(f"-o {args.out}: exists and is not a folder")
    # Every run is opened before anything is written. An archive named on the command line that
    # cannot be read is an error (named, no traceback, no half-made output); a file found in a
    # folder that is not a run archive (a trace, a damaged file) is left out, saying why.
    paths, runs = [], []
    for p in named + found:
        try:
            runs.append(softevo.open_run(p))
            paths.append(p)
        except (softevo.ArchiveError, OSError) as e:
            if p in named:
                print(f"strategies: {e}", file=sys.stderr)
                return 2
            print(f"strategies: skipped {e}", file=sys.stderr)
    if not paths:
        parser.error("no run archive given")
    grid = None
    if args.grid:
        names = [n.strip() for n in args.grid.split(",")]
        unknown = [n for n in names if n not in DEFAULTS]
        if len(names) != 2 or unknown:
            parser.error(f"--grid {args.grid}: give two descriptors of "
                         f"{', '.join(sorted(DEFAULTS))}" +
                         (f" ({', '.join(map(repr, unknown))} is not one)" if unknown else ""))
        grid = Grid.named(names)
    else:
        grid = next((Grid.of_run(run) for run in runs if run.strategy == "map_elites"), None)
        grid = grid or Grid.named(["chamber_count", "actuated_fraction"])
    out.mkdir(parents=True, exist_ok=True)
    rows, curves = [], []
    for p in paths:
        summary, curve, cells = analyse(p, grid, args.qd_offset, args.walk_cm)
        rows.append(summary)
        curves.append((summary, curve))
        heatmap(cells, grid, f"{p.name}: {summary['strategy']}, best {summary['best_fitness']:.2f}"
                f" cm, coverage {summary['coverage']:.0%}", out / f"heatmap_{p.stem}")
    with open(out / "strategies.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    fig, (ax_qd, ax_cov) = plt.subplots(1, 2, figsize=(10, 4))
    for summary, curve in curves:
        g = [c[0] for c in curve]
        colour = COLOURS.get(summary["strategy"], "black")
        ax_qd.plot(g, [c[2] for c in curve], color=colour, label=summary["run"])
        ax_cov.plot(g, [100 * c[1] for c in curve], color=colour, label=summary["run"])
    for ax in (ax_qd, ax_cov):  # generations are whole numbers: no 0.25 ticks on a short run
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax_qd.set_xlabel("generation")
    ax_qd.set_ylabel(f"QD score [cm] (offset {args.qd_offset:g} cm)")
    ax_cov.set_xlabel("generation")
    ax_cov.set_ylabel(f"coverage [% of {grid.cells} cells]")
    ax_cov.legend(fontsize=7)
    fig.suptitle(f"grid {' x '.join(grid.names)}; colour: strategy "
                 "(blue neat, orange map_elites, green afpo)", fontsize=9)
    fig.tight_layout()
    for ext in ("png", "pdf"):
        fig.savefig(out / f"qd_curves.{ext}", dpi=120)
    plt.close(fig)
    for r in rows:
        print(f"{r['run']:32s} {r['strategy']:10s} best {r['best_fitness']:8.3f} cm  walking "
              f"chamber counts {r['chamber_counts_walking']} [{r['chamber_counts_walking_list']}]"
              f"  coverage {r['coverage']:.1%}  qd {r['qd_score']:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

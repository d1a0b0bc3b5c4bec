#!/usr/bin/env python3
"""All figures and tables of an experiment grid from a folder of softevo run archives.

    python3 analysis/figures.py RUNS_DIR -o OUT_DIR [--generation G] [--compare A,B] [--no-verify]

Writes (PNG and PDF for every figure, CSV for every table):
  fitness_gait.*, fitness_directed.*   mean and best fitness over generations per experiment,
                                       averaged over the repetitions, shaded +-1 sd (thesis
                                       figures 4.1 and 4.2)
  fitness_<experiment>.csv             the numbers behind those curves
  comparison_gait.*, comparison_directed.*
                                       open vs closed loop: per-run population mean and best
                                       fitness at the last generation all runs of both have
  comparison.csv                       Welch's t-test and Mann-Whitney U for those (the thesis
                                       reports p = 0.012 for the gait population means)
  champions.csv, champions.*           table of run champions (best of the last generation)
  learning.*, learning.csv             when a run learns controllers (docs/model.md §8.11):
                                       best fitness so far against evaluations simulated, every
                                       experiment (equal budgets compare at equal x), and the
                                       mean learning curve of the new bodies

Pairs compared: the thesis' open vs closed loop of each task (gait, directed) and of their
rough-ground variants (gait-rough-*, dir-rough-*) when the folder has them, or, with
--compare A,B, experiments A and B of the grid (any two, e.g. gait-open,gait-rough-open);
such a pair's files are named fitness_A_vs_B.*, comparison_A_vs_B.*.

The experiment of each archive is its root attribute `experiment`, else derived from its
/config text (task.kind, task.control). Runs are repetitions of each other when their experiment
hashes agree (the config without run length and seed, docs/archive.md); runs of one experiment
name with different configs are kept apart, labelled with their hash, and a warning names them.
"""

from __future__ import annotations

import argparse
import csv
import math
import pathlib
import sys
import warnings

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from requirements import require  # noqa: E402

require("figures.py")
import matplotlib  # noqa: E402

matplotlib.use("Agg")  # headless
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from softevo_archive import (EXPERIMENTS, Run, evaluations_per_generation, find_runs,  # noqa: E402
                             status_name)

# The pairs compared by default: name -> (first, second) experiment, and their titles.
TASKS = {"gait": ("gait-open", "gait-closed"), "directed": ("dir-open", "dir-closed"),
         "gait_rough": ("gait-rough-open", "gait-rough-closed"),
         "directed_rough": ("dir-rough-open", "dir-rough-closed")}
TASK_TITLES = {"gait": "Gait learning", "directed": "Directed locomotion",
               "gait_rough": "Gait learning on rough ground",
               "directed_rough": "Directed locomotion on rough ground"}
# (best, mean) colours of the first and second experiment of a pair (open loop first in the
# thesis pairs): blues, then reds; best dark, mean light.
PAIR_COLOURS = (("#1f4e9c", "#6fa8dc"), ("#a61c1c", "#f08a5d"))


def fitness_unit(experiments) -> str:
    """Gait and directed fitness are distances in cm (docs/model.md §7)."""
    return "cm" if all(e.startswith(("gait-", "dir-")) for e in experiments) else "task units"


def base_experiment(label: str) -> str:
    """"gait-open" of a group label "gait-open" or "gait-open [1a2b3c4d]"."""
    return label.split(" ")[0]


def group_runs(runs: list[Run]) -> tuple[dict[str, list[Run]], list[str]]:
    """Runs grouped by experiment hash, labelled by experiment name ("gait-open"), or by name
    and hash ("gait-open [1a2b3c4d]") when one name covers several configs; plus one warning
    per such name."""
    by_hash: dict[tuple[str, str], list[Run]] = {}
    for r in runs:
        by_hash.setdefault((r.experiment, r.experiment_hash), []).append(r)
    groups: dict[str, list[Run]] = {}
    messages: list[str] = []
    order = {e: i for i, e in enumerate(EXPERIMENTS)}
    for exp in sorted({e for (e, _) in by_hash}, key=lambda e: (order.get(e, len(order)), e)):
        hashes = sorted(h for (e, h) in by_hash if e == exp)
        if len(hashes) > 1:
            parts = "; ".join(
                f"{h or '(none)'}: " + ", ".join(str(r.path.name) for r in by_hash[(exp, h)])
                for h in hashes)
            messages.append(f"figures: warning: experiment {exp} covers {len(hashes)} different "
                            f"configs (experiment hash {parts}); they are not pooled, each is "
                            f"its own group")
        for h in hashes:
            label = exp if len(hashes) == 1 else f"{exp} [{h[:8]}]"
            groups[label] = by_hash[(exp, h)]
    return groups, messages


def save(fig, out: pathlib.Path, stem: str, written: list[pathlib.Path]) -> None:
    for ext in ("png", "pdf"):
        path = out / f"{stem}.{ext}"
        fig.savefig(path, dpi=150, bbox_inches="tight")
        written.append(path)
    plt.close(fig)


def write_csv(path: pathlib.Path, header: list[str], rows: list[list], written: list[pathlib.Path]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for row in rows:
            w.writerow([f"{v:.10g}" if isinstance(v, float) else v for v in row])
    written.append(path)


def aligned_curves(runs: list[Run]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Generations present in every run, and [runs x generations] arrays of population mean
    and best fitness."""
    curves = [r.fitness_curves() for r in runs]
    common = set(curves[0][0].tolist())
    for g, _, _ in curves[1:]:
        common &= set(g.tolist())
    gens = np.array(sorted(common), dtype=np.int64)
    means = np.array([[m[np.searchsorted(g, x)] for x in gens] for g, m, _ in curves])
    bests = np.array([[b[np.searchsorted(g, x)] for x in gens] for g, _, b in curves])
    return gens, means.reshape(len(runs), len(gens)), bests.reshape(len(runs), len(gens))


def sd(a: np.ndarray, axis=None) -> np.ndarray:
    """Sample standard deviation (n - 1); 0 for a single run."""
    n = a.shape[0] if axis == 0 else a.size
    return np.std(a, axis=axis, ddof=1) if n > 1 else np.zeros_like(np.mean(a, axis=axis))


def fitness_figure(task: str, by_exp: dict[str, list[Run]], out: pathlib.Path,
                   written: list[pathlib.Path]) -> None:
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    plotted = False
    labels = [label for exp in TASKS[task] for label in by_exp if base_experiment(label) == exp]
    for label in labels:
        runs = by_exp[label]
        exp = base_experiment(label)
        # Several configs of one name share its colours: markers tell them apart.
        same_name = [other for other in labels if base_experiment(other) == exp]
        marker = (None, "o", "s", "^")[same_name.index(label) % 4]
        gens, means, bests = aligned_curves(runs)
        if len(gens) == 0:
            continue
        rows = []
        for k, (name, data, style) in enumerate((("mean", means, "--"), ("best", bests, "-"))):
            colour = PAIR_COLOURS[TASKS[task].index(exp)][1 if name == "mean" else 0]
            mu, s = np.mean(data, axis=0), sd(data, axis=0)
            ax.plot(gens, mu, style, color=colour, marker=marker, markersize=4,
                    label=f"{label} {name} (n={len(runs)})")
            ax.fill_between(gens, mu - s, mu + s, color=colour, alpha=0.15, linewidth=0)
            rows.append((mu, s))
        stem = label.replace(" [", "-").replace("]", "")
        write_csv(out / f"fitness_{stem}.csv",
                  ["generation", "runs", "mean_of_population_mean", "sd_of_population_mean",
                   "mean_of_best", "sd_of_best"],
                  [[int(g), len(runs), float(rows[0][0][i]), float(rows[0][1][i]),
                    float(rows[1][0][i]), float(rows[1][1][i])] for i, g in enumerate(gens)],
                  written)
        plotted = True
    if not plotted:
        plt.close(fig)
        return
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_xlabel("generation")
    # Gait fitness is the distance covered in task.eval_seconds (10 s in the thesis), docs/model.md
    # §7.1; directed fitness a distance weighted by path straightness and heading, §7.2.
    ax.set_ylabel(f"fitness [{fitness_unit(TASKS[task])}]")
    ax.set_title(f"{TASK_TITLES[task]}: mean and best fitness\naveraged over runs (band: +-1 sd)",
                 fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, out, f"fitness_{task}", written)


def last_common_generation(runs: list[Run]) -> int | None:
    common = set(runs[0].generation_numbers)
    for r in runs[1:]:
        common &= set(r.generation_numbers)
    return max(common) if common else None


def value_at(run: Run, generation: int) -> tuple[float, float]:
    fitness = run.generation(generation).fitness
    return float(np.mean(fitness)), float(np.max(fitness))


def test_groups(a: list[float], b: list[float]) -> tuple[float, float, float, float]:
    """Welch's t (statistic, p) and two-sided Mann-Whitney U (statistic, p); NaN when a group
    is too small to test."""
    t = p_t = u = p_u = math.nan
    if len(a) >= 2 and len(b) >= 2:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # zero variance -> NaN, reported
            res = stats.ttest_ind(a, b, equal_var=False)
        t, p_t = float(res.statistic), float(res.pvalue)
    if len(a) >= 1 and len(b) >= 1:
        res = stats.mannwhitneyu(a, b, alternative="two-sided")
        u, p_u = float(res.statistic), float(res.pvalue)
    return t, p_t, u, p_u


def comparison(task: str, by_exp: dict[str, list[Run]], generation: int | None,
               out: pathlib.Path, written: list[pathlib.Path], rows: list[list]) -> None:
    open_exp, closed_exp = TASKS[task]
    chosen = []
    for exp in (open_exp, closed_exp):
        labels = sorted((label for label in by_exp if base_experiment(label) == exp),
                        key=lambda label: -len(by_exp[label]))
        if len(labels) > 1:
            print(f"figures: warning: {task} comparison uses {labels[0]} ({len(by_exp[labels[0]])}"
                  f" runs) of the {len(labels)} configs named {exp}", file=sys.stderr)
        chosen.append(by_exp[labels[0]] if labels else [])
    runs_open, runs_closed = chosen
    if not runs_open or not runs_closed:
        return
    g = generation if generation is not None else last_common_generation(runs_open + runs_closed)
    if g is None:
        print(f"figures: {task}: {open_exp} and {closed_exp} share no generation, no comparison",
              file=sys.stderr)
        return
    missing = [str(r.path) for r in runs_open + runs_closed if g not in r.generation_numbers]
    if missing:
        raise SystemExit(f"figures: generation {g} is missing in {', '.join(missing)}")
    vals = {exp: [value_at(r, g) for r in runs] for exp, runs in
            ((open_exp, runs_open), (closed_exp, runs_closed))}
    fig, axes = plt.subplots(1, 2, figsize=(7.0, 3.6))
    for k, metric in enumerate(("population mean", "best")):
        a = [v[k] for v in vals[open_exp]]
        b = [v[k] for v in vals[closed_exp]]
        t, p_t, u, p_u = test_groups(a, b)
        rows.append([task, metric, g, len(a), len(b), float(np.mean(a)), float(sd(np.array(a))),
                     float(np.mean(b)), float(sd(np.array(b))), t, p_t, u, p_u])
        ax = axes[k]
        ax.boxplot([a, b], widths=0.5, showfliers=False)
        for j, data in enumerate((a, b)):
            jitter = np.linspace(-0.08, 0.08, len(data)) if len(data) > 1 else np.zeros(1)
            ax.plot(np.full(len(data), j + 1) + jitter, data, "o",
                    color=PAIR_COLOURS[j][0], alpha=0.7)
        ax.set_xticks([1, 2], [open_exp, closed_exp])
        ax.set_title(f"{metric} fitness, gen {g}\nWelch p={p_t:.3g}, Mann-Whitney p={p_u:.3g}",
                     fontsize=9)
        ax.set_ylabel(f"fitness [{fitness_unit(TASKS[task])}]")
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"{TASK_TITLES[task]}: {open_exp} vs {closed_exp} (one point per run)",
                 fontsize=10)
    fig.tight_layout()
    save(fig, out, f"comparison_{task}", written)


def champions(runs: list[Run], out: pathlib.Path, written: list[pathlib.Path]) -> None:
    header = ["experiment", "seed", "archive", "state", "generations", "champion_generation",
              "champion_id", "fitness", "status", "voxels", "chambers", "best_ever_fitness",
              "best_ever_generation", "best_ever_id"]
    rows = []
    killed = []
    order = {e: i for i, e in enumerate(EXPERIMENTS)}
    for r in sorted(runs, key=lambda r: (order.get(r.experiment, len(order)), r.experiment, r.seed,
                                         str(r.path))):
        if not r.generation_numbers:
            continue
        last = r.generation(r.generation_numbers[-1])
        i = int(np.argmax(last.fitness))  # first maximum = lowest id (rows sorted by id)
        best_ever = (-math.inf, -1, -1)
        for gen in r.generations():
            j = int(np.argmax(gen.fitness))
            if gen.fitness[j] > best_ever[0]:
                best_ever = (float(gen.fitness[j]), gen.number, int(gen.id[j]))
        if status_name(last.status[i]) != "ok":
            killed.append(f"{r.path.name} (id {int(last.id[i])}: {status_name(last.status[i])})")
        rows.append([r.experiment, r.seed, r.path.name, r.state, len(r.generation_numbers),
                     last.number, int(last.id[i]), float(last.fitness[i]),
                     status_name(last.status[i]),
                     int(last.voxels[i]), int(last.chambers[i]), best_ever[0], best_ever[1],
                     best_ever[2]])
    write_csv(out / "champions.csv", header, rows, written)
    if killed:
        print("figures: warning: a champion was not evaluated ok (its fitness is 0 by rule): " +
              ", ".join(killed), file=sys.stderr)
    # The same table as a figure.
    shown = ["experiment", "seed", "champion_generation", "champion_id", "fitness", "status",
             "voxels", "chambers", "best_ever_fitness"]
    idx = [header.index(c) for c in shown]
    cells = [[f"{row[i]:.2f}" if isinstance(row[i], float) else str(row[i]) for i in idx]
             for row in rows]
    fig, ax = plt.subplots(figsize=(8.5, 0.6 + 0.25 * max(1, len(cells))))
    ax.axis("off")
    if cells:
        labels = ["experiment", "seed", "gen", "id", "fitness [cm]", "status", "voxels",
                  "chambers", "best ever [cm]"]
        table = ax.table(cellText=cells, colLabels=labels, loc="center")
        table.auto_set_font_size(False)
        table.set_fontsize(7)
        table.scale(1.0, 1.2)
        # A champion that was not evaluated ok is marked, not passed off as a result.
        status_col = labels.index("status")
        for k, row in enumerate(cells):
            if row[status_col] != "ok":
                table[k + 1, status_col].set_facecolor("#f4cccc")
    ax.set_title("Run champions: best individual of each run's last generation", fontsize=9,
                 pad=12)
    save(fig, out, "champions", written)


def budget_curves(runs: list[Run], end: float) -> tuple[np.ndarray, np.ndarray]:
    """A grid of simulated evaluations up to `end` and [runs x grid] best-so-far fitness at each
    point: a step function that starts when the run's first generation is archived (NaN before)
    and holds each generation's value until the next one's evaluations are all spent."""
    grid = np.linspace(0, end, 400)
    values = []
    for r in runs:
        _, counts = evaluations_per_generation(r)
        _, _, bests = r.fitness_curves()
        x, b = np.cumsum(counts), np.maximum.accumulate(bests)
        k = np.searchsorted(x, grid, side="right") - 1  # the last generation complete at v
        values.append(np.where(k >= 0, b[np.maximum(k, 0)], np.nan))
    return grid, np.array(values)


def run_budget(r: Run) -> int:
    """Work units the run has simulated (every archived generation)."""
    return int(evaluations_per_generation(r)[1].sum())


def learning_figure(by_exp: dict[str, list[Run]], out: pathlib.Path,
                    written: list[pathlib.Path]) -> None:
    """learning.*: every experiment's best-so-far fitness against the evaluations it simulated
    (equal budgets compare at equal x), and the mean learning curve of the learning runs' new
    bodies (fitness gained against strategy iterations); learning.csv: the numbers."""
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    rows: list[list] = []
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    # Equal budgets: every experiment up to the smallest budget any run of them has spent.
    end = min(run_budget(r) for runs in by_exp.values() for r in runs)
    for k, (label, runs) in enumerate(by_exp.items()):
        grid, values = budget_curves(runs, end)
        with warnings.catch_warnings():  # columns before a run's first generation: all NaN
            warnings.simplefilter("ignore", category=RuntimeWarning)
            m = np.nanmean(values, axis=0)
            s = np.nanstd(values, axis=0, ddof=1) if len(runs) > 1 else np.zeros_like(m)
        m[np.isnan(values).any(axis=0)] = np.nan  # only where every run has a generation
        c = colours[k % len(colours)]
        ax.plot(grid, m, color=c, label=f"{label} (n={len(runs)}): {m[-1]:.3g} at {end}")
        ax.fill_between(grid, m - s, m + s, color=c, alpha=0.2, linewidth=0)
        rows += [[label, "best_so_far", float(x), float(y), float(z)]
                 for x, y, z in zip(grid[::40], m[::40], s[::40]) if not np.isnan(y)]
        rows.append([label, "best_so_far", float(grid[-1]), float(m[-1]), float(s[-1])])
        learners = [r for r in runs if r.learning is not None]
        if not learners:
            continue
        gains = [np.asarray(curve) - curve[0] for r in learners
                 for curve, fresh in zip(r.learning["learning_curve"],
                                         r._columns["reused_from"] == -1) if fresh]
        gains = np.array(gains)
        gm = gains.mean(axis=0)
        it = np.arange(len(gm))
        ax2.plot(it, gm, color=c, marker="o", markersize=3,
                 label=f"{label}: {len(gains)} bodies")
        ax2.fill_between(it, np.percentile(gains, 25, axis=0), np.percentile(gains, 75, axis=0),
                         color=c, alpha=0.2, linewidth=0)
        rows += [[label, "mean_gain", int(i), float(g), float(np.std(gains[:, i]))]
                 for i, g in enumerate(gm)]
    unit = fitness_unit(base_experiment(label) for label in by_exp)
    ax.set_xlabel("evaluations simulated (work units)")
    ax.set_ylabel(f"best fitness so far [{unit}]")
    ax.set_title("Best fitness against evaluations simulated, to the smallest budget\n"
                 "(mean +- 1 sd over runs; from each run's first archived generation)", fontsize=9)
    ax.legend(fontsize=7)
    ax2.set_xlabel("strategy iteration")
    ax2.set_ylabel(f"fitness gained by learning [{unit}]")
    ax2.set_title("Learning curve of the new bodies (mean, 25-75 %)", fontsize=9)
    if ax2.lines:
        ax2.legend(fontsize=7)
    fig.tight_layout()
    save(fig, out, "learning", written)
    write_csv(out / "learning.csv", ["experiment", "series", "x", "mean", "sd"], rows, written)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs_dir", help="folder with run archives (*.h5, searched recursively)")
    ap.add_argument("-o", "--out", required=True, help="output folder (created)")
    ap.add_argument("--generation", type=int, default=None,
                    help="generation of the open/closed comparison (default: last common)")
    ap.add_argument("--compare", default=None, metavar="A,B",
                    help="compare experiments A and B of the grid instead of the default pairs")
    ap.add_argument("--no-verify", action="store_true",
                    help="read archives that fail softevo info's integrity checks (default: "
                         "skip them with the reason)")
    args = ap.parse_args(argv)
    if args.compare is not None:
        pair = tuple(e.strip() for e in args.compare.split(","))
        if len(pair) != 2 or not all(pair) or pair[0] == pair[1]:
            ap.error(f"--compare wants two different experiments A,B, got {args.compare!r}")
        name = f"{pair[0]}_vs_{pair[1]}"
        TASKS.clear()
        TASKS[name] = pair
        TASK_TITLES[name] = f"{pair[0]} vs {pair[1]}"

    if not pathlib.Path(args.runs_dir).is_dir():
        ap.error(f"{args.runs_dir}: " + ("is a file; give the folder of the runs (one archive: "
                                          "analysis/lineage.py or analysis/strategies.py)"
                                          if pathlib.Path(args.runs_dir).exists()
                                          else "no such folder"))
    runs, skipped = find_runs(args.runs_dir, verify=not args.no_verify)
    for msg in skipped:
        print(f"figures: skipped {msg}", file=sys.stderr)
    if not runs:
        print(f"figures: no run archive (format softevo.run/1) under {args.runs_dir}",
              file=sys.stderr)
        return 2
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with_data = []
    for r in runs:
        if r.generation_numbers:
            with_data.append(r)
        else:
            print(f"figures: {r.path} has no generation yet, left out", file=sys.stderr)
    by_exp, mixed = group_runs(with_data)
    for msg in mixed:
        print(msg, file=sys.stderr)
    print("runs: " + ", ".join(f"{label} x{len(rs)}" for label, rs in by_exp.items()))
    if args.compare is not None:
        present = {base_experiment(label) for label in by_exp}
        missing = [e for e in TASKS[name] if e not in present]
        if missing:
            print(f"figures: no run of {', '.join(missing)} under {args.runs_dir} (it has "
                  f"{', '.join(sorted(present)) or 'none'})", file=sys.stderr)
            return 2

    written: list[pathlib.Path] = []
    for task in TASKS:
        fitness_figure(task, by_exp, out, written)
    comparison_rows: list[list] = []
    for task in TASKS:
        comparison(task, by_exp, args.generation, out, written, comparison_rows)
    write_csv(out / "comparison.csv",
              ["task", "metric", "generation", "n_open", "n_closed", "mean_open", "sd_open",
               "mean_closed", "sd_closed", "welch_t", "welch_p", "mannwhitney_u",
               "mannwhitney_p"], comparison_rows, written)
    for row in comparison_rows:
        print(f"{row[0]:8s} {row[1]:15s} gen {row[2]}: open {row[5]:.4g} +- {row[6]:.3g} (n={row[3]})"
              f" vs closed {row[7]:.4g} +- {row[8]:.3g} (n={row[4]}); Welch p = {row[10]:.3g},"
              f" Mann-Whitney p = {row[12]:.3g}")
    champions([r for rs in by_exp.values() for r in rs], out, written)
    if any(r.learning is not None for rs in by_exp.values() for r in rs):
        learning_figure(by_exp, out, written)
    print("wrote:")
    for p in written:
        print(f"  {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

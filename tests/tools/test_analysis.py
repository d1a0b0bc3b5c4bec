#!/usr/bin/env python3
"""Tests of analysis/figures.py and analysis/lineage.py.

Synthetic archives are written with h5py following the softevo.run/1 schema (docs/archive.md)
for a 2x2 grid per task (4 experiments x 2 repetitions); when the built `softevo-mpi` exists
(SOFTEVO_BINARY_DIR/bin), a real tiny grid is run as well and analysed the same way.

Run: python3 tests/tools/test_analysis.py   (from the repository root; ctest does this)
"""

from __future__ import annotations

import csv
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np

REPO = pathlib.Path(os.environ.get("SOFTEVO_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
ANALYSIS = REPO / "analysis"
sys.path.insert(0, str(ANALYSIS))
import figures  # noqa: E402
import lineage  # noqa: E402
from softevo_archive import ArchiveError, Run, experiment_from_config  # noqa: E402

EXPERIMENT_CONFIG = {
    "gait-open": ("gait", "open"), "gait-closed": ("gait", "closed"),
    "dir-open": ("directed", "open"), "dir-closed": ("directed", "closed"),
}


def write_synthetic_archive(path: pathlib.Path, experiment: str, seed: int, generations: int,
                            pop: int, level: float, with_experiment_attr: bool = True,
                            task_keys: str = "", learning: bool = False) -> None:
    """A complete archive whose population fitness is `level` + noise, best = level + 10 + g.
    Each individual's parent1 is the individual of the previous generation one row below.
    `learning`: a run with controller learning (docs/archive.md): 5 evaluations per body, a
    3-point learning curve from fitness - 2 up to fitness; row 0 of each generation but the
    first reuses an earlier result (no evaluation)."""
    kind, control = EXPERIMENT_CONFIG[experiment.removesuffix("-learn")]
    if learning:
        task_keys += ('\n[learning]\nmethod = "es"\nevaluations = 5\npopulation = 2\n')
    n_dir = 5 if kind == "directed" else 1
    rng = np.random.default_rng(seed)
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "softevo.run/1"
        f.attrs["version"] = "0.1.0"
        f.attrs["git_commit"] = "synthetic"
        f.attrs["seed"] = np.int64(seed)
        f.attrs["ranks"] = np.int32(1)
        f.attrs["host"] = "test"
        f.attrs["start_time"] = "2026-01-01T00:00:00Z"
        f.attrs["end_time"] = "2026-01-01T00:01:00Z"
        f.attrs["config_hash"] = "0123456789abcdef"
        if with_experiment_attr:
            f.attrs["experiment"] = experiment
        f.attrs["state"] = "complete"
        f.attrs["generations_done"] = np.int64(generations)
        f["config"] = (f'[run]\nseed = {seed}\n\n[task]\nkind = "{kind}"\ncontrol = "{control}"\n'
                       + task_keys)
        stats = []
        for g in range(generations):
            grp = f.create_group(f"generations/{g:06d}")
            ids = np.arange(g * pop + 1, (g + 1) * pop + 1, dtype=np.int64)
            fitness = level + rng.normal(0.0, 1.0, pop)
            fitness[0] = level + 10.0 + g  # the best: id g*pop+1
            parent1 = np.full(pop, -1, dtype=np.int64) if g == 0 else ids - pop + 1
            if g > 0:
                parent1[-1] = ids[0] - pop  # keep parents inside the previous generation
            grp["id"] = ids
            grp["parent1"] = parent1
            grp["parent2"] = np.full(pop, -1, dtype=np.int64)
            grp["species"] = np.ones(pop, dtype=np.int64)
            grp["status"] = np.zeros(pop, dtype=np.uint8)
            grp["fitness"] = fitness
            grp["voxels"] = np.full(pop, 500, dtype=np.int32)
            grp["chambers"] = np.full(pop, 1 + g, dtype=np.int32)
            grp["wall_seconds"] = np.full(pop, 0.1)
            grp["worker_rank"] = np.zeros(pop, dtype=np.int32)
            vlen = h5py.vlen_dtype(np.uint8)
            genome = grp.create_dataset("genome", (pop,), dtype=vlen)
            for i in range(pop):
                genome[i] = np.frombuffer(b"synthetic", dtype=np.uint8)
            grp["components"] = np.zeros((pop, n_dir, 6))
            if learning:
                grp["reused_from"] = np.array([1 if g > 0 and i == 0 else -1 for i in range(pop)],
                                              dtype=np.int64)
                grp["fitness_before"] = fitness - 2.0
                grp["learn_evaluations"] = np.full(pop, 5, dtype=np.int64)
                learned = grp.create_dataset("learned_genome", (pop,), dtype=vlen)
                for i in range(pop):
                    learned[i] = np.frombuffer(b"learned", dtype=np.uint8)
                grp["learning_curve"] = np.stack([fitness - 2.0, fitness - 1.0, fitness], axis=1)
            for k, v in (("best", fitness.max()), ("mean", fitness.mean()), ("sd", fitness.std())):
                grp.attrs[k] = float(v)
            grp.attrs["species_count"] = np.int64(1)
            grp.attrs["evaluations"] = np.int64(pop * n_dir)
            grp.attrs["eval_wall_seconds"] = 1.0
            stats.append([g, fitness.max(), fitness.mean(), fitness.std(), 1, 10.0])
        f["stats"] = np.array(stats)
        f.create_group("checkpoint")


EXPECTED_FILES = [
    "fitness_gait.png", "fitness_gait.pdf", "fitness_directed.png", "fitness_directed.pdf",
    "fitness_gait-open.csv", "fitness_gait-closed.csv", "fitness_dir-open.csv",
    "fitness_dir-closed.csv", "comparison_gait.png", "comparison_gait.pdf",
    "comparison_directed.png", "comparison_directed.pdf", "comparison.csv", "champions.csv",
    "champions.png", "champions.pdf",
]


def run_figures(runs_dir: pathlib.Path, out: pathlib.Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ANALYSIS / "figures.py"), str(runs_dir), "-o", str(out),
                           *extra], capture_output=True, text=True, timeout=300)


def run_figures_synthetic(runs_dir: pathlib.Path, out: pathlib.Path, *extra: str) -> subprocess.CompletedProcess:
    """figures.py over hand-made archives: they carry a placeholder config hash and no usable
    checkpoint, so they fail the integrity checks and are read with --no-verify."""
    return run_figures(runs_dir, out, "--no-verify", *extra)


class MixedConfigs(unittest.TestCase):
    """Two gait-open archives of different configs (3 s and 1.5 s robots) are two experiments:
    figures.py says so and does not pool them."""

    def test_one_name_over_two_configs_warns_and_keeps_them_apart(self):
        tmp = pathlib.Path(tempfile.mkdtemp(prefix="softevo_test_mixed_"))
        try:
            runs = tmp / "runs"
            runs.mkdir()
            for seed, keys in ((1, "eval_seconds = 3.0\n"), (2, "eval_seconds = 3.0\n"),
                               (3, "eval_seconds = 1.5\n")):
                write_synthetic_archive(runs / f"gait-open-{seed:02d}.h5", "gait-open", seed,
                                        generations=3, pop=4, level=10.0, task_keys=keys)
            result = run_figures_synthetic(runs, tmp / "figs")
            self.assertEqual(result.returncode, 0, result.stderr)
            self.assertIn("experiment gait-open covers 2 different configs", result.stderr)
            self.assertIn("gait-open-03.h5", result.stderr)
            runs_line = next(line for line in result.stdout.splitlines()
                             if line.startswith("runs: "))
            self.assertEqual(runs_line.count("gait-open ["), 2, runs_line)
            self.assertIn("x2", runs_line)
            self.assertIn("x1", runs_line)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)

    def test_repetitions_of_one_config_are_pooled_without_warning(self):
        tmp = pathlib.Path(tempfile.mkdtemp(prefix="softevo_test_pooled_"))
        try:
            runs = tmp / "runs"
            runs.mkdir()
            for seed in (1, 2):
                write_synthetic_archive(runs / f"gait-open-{seed:02d}.h5", "gait-open", seed,
                                        generations=3, pop=4, level=10.0)
            result = run_figures_synthetic(runs, tmp / "figs")
            self.assertEqual(result.returncode, 0, result.stderr)
            self.assertNotIn("different configs", result.stderr)
            self.assertIn("runs: gait-open x2", result.stdout)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


class SyntheticGrid(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = pathlib.Path(tempfile.mkdtemp(prefix="softevo_test_analysis_"))
        cls.runs = cls.tmp / "runs"
        (cls.runs / "nested").mkdir(parents=True)
        # 2 repetitions per experiment; open loop clearly better than closed (population mean).
        levels = {"gait-open": 40.0, "gait-closed": 26.0, "dir-open": 30.0, "dir-closed": 29.0}
        for exp, level in levels.items():
            for seed in (1, 2):
                # One archive without the experiment attribute: taken from /config instead.
                write_synthetic_archive(cls.runs / ("nested" if seed == 2 else "") / f"{exp}-{seed:02d}.h5",
                                        exp, seed, generations=4, pop=6, level=level + seed,
                                        with_experiment_attr=not (exp == "dir-closed" and seed == 2))
        # A file that is not a run archive is skipped with a message, not fatal.
        with h5py.File(cls.runs / "trace.h5", "w") as f:
            f["positions"] = np.zeros((1, 1, 3))
        # The segment directory of a run still writing is not a folder of archives.
        (cls.runs / "gait-open-01.h5.d").mkdir()
        with h5py.File(cls.runs / "gait-open-01.h5.d" / "gen-000009.h5", "w") as f:
            f.attrs["format"] = "softevo.segment/1"
        cls.out = cls.tmp / "figs"
        cls.result = run_figures_synthetic(cls.runs, cls.out)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_writes_every_figure_and_table(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        for name in EXPECTED_FILES:
            path = self.out / name
            self.assertTrue(path.is_file(), f"{name} not written")
            self.assertGreater(path.stat().st_size, 200, name)
        self.assertIn("trace.h5", self.result.stderr)  # skipped, and said so
        self.assertNotIn("gen-000009.h5", self.result.stderr)  # a segment: not even mentioned

    def test_fitness_curves_average_the_repetitions(self):
        with open(self.out / "fitness_gait-open.csv") as f:
            rows = list(csv.DictReader(f))
        self.assertEqual([int(r["generation"]) for r in rows], [0, 1, 2, 3])
        self.assertEqual({int(r["runs"]) for r in rows}, {2})
        # best = level + seed + 10 + g, averaged over seeds 1 and 2: 40 + 1.5 + 10 + g, sd 0.707.
        for r in rows:
            self.assertAlmostEqual(float(r["mean_of_best"]), 51.5 + int(r["generation"]), places=9)
            self.assertAlmostEqual(float(r["sd_of_best"]), np.sqrt(0.5), places=9)

    def test_open_vs_closed_statistics(self):
        with open(self.out / "comparison.csv") as f:
            rows = {(r["task"], r["metric"]): r for r in csv.DictReader(f)}
        gait = rows[("gait", "population mean")]
        self.assertEqual(int(gait["generation"]), 3)
        self.assertEqual((int(gait["n_open"]), int(gait["n_closed"])), (2, 2))
        self.assertGreater(float(gait["mean_open"]), float(gait["mean_closed"]) + 10)
        # Same numbers through scipy directly, from the archives.
        from scipy import stats
        a = [float(np.mean(Run(self.runs / p, verify=False).generation(3).fitness))
             for p in ("gait-open-01.h5", "nested/gait-open-02.h5")]
        b = [float(np.mean(Run(self.runs / p, verify=False).generation(3).fitness))
             for p in ("gait-closed-01.h5", "nested/gait-closed-02.h5")]
        self.assertAlmostEqual(float(gait["welch_p"]), stats.ttest_ind(a, b, equal_var=False).pvalue, places=9)
        self.assertAlmostEqual(float(gait["mannwhitney_p"]),
                               stats.mannwhitneyu(a, b, alternative="two-sided").pvalue, places=9)
        self.assertIn(("directed", "best"), rows)

    def test_champions_table(self):
        with open(self.out / "champions.csv") as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(rows), 8)
        self.assertEqual(sorted({r["experiment"] for r in rows}),
                         ["dir-closed", "dir-open", "gait-closed", "gait-open"])
        first = rows[0]
        self.assertEqual(first["experiment"], "gait-open")
        self.assertEqual(int(first["champion_generation"]), 3)
        self.assertEqual(int(first["champion_id"]), 3 * 6 + 1)
        self.assertAlmostEqual(float(first["fitness"]), 40 + 1 + 10 + 3)

    def test_experiment_from_config_text(self):
        self.assertEqual(experiment_from_config('[task]\nkind = "directed"\ncontrol = "closed"\n'),
                         "dir-closed")
        with Run(self.runs / "nested" / "dir-closed-02.h5", verify=False) as run:
            self.assertEqual(run.experiment, "dir-closed")

    def test_lineage_follows_parent1_to_the_initial_population(self):
        with Run(self.runs / "gait-open-01.h5", verify=False) as run:
            line = lineage.lineage(run, 3, 19)
        # 19 <- 14 <- 9 <- 4 (parent1 = id - pop + 1), 4 is in generation 0.
        self.assertEqual([(e["generation"], e["id"]) for e in line], [(3, 19), (2, 14), (1, 9), (0, 4)])
        self.assertEqual([e["chambers"] for e in line], [4, 3, 2, 1])
        out = subprocess.run([sys.executable, str(ANALYSIS / "lineage.py"),
                              str(self.runs / "gait-open-01.h5"), "--best", "--no-verify"],
                             capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("lineage of id 19", out.stdout)
        self.assertIn("chambers 3 -> 4", out.stdout)

    def test_empty_folder_is_an_error(self):
        empty = self.tmp / "empty"
        empty.mkdir()
        result = run_figures(empty, self.tmp / "none")
        self.assertEqual(result.returncode, 2)
        self.assertIn("no run archive", result.stderr)

    def test_a_file_or_missing_folder_is_named(self):
        # figures.py takes a folder: one archive given instead is named as a file (before, the
        # message was "no run archive under RUN.h5"), a missing folder as missing.
        archive = self.tmp / "one.h5"
        archive.write_text("")
        result = run_figures(archive, self.tmp / "none")
        self.assertEqual(result.returncode, 2)
        self.assertIn("one.h5: is a file; give the folder of the runs", result.stderr)
        result = run_figures(self.tmp / "absent", self.tmp / "none")
        self.assertEqual(result.returncode, 2)
        self.assertIn("absent: no such folder", result.stderr)
        self.assertFalse((self.tmp / "none").exists())

    def test_archives_failing_the_integrity_checks_are_skipped_with_the_reason(self):
        result = run_figures(self.runs, self.tmp / "verified")
        self.assertEqual(result.returncode, 2, result.stderr)
        self.assertIn("integrity FAILED", result.stderr)
        self.assertIn("config_hash attribute is 0123456789abcdef", result.stderr)
        with self.assertRaises(ArchiveError):
            Run(self.runs / "gait-open-01.h5")
        out = subprocess.run([sys.executable, str(ANALYSIS / "lineage.py"),
                              str(self.runs / "gait-open-01.h5")],
                             capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 2, out.stdout)
        self.assertIn("integrity FAILED", out.stderr)


class LearningRuns(unittest.TestCase):
    """gait-closed with and without controller learning: figures.py --compare pools each,
    and writes learning.* (fitness against evaluations simulated, mean learning curve)."""

    def test_learning_figure_counts_evaluations_and_gains(self):
        tmp = pathlib.Path(tempfile.mkdtemp(prefix="softevo_test_learning_"))
        try:
            runs = tmp / "runs"
            runs.mkdir()
            for seed in (1, 2):
                write_synthetic_archive(runs / f"plain-{seed}.h5", "gait-closed", seed,
                                        generations=10, pop=4, level=10.0)
                write_synthetic_archive(runs / f"learn-{seed}.h5", "gait-closed-learn", seed,
                                        generations=2, pop=4, level=12.0, learning=True)
            result = run_figures_synthetic(runs, tmp / "figs", "--compare",
                                           "gait-closed,gait-closed-learn")
            self.assertEqual(result.returncode, 0, result.stderr)
            self.assertIn("runs: gait-closed x2, gait-closed-learn x2", result.stdout)
            for name in ("learning.png", "learning.pdf", "learning.csv"):
                self.assertTrue((tmp / "figs" / name).is_file(), name)
            with open(tmp / "figs" / "learning.csv") as f:
                rows = list(csv.DictReader(f))
            # Budget: plain runs simulate 4 units per generation (40), learning runs 5 per
            # fresh body (4 + 3 = 7 bodies: 35); the common grid ends at the smaller.
            best = [r for r in rows if r["series"] == "best_so_far"]
            self.assertEqual({r["experiment"] for r in best}, {"gait-closed", "gait-closed-learn"})
            self.assertLessEqual(max(float(r["x"]) for r in best), 35.0)
            gains = [r for r in rows if r["series"] == "mean_gain"]
            self.assertEqual([float(r["mean"]) for r in gains], [0.0, 1.0, 2.0])
            run = Run(runs / "learn-1.h5", verify=False)
            self.assertEqual(run.experiment, "gait-closed-learn")
            from softevo_archive import evaluations_per_generation
            self.assertEqual(evaluations_per_generation(run)[1].tolist(), [20, 15])
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


def find_softevo_mpi() -> pathlib.Path | None:
    build = os.environ.get("SOFTEVO_BINARY_DIR")
    if not build:
        return None
    exe = pathlib.Path(build) / "bin" / "softevo-mpi"
    return exe if exe.is_file() else None


@unittest.skipIf(find_softevo_mpi() is None, "softevo-mpi not built (set SOFTEVO_BINARY_DIR)")
class RealGrid(unittest.TestCase):
    """A real 2x2 gait grid (open/closed x 2 seeds), tiny: 4 individuals, 2 generations, 1 s."""

    def test_real_archives_make_every_gait_figure(self):
        tmp = pathlib.Path(tempfile.mkdtemp(prefix="softevo_test_analysis_real_"))
        try:
            runs = tmp / "runs"
            runs.mkdir()
            quickstart = REPO / "configs" / "quickstart.toml"
            for control in ("open", "closed"):
                for seed in (1, 2):
                    cmd = [str(find_softevo_mpi()), "--config", str(quickstart), "--seed", str(seed),
                           "--out", str(runs / f"gait-{control}-{seed:02d}.h5"),
                           "--generations", "2", "--population", "4",
                           "--set", "task.kind=gait", "--set", f"task.control={control}",
                           "--set", "task.eval_seconds=1.0"]
                    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
                    self.assertEqual(res.returncode, 0, f"{cmd}\n{res.stdout}\n{res.stderr}")
            result = run_figures(runs, tmp / "figs")
            self.assertEqual(result.returncode, 0, result.stderr)
            for name in ("fitness_gait.png", "fitness_gait.pdf", "fitness_gait-open.csv",
                         "fitness_gait-closed.csv", "comparison_gait.png", "comparison.csv",
                         "champions.csv", "champions.png"):
                self.assertTrue((tmp / "figs" / name).is_file(), name)
            with open(tmp / "figs" / "champions.csv") as f:
                rows = list(csv.DictReader(f))
            self.assertEqual(len(rows), 4)
            self.assertEqual({int(r["generations"]) for r in rows}, {2})
            # An archive changed after the run (a fitness rewritten) is skipped, with the reason.
            with h5py.File(runs / "gait-open-01.h5", "r+") as f:
                f["generations/000001/fitness"][0] = 123.456
            result = run_figures(runs, tmp / "figs-tampered")
            self.assertEqual(result.returncode, 0, result.stderr)
            self.assertIn("gait-open-01.h5", result.stderr)
            self.assertIn("integrity FAILED", result.stderr)
            self.assertIn("gait-open x1", result.stdout)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    unittest.main(verbosity=2)

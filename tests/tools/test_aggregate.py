"""slurm/aggregate.py: a malformed --array, --reps or --experiments is a usage error (exit 2)
naming the option, checked before any archive is read (before: a Python traceback, or an
IndexError for a task beyond the grid).

Run: python3 -m pytest tests/tools/test_aggregate.py   (ctest does this)
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(os.environ.get("SOFTEVO_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SCRIPT = REPO / "slurm" / "aggregate.py"


@pytest.mark.parametrize("extra, message", [
    (["--array", "0-x"], "--array '0-x': give task ranges"),
    (["--array", "40"], "--array 40: task 40 is outside the grid of 4 experiments x 10"),
    (["--array", "0-3", "--reps", "0"], "--reps 0: must be >= 1"),
    (["--experiments", ","], "--experiments: give at least one experiment"),
    (["--array", "2", "--reps", "1", "--experiments", "gait-open,dir-open"],
     "task 2 is outside the grid of 2 experiments x 1 repetitions (tasks 0-1)"),
])
def test_bad_grid_options_are_usage_errors(tmp_path, extra, message):
    done = subprocess.run([sys.executable, str(SCRIPT), "--softevo", "/bin/false", "--runs",
                           str(tmp_path), *extra], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stderr
    assert message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "grid-summary.tsv").exists()


def test_missing_archives_are_problems_not_a_crash(tmp_path):
    done = subprocess.run([sys.executable, str(SCRIPT), "--softevo", "/bin/false", "--runs",
                           str(tmp_path), "--array", "0-1", "--reps", "2",
                           "--experiments", "gait-open"], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("PROBLEM: ") == 2, done.stderr
    assert (tmp_path / "grid-summary.tsv").read_text().startswith("experiment\tseed")

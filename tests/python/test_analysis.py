"""analysis/ on the softevo package: lineage.py prints the package's lineage of a real run, and
the scripts say clearly what is missing (no traceback) under a Python without their
requirements (pyproject.toml). The figures themselves: tests/tools/test_analysis.py."""

import os
import subprocess
import sys


import softevo
from conftest import SOURCE_DIR

ANALYSIS = SOURCE_DIR / "analysis"


def run_script(*args: str, code: str | None = None) -> subprocess.CompletedProcess:
    command = [sys.executable, "-c", code, *args] if code else [sys.executable, *args]
    return subprocess.run(command, capture_output=True, text=True, env=dict(os.environ), timeout=120)


def test_lineage_prints_the_package_lineage(tiny_run):
    done = run_script(str(ANALYSIS / "lineage.py"), str(tiny_run), "--csv")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().splitlines()
    assert lines[0].startswith("generation,id,fitness,status")
    run = softevo.open_run(tiny_run)
    expected = run.lineage(run.best()[1], generation=run.generations[-1])
    assert len(lines) == 1 + len(expected)
    assert lines[1].split(",")[1] == str(expected[0]["id"])


def test_lineage_of_a_missing_archive_is_a_message(tmp_path):
    done = run_script(str(ANALYSIS / "lineage.py"), str(tmp_path / "none.h5"))
    assert done.returncode == 2
    assert "none.h5" in done.stderr and "Traceback" not in done.stderr


BLOCK_MATPLOTLIB = (
    "import runpy, sys; sys.modules['matplotlib'] = None; sys.argv = sys.argv[1:];"
    "runpy.run_path(sys.argv[0], run_name='__main__')")


def test_figures_without_matplotlib_says_what_to_install(tmp_path):
    done = run_script(str(ANALYSIS / "figures.py"), str(tmp_path), "-o", str(tmp_path / "o"),
                      code=BLOCK_MATPLOTLIB)
    assert done.returncode != 0
    assert "lacks matplotlib" in done.stderr and "python3-matplotlib" in done.stderr
    assert "pyproject.toml" in done.stderr
    assert "Traceback" not in done.stderr

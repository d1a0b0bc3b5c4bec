"""cmake/GitCommit.cmake: the commit a build records (archives' git_commit, --version) is taken at
every build, marks uncommitted changes to tracked files, and rewrites its file only when the
commit changed (so an unchanged tree recompiles nothing).

Run: python3 -m pytest tests/tools/test_git_commit.py   (ctest does this)
"""

from __future__ import annotations

import os
import pathlib
import re
import shutil
import subprocess

import pytest

REPO = pathlib.Path(os.environ.get("SOFTEVO_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SCRIPT = REPO / "cmake" / "GitCommit.cmake"
CMAKE = os.environ.get("SOFTEVO_CMAKE", shutil.which("cmake") or "cmake")

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")


def recorded(source: pathlib.Path, output: pathlib.Path) -> str:
    subprocess.run([CMAKE, f"-DSOURCE_DIR={source}", f"-DOUTPUT={output}", "-P", str(SCRIPT)],
                   check=True, capture_output=True)
    match = re.search(r'return "([^"]*)";', output.read_text())
    assert match, output.read_text()
    return match.group(1)


def git(repo: pathlib.Path, *args: str) -> str:
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@example.org",
                           "-c", "commit.gpgsign=false", *args], cwd=repo, check=True,
                          capture_output=True, text=True).stdout.strip()


def committed_repo(tmp_path: pathlib.Path) -> pathlib.Path:
    """A new repository with one commit of a.txt."""
    repo = tmp_path / "repo"
    repo.mkdir()
    git(repo, "init", "-q")
    (repo / "a.txt").write_text("one\n")
    git(repo, "add", "a.txt")
    git(repo, "commit", "-q", "-m", "first")
    return repo


def test_the_commit_then_dirty_then_the_next_commit(tmp_path):
    repo = committed_repo(tmp_path)
    out = tmp_path / "git_commit.cpp"
    first = git(repo, "rev-parse", "--short=12", "HEAD")
    assert recorded(repo, out) == first
    (repo / "untracked.txt").write_text("not part of the build\n")
    assert recorded(repo, out) == first  # untracked files do not make a tree dirty
    (repo / "a.txt").write_text("two\n")
    assert recorded(repo, out) == first + "-dirty"
    git(repo, "commit", "-q", "-am", "second")
    second = git(repo, "rev-parse", "--short=12", "HEAD")
    assert second != first
    assert recorded(repo, out) == second  # a rebuild after a commit records the new one


def test_an_unchanged_commit_rewrites_nothing(tmp_path):
    repo = committed_repo(tmp_path)
    out = tmp_path / "git_commit.cpp"
    recorded(repo, out)
    os.utime(out, ns=(1_000_000_000, 1_000_000_000))
    recorded(repo, out)
    assert out.stat().st_mtime_ns == 1_000_000_000


def test_without_git_the_commit_is_unknown(tmp_path, monkeypatch):
    plain = tmp_path / "tarball"
    plain.mkdir()
    # GIT_CEILING_DIRECTORIES keeps git from finding a repository above the temporary directory.
    monkeypatch.setenv("GIT_CEILING_DIRECTORIES", str(tmp_path))
    assert recorded(plain, tmp_path / "git_commit.cpp") == "unknown"

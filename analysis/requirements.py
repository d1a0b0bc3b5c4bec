"""What the analysis scripts need, read from the one place that states it: pyproject.toml
([project] dependencies and the optional "analysis" group). A script calls require() before
its third-party imports; a missing module ends it with a message saying what to install,
not a traceback."""

from __future__ import annotations

import importlib.util
import pathlib
import sys
import tomllib

PYPROJECT = pathlib.Path(__file__).resolve().parents[1] / "pyproject.toml"
DEBIAN = {"numpy": "python3-numpy", "matplotlib": "python3-matplotlib", "scipy": "python3-scipy",
          "pandas": "python3-pandas", "pytest": "python3-pytest"}


def _module_of(requirement: str) -> str:
    """'numpy>=1.24' -> 'numpy'."""
    name = requirement
    for sep in "<>=!~;[ ":
        name = name.split(sep)[0]
    return name.strip().replace("-", "_")


def requirements(group: str | None) -> list[str]:
    """The package's dependencies plus optional group `group` (if any), as module names."""
    project = tomllib.loads(PYPROJECT.read_text())["project"]
    listed = list(project.get("dependencies", []))
    if group:
        listed += project.get("optional-dependencies", {}).get(group, [])
    return [_module_of(r) for r in listed]


def require(script: str, group: str | None = "analysis") -> None:
    """Exit with a clear message (status 2) unless softevo and every module it and `group`
    need import."""
    missing = [m for m in requirements(group) if importlib.util.find_spec(m) is None]
    if missing:
        debs = " ".join(DEBIAN.get(m, f"python3-{m}") for m in missing)
        sys.exit(f"{script}: this Python ({sys.executable}) lacks {', '.join(missing)}.\n"
                 f"  Debian: apt install {debs} and run /usr/bin/python3\n"
                 f"  pip:    pip install '.{f'[{group}]' if group else ''}' (the requirements are "
                 f"in {PYPROJECT})")
    if importlib.util.find_spec("softevo") is None:
        sys.exit(f"{script}: the softevo Python package is not importable from {sys.executable}.\n"
                 f"  Build it with `bash tools/bootstrap.sh quickstart` (it installs a .pth file "
                 f"for /usr/bin/python3), or put <build>/python on PYTHONPATH")

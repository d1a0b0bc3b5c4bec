"""Loads a developer script of tools/dev/ as a module for its pytest file (the scripts are not a package)."""

from __future__ import annotations

import importlib.util
import os
import pathlib
import sys

REPO = pathlib.Path(os.environ.get("SOFTEVO_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


def load_tool(name: str):
    """tools/dev/<name>.py as module `name` (registered in sys.modules: dataclasses look it up)."""
    spec = importlib.util.spec_from_file_location(name, REPO / "tools" / "dev" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module

"""Shared fixtures of the Python package tests (run by ctest: tests/python/CMakeLists.txt).

The package comes from PYTHONPATH (<build>/python, set by ctest); the built executables from
SOFTEVO_BINARY_DIR; the thesis champions from <source>/../shared/reference/bestbots, as the
C++ tests find them (tests/reference_data.hpp): tests that need them skip when it is absent.
"""

from __future__ import annotations

import json
import math
import os
import pathlib
import subprocess

import pytest

import softevo

SOURCE_DIR = pathlib.Path(os.environ.get("SOFTEVO_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
BINARY_DIR = pathlib.Path(os.environ.get("SOFTEVO_BINARY_DIR", SOURCE_DIR / "build"))
BESTBOTS = SOURCE_DIR / ".." / "shared" / "reference" / "bestbots"


def champion(name: str) -> softevo.Robot:
    """A thesis champion robot file; skips the test when the reference data is absent."""
    path = BESTBOTS / f"{name}.robot.json"
    if not path.exists():
        pytest.skip(f"reference data not found ({BESTBOTS})")
    return softevo.load_robot(path)


def block_robot_json(closed: bool = False, directed: bool = False, name: str = "block") -> dict:
    """A 7x4x4 block of material 10 with two chambers behind each other along x and a complete
    controller (the synthetic robot of the C++ worker tests)."""
    lx, ly, lz = 7, 4, 4
    cells = [10] * (lx * ly * lz)
    for y in (1, 2):
        for z in (1, 2):
            for x, chamber in ((1, 11), (2, 11), (4, 12), (5, 12)):
                cells[(x * ly + y) * lz + z] = chamber
    inputs = 2 + (1 if directed else 0) + (10 if closed else 0)
    pattern = lambda n, scale: [scale * math.sin(2.0 + 1.3 * i) for i in range(n)]  # noqa: E731
    return {
        "format": "softevo.robot/1",
        "name": name,
        "voxel_size": 0.01,
        "lattice": [lx, ly, lz],
        "cells": cells,
        "materials": {str(k): {"youngs_modulus": 1.0e4 * k, "density": 1000.0} for k in range(1, 11)},
        "controller": {
            "kind": "elman", "control": "closed" if closed else "open", "directed": directed,
            "hidden": 4, "outputs": 20, "frequency": 3.0,
            "weights_hidden": pattern(inputs * 4, 1.5), "bias_hidden": pattern(4, 0.5),
            "weights_out": pattern(80, 2.0), "bias_out": pattern(20, 0.5),
            "weights_recurrent": pattern(16, 0.5), "weights_recurrent_self": pattern(4, 0.5),
            "weights_context": pattern(4, 0.5), "bias_context": pattern(4, 0.1),
        },
    }


def block_robot(closed: bool = False, directed: bool = False) -> softevo.Robot:
    """block_robot_json() as a Robot."""
    return softevo.Robot.from_json(json.dumps(block_robot_json(closed, directed)), "<block>")


def binary(name: str) -> pathlib.Path:
    """A built executable; skips the test when it was not built."""
    path = BINARY_DIR / "bin" / name
    if not path.exists():
        pytest.skip(f"{path} not built")
    return path


@pytest.fixture(scope="session")
def learning_run(tmp_path_factory) -> pathlib.Path:
    """A tiny real run with controller learning (docs/model.md §8.11): 2 generations of 4
    robots, 0.3 s each, 5 evaluations per new body."""
    path = tmp_path_factory.mktemp("learn") / "learn.h5"
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    subprocess.run([str(binary("softevo-mpi")), "--config", str(SOURCE_DIR / "configs/quickstart.toml"),
                    "--seed", "5", "--generations", "2", "--population", "4",
                    "--set", "body.lattice=[4,4,4]", "--set", "task.eval_seconds=0.3",
                    "--set", "learning.method=es", "--set", "learning.evaluations=5",
                    "--set", "learning.population=2", "--out", str(path)],
                   check=True, env=env, capture_output=True, cwd=SOURCE_DIR)
    return path


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory) -> pathlib.Path:
    """A tiny real run archive (2 generations of 6 robots, 0.5 s each) made by softevo-mpi."""
    path = tmp_path_factory.mktemp("run") / "tiny.h5"
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    subprocess.run([str(binary("softevo-mpi")), "--config", str(SOURCE_DIR / "configs/quickstart.toml"),
                    "--seed", "3", "--generations", "2", "--population", "6",
                    "--set", "task.eval_seconds=0.5", "--out", str(path)],
                   check=True, env=env, capture_output=True, cwd=SOURCE_DIR)
    return path

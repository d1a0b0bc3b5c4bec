"""The worked examples in examples/, each run at a tiny size: champions evaluated from Python,
controller learning with a numpy evolution strategy, a random policy on SoftRobotEnv."""

import os
import subprocess
import sys


import pytest

import softevo
from conftest import BESTBOTS, SOURCE_DIR, block_robot

EXAMPLES = SOURCE_DIR / "examples"


def run_example(name: str, *args: str) -> str:
    done = subprocess.run([sys.executable, str(EXAMPLES / name), *args], capture_output=True,
                          text=True, env=dict(os.environ), timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_evaluate_champions():
    if not BESTBOTS.exists():
        pytest.skip(f"reference data not found ({BESTBOTS})")
    out = run_example("evaluate_champions.py", "--reference", str(BESTBOTS), "--seconds", "0.2",
                      "--workers", "2", "gait-open-01", "dir-closed-04")
    assert "gait-open-01" in out and "dir-closed-04" in out and "2 robots" in out


def test_evaluate_the_sample_robots_by_default():
    samples = sorted((SOURCE_DIR / "robots").glob("*.robot.json"))
    assert len(samples) >= 4, "robots/ holds the sample robots"
    out = run_example("evaluate_champions.py", "--seconds", "0.1", "--workers", "2")
    assert f"{len(samples)} robots" in out
    for path in samples:
        assert softevo.load_robot(path).name in out


def test_evaluate_champions_without_the_reference(tmp_path):
    out = run_example("evaluate_champions.py", "--reference", str(tmp_path / "none"))
    assert "robot folder not found" in out and "nothing to do" in out


def test_learn_controller_improves_the_fitness(tmp_path):
    robot = tmp_path / "block.json"
    block_robot().save(str(robot))
    out = run_example("learn_controller.py", "--robot", str(robot), "--iterations", "3",
                      "--population", "4", "--seconds", "0.25", "--workers", "2")
    lines = [l for l in out.splitlines() if l.startswith("iteration")]
    assert len(lines) == 3
    parent = [float(l.split()[7]) for l in lines]
    assert parent == sorted(parent)  # elitist: never falls
    assert "iterations x 4 evaluations" in out


def test_learn_controller_is_deterministic(tmp_path):
    sys.path.insert(0, str(EXAMPLES))
    try:
        import learn_controller
    finally:
        sys.path.pop(0)
    robot = block_robot()
    first = learn_controller.learn(robot, 2, 4, 0.5, 0.2, seed=7, workers=2, log=lambda s: None)
    second = learn_controller.learn(robot, 2, 4, 0.5, 0.2, seed=7, workers=1, log=lambda s: None)
    assert first == second


def test_random_policy(tmp_path):
    robot = tmp_path / "block.json"
    block_robot().save(str(robot))
    out = run_example("random_policy.py", "--robot", str(robot), "--episodes", "2",
                      "--seconds", "0.1")
    assert out.count("episode") == 2 and "in 6 steps" in out

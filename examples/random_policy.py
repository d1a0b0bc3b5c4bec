#!/usr/bin/env python3
"""Drive softevo.env.SoftRobotEnv with a random policy.

    python3 examples/random_policy.py [--robot FILE] [--episodes N] [--seconds T] [--seed K]

Each step opens the valves at random (the action space's sampler); each episode prints its
return (= the task's fitness of the random motion), its length and how it ended. Default
robot: the sample gait walker of the repository (robots/gait-open-walker.robot.json).
"""

from __future__ import annotations

import argparse
import pathlib
import sys

import softevo
import softevo.env

DEFAULT_ROBOT = pathlib.Path(__file__).resolve().parents[1] / "robots" / "gait-open-walker.robot.json"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", type=pathlib.Path, default=None)
    ap.add_argument("--episodes", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    path = args.robot or DEFAULT_ROBOT
    if args.robot is None and not path.exists():
        print(f"random_policy: {path} not found; give --robot FILE")
        return 0
    env = softevo.env.SoftRobotEnv(softevo.load_robot(path), seconds=args.seconds)
    for episode in range(args.episodes):
        env.reset(seed=args.seed + episode)
        total, steps, done = 0.0, 0, False
        while not done:
            _, reward, terminated, truncated, info = env.step(env.action_space.sample())
            total += reward
            steps += 1
            done = terminated or truncated
        print(f"episode {episode}: return {total:.4f} in {steps} steps "
              f"({'terminated: ' + info['status'] if terminated else 'truncated'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Writes examples/quickstart.ipynb from the cells below (the notebook is generated, so its
source stays reviewable here; run this after changing a cell). Needs nbformat (Debian:
python3-nbformat). CI executes the notebook headless (tools/run_notebook.py)."""

import pathlib

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

CELLS = [
    ("md", """# softevo quickstart

Load a robot that ships with the repository, evaluate it, step its simulation with its own
controller, evolve a few generations with `softevo.evolve`, plot the fitness and look at a
frame of the headless renderer. Everything runs on the CPU of this machine, in a few seconds.

Start Jupyter with the interpreter the package was built for (Debian's `/usr/bin/python3`
after `bash tools/bootstrap.sh quickstart`)."""),
    ("code", """import pathlib
import tempfile

import matplotlib.pyplot as plt
import numpy as np

import softevo
import softevo.env

# The repository root (the notebook may be started from examples/ or from the root).
ROOT = next(p for p in [pathlib.Path.cwd(), *pathlib.Path.cwd().parents]
            if (p / "configs" / "quickstart.toml").exists())
print("softevo", softevo.__version__, "from", ROOT)"""),
    ("md", """## A sample robot

`robots/` holds robots evolved by softevo itself (robots/README.md names the command that
evolved each one and its fitness). A robot file carries its run's settings, so `evaluate`
reproduces the archived fitness bit for bit."""),
    ("code", """robot = softevo.load_robot(ROOT / "robots" / "gait-open-walker.robot.json")
print(robot)
result = softevo.evaluate(robot)
result.to_dict()"""),
    ("md", """## Step the simulation

One step is one 60 Hz control frame. The robot's own controller as a policy gives the same
bits as `evaluate` (here for the first 3 s, to keep the notebook fast). Observations give every
pressure in Pa, lengths in m."""),
    ("code", """sim = softevo.Simulation(robot, seconds=3)
controller = softevo.Controller(robot)
obs = sim.reset()
xs, ts = [], []
while not sim.done:
    obs, info = sim.step(controller.act(obs))
    ts.append(obs["time"])
    xs.append(100 * obs["centroid"][0])  # [cm]
assert sim.result().fitness == softevo.evaluate(robot, seconds=3).fitness  # the same bits
plt.figure(figsize=(6, 3))
plt.plot(ts, xs)
plt.xlabel("time [s]")
plt.ylabel("centroid x displacement [cm]")
plt.title(f"{robot.name}: the first 3 s of its {result.fitness:.2f} cm walk")
plt.tight_layout()
plt.show()"""),
    ("md", """## Evolve a few generations

`softevo.evolve` runs the evolution of `softevo-mpi` in this process, one worker thread per
core; the archive is the one `softevo evolve` and `mpirun ... softevo-mpi` write for the same
config (the same `fitness_digest`). Here a tiny version of `configs/quickstart.toml` so that it
takes seconds; Ctrl-C (Interrupt the kernel) checkpoints, `resume=True` continues."""),
    ("code", """out = pathlib.Path(tempfile.mkdtemp()) / "notebook.h5"
history = []
run = softevo.evolve(ROOT / "configs" / "quickstart.toml", out=out, generations=4, population=8,
                     overrides={"body.lattice": [5, 5, 5], "task.eval_seconds": 1.0},
                     callback=lambda gen: history.append(gen))
for gen in history:
    print(f"generation {gen.generation}: best {gen.best:.3f} {gen.fitness_unit}, "
          f"mean {gen.mean:.3f}, {gen.status_counts}")
print(run, run.fitness_digest())"""),
    ("code", """stats = run.stats()
plt.figure(figsize=(6, 3))
plt.plot(stats["generation"], stats["best"], marker="o", label="best")
plt.plot(stats["generation"], stats["mean"], marker="o", label="mean")
plt.xticks(stats["generation"])
plt.xlabel("generation")
plt.ylabel("fitness [cm]")
plt.legend()
plt.tight_layout()
plt.show()"""),
    ("md", """## A rendered frame

`SoftRobotEnv(render_mode="rgb_array")` draws frames with the headless renderer of
`softevo render` (no display, no GPU): here the sample robot after one second of walking."""),
    ("code", """env = softevo.env.SoftRobotEnv(robot, render_mode="rgb_array", render_size=(480, 320))
obs, info = env.reset()
policy = softevo.Controller(robot)
state = env.simulation.observation()
for _ in range(60):
    obs, reward, terminated, truncated, info = env.step(policy.act(state))
    state = env.simulation.observation()
frame = env.render()
plt.figure(figsize=(6, 4))
plt.imshow(frame)
plt.axis("off")
plt.show()
frame.shape"""),
]


def main() -> None:
    nb = new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    for kind, text in CELLS:
        nb.cells.append(new_markdown_cell(text) if kind == "md" else new_code_cell(text))
    path = pathlib.Path(__file__).resolve().parents[2] / "examples" / "quickstart.ipynb"
    nbformat.write(nb, path)
    print("wrote", path)


if __name__ == "__main__":
    main()

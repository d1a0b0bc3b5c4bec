"""softevo.evolve / softevo.evolution: an evolution from Python writes the archive of
`softevo evolve` and softevo-mpi (fitness and content digests), yields each generation's stats
and best robot, stops on request or Ctrl-C with a checkpoint, and resumes to the same bits."""

import os
import re
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

import softevo
from conftest import SOURCE_DIR, binary

@pytest.fixture
def tiny_config():
    """The tiny real problem shared with tests/tools/test_cmd_evolve.cpp."""
    return SOURCE_DIR / "tests" / "data" / "tiny-run.toml"


def digests(path):
    out = subprocess.run([str(binary("softevo")), "info", str(path), "--json"], check=True,
                         capture_output=True, text=True).stdout
    import json
    info = json.loads(out)
    return info["fitness_digest"], info.get("content_digest")


def test_evolve_writes_the_archive_of_the_command_line(tiny_config, tmp_path):
    cli = tmp_path / "cli.h5"
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    subprocess.run([str(binary("softevo-mpi")), "--config", str(tiny_config), "--out", str(cli),
                    "-q"], check=True, env=env)
    seen = []
    run = softevo.evolve(tiny_config, workers=2, out=tmp_path / "py.h5", callback=seen.append)
    assert isinstance(run, softevo.Run)
    assert run.info["state"] == "complete"
    assert run.info["ranks"] == 3
    assert run.fitness_digest() == softevo.open_run(cli).fitness_digest()
    assert digests(tmp_path / "py.h5") == digests(cli)
    assert [g.generation for g in seen] == [0, 1, 2]
    stats = run.stats()
    for g in seen:
        assert g.generations == 3
        assert g.fitness_unit == "cm"
        assert g.best == pytest.approx(float(stats["best"][g.generation]), abs=0)
        assert g.individuals >= 6 and sum(g.status_counts.values()) == g.individuals
        assert isinstance(g.best_robot, softevo.Robot)
        assert "best_robot" not in g.to_dict()
    # The best robot re-evaluates to its archived fitness (it carries its run's config).
    last = seen[-1]
    assert softevo.evaluate(last.best_robot).fitness == last.best


# Controller learning on the tiny problem (docs/model.md §8.11): 2 generations, every new body
# learns for 5 evaluations (born + 2 iterations of 2 candidates).
LEARNING = {"learning.method": "es", "learning.evaluations": 5, "learning.population": 2}


def test_evolve_with_controller_learning_writes_the_archive_of_the_command_line(tiny_config,
                                                                                tmp_path):
    cli = tmp_path / "cli.h5"
    sets = [arg for key, value in LEARNING.items() for arg in ("--set", f"{key}={value}")]
    subprocess.run([str(binary("softevo")), "evolve", "--config", str(tiny_config),
                    "--generations", "2", "-j", "2", "-q", "--out", str(cli), *sets], check=True)
    seen = []
    run = softevo.evolve(tiny_config, workers=2, out=tmp_path / "py.h5", generations=2,
                         overrides=LEARNING, callback=seen.append)
    assert run.info["state"] == "complete"
    assert run.info["experiment"] == "gait-open-learn"
    assert run.fitness_digest() == softevo.open_run(cli).fitness_digest()
    assert digests(tmp_path / "py.h5") == digests(cli)
    assert [g.generation for g in seen] == [0, 1]

    rows = run.individuals()
    fresh = rows[np.asarray(rows["reused_from"]) == -1]
    assert len(fresh) >= 6
    assert (np.asarray(fresh["learn_evaluations"]) == 5).all()
    reused = rows[np.asarray(rows["reused_from"]) != -1]
    assert (np.asarray(reused["learn_evaluations"]) == 5).all()  # repeats its origin's
    gained = 0
    for before, after, curve in zip(rows["fitness_before"], rows["fitness"],
                                    rows["learning_curve"]):
        assert len(curve) == 3 and curve[0] == before and curve[-1] == after
        assert np.all(np.diff(curve) >= 0)
        gained += after > before
    assert gained > 0  # learning found better controllers on the real problem
    # The best robot of the last generation is the learned one: it evaluates to its fitness.
    assert softevo.evaluate(seen[-1].best_robot).fitness == seen[-1].best


def test_no_lock_file_stays_beside_a_finished_archive(tiny_config, tmp_path):
    """As on the command line (issue 39: Python runs left RUN.h5.lock behind)."""
    out = tmp_path / "done.h5"
    softevo.evolve(tiny_config, workers=1, out=out, generations=1)
    assert out.exists()
    assert not (tmp_path / "done.h5.lock").exists()
    stopped = tmp_path / "stopped.h5"
    softevo.evolve(tiny_config, workers=1, out=stopped, generations=3,
                   callback=lambda g: False)
    assert not (tmp_path / "stopped.h5.lock").exists()
    with softevo.evolution(tiny_config, workers=1, out=tmp_path / "never.h5"):
        pass  # closed before its first generation
    assert not (tmp_path / "never.h5.lock").exists()


def test_a_full_disk_raises_and_the_interpreter_lives_on(tiny_config, tmp_path):
    """A real full disk (a 200 kB tmpfs; root only): evolve raises RunError naming the cause and
    the interpreter exits normally afterwards (issue 39: it crashed at exit in libhdf5's
    clean-up). In a child interpreter, whose exit is what is checked."""
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    small = tmp_path / "small"
    small.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(small)]).returncode:
        pytest.skip("cannot mount a small tmpfs")
    try:
        script = (
            "import softevo, sys\n"
            "try:\n"
            f"    softevo.evolve({str(tiny_config)!r}, workers=1, out={str(small / 'r.h5')!r},\n"
            "                   generations=6, progress=False)\n"
            "except softevo.RunError as e:\n"
            "    print('raised:', e)\n"
            "    sys.exit(0)\n"
            "sys.exit(3)\n")
        child = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
        assert child.returncode == 0, child.stdout + child.stderr
        assert "raised:" in child.stdout and "No space left on device" in child.stdout
    finally:
        subprocess.run(["umount", "-l", str(small)])


def test_progress_lines_by_default_and_silence_on_request(tiny_config, tmp_path, capsys):
    """The command line's line per generation with its ETA (issue 39: evolve printed nothing)."""
    softevo.evolve(tiny_config, workers=1, out=tmp_path / "loud.h5", generations=2)
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("gen ")]
    assert len(lines) == 2, lines
    assert "0/2" in lines[0] and "best" in lines[0] and "ETA" in lines[0]
    softevo.evolve(tiny_config, workers=1, out=tmp_path / "quiet.h5", generations=2,
                   progress=False)
    assert capsys.readouterr().out == ""
    with pytest.raises(TypeError, match="progress"):
        softevo.evolve(tiny_config, out=tmp_path / "x.h5", progress="yes")


def test_a_config_object_and_the_iterator(tiny_config, tmp_path):
    config = softevo.load_config(tiny_config)
    out = tmp_path / "it.h5"
    with softevo.evolution(config, workers=1, out=out, generations=2) as evo:
        gens = [g.generation for g in evo]
    assert gens == [0, 1]
    assert evo.state == "complete"
    assert softevo.open_run(out).info["generations_done"] == 2


def test_stop_and_resume_give_the_same_bits(tiny_config, tmp_path):
    ref = softevo.evolve(tiny_config, workers=2, out=tmp_path / "ref.h5")
    out = tmp_path / "stopped.h5"
    run = softevo.evolve(tiny_config, workers=2, out=out, callback=lambda g: g.generation < 1)
    assert run.info["state"] == "interrupted"
    assert run.info["generations_done"] == 2
    # in Python's words (issue 39: it said "pass --resume ... --overwrite ... --out")
    with pytest.raises(softevo.RunError, match="exists: pass resume=True to continue it, "
                       "overwrite=True to replace it, or choose another out=") as e:
        softevo.evolve(tiny_config, workers=2, out=out)
    assert "--" not in str(e.value)
    done = softevo.evolve(tiny_config, workers=3, out=out, resume=True)
    assert done.info["state"] == "complete"
    assert done.fitness_digest() == ref.fitness_digest()
    assert digests(out) == digests(tmp_path / "ref.h5")


def test_ctrl_c_checkpoints_and_resume_completes(tiny_config, tmp_path):
    ref = softevo.evolve(tiny_config, workers=2, out=tmp_path / "ref.h5", generations=5)
    out = tmp_path / "interrupted.h5"

    def interrupt_soon(gen):
        if gen.generation == 1:  # Ctrl-C while generation 2 is evaluated (or just before)
            threading.Timer(0.01, os.kill, (os.getpid(), signal.SIGINT)).start()

    with pytest.raises(KeyboardInterrupt):
        softevo.evolve(tiny_config, workers=2, out=out, generations=5, callback=interrupt_soon)
    info = softevo.open_run(out).info
    assert info["state"] == "interrupted"
    assert 2 <= info["generations_done"] < 5
    done = softevo.evolve(tiny_config, workers=2, out=out, generations=5, resume=True)
    assert done.fitness_digest() == ref.fitness_digest()


def test_bad_arguments(tiny_config, tmp_path):
    with pytest.raises(ValueError, match="workers"):
        softevo.evolve(tiny_config, workers=0, out=tmp_path / "x.h5")
    # the command line's cap: 100,000 threads aborted the interpreter (issue 39)
    with pytest.raises(ValueError, match="workers must be an int from 1 to 4096"):
        softevo.evolve(tiny_config, workers=100000, out=tmp_path / "x.h5")
    with pytest.raises(ValueError, match="at most 4096"):
        softevo._softevo._Evolution(softevo.load_config(tiny_config), str(tmp_path / "x.h5"),
                                    4097, False, False)
    with pytest.raises(TypeError, match="config"):
        softevo.evolve(42, out=tmp_path / "x.h5")
    with pytest.raises(FileNotFoundError):
        softevo.evolve(tmp_path / "absent.toml", out=tmp_path / "x.h5")
    with pytest.raises(softevo.ConfigError, match="pop_size"):
        softevo.evolve(tiny_config, out=tmp_path / "x.h5", overrides={"neat.pop_size": -3})
    # A shorthand out of range is named as passed, not as the override it becomes.
    for argument, value, key in (("generations", -1, "run.generations"),
                                 ("population", 1, "neat.pop_size"), ("seed", -5, "run.seed")):
        with pytest.raises(softevo.ConfigError,
                           match=rf"^{argument}={value}: {key} = {value} is out of range"):
            softevo.evolve(tiny_config, out=tmp_path / "x.h5", **{argument: value})
    # overrides is a dict of "section.key" or a list of "section.key=value" strings.
    for overrides, item in (([("neat.pop_size", 4)], "item ('neat.pop_size', 4) (tuple) is not"),
                            ({3: 4}, "key 3 (int) is not a string"), (7, "strings, not int")):
        with pytest.raises(TypeError, match=re.escape(item)):
            softevo.evolve(tiny_config, out=tmp_path / "x.h5", overrides=overrides)
    assert not (tmp_path / "x.h5").exists()


def test_best_robot_of_a_resampled_ground_re_evaluates_to_its_fitness(tiny_config, tmp_path):
    # Bumps drawn anew every generation: the robot file carries the generation and id it was
    # archived with, and evaluate() / Simulation take their ground from them.
    rough = {"terrain.kind": "heightfield", "terrain.heightfield": "bumps",
             "terrain.amplitude": 0.01, "terrain.correlation_length": 0.05,
             "terrain.resample": "per_generation"}
    gens = list(softevo.evolution(tiny_config, workers=2, out=tmp_path / "rough.h5",
                                  overrides=rough))
    for gen in gens[1:]:
        assert softevo.evaluate(gen.best_robot).fitness == gen.best
    sim = softevo.Simulation(gens[-1].best_robot)
    controller = softevo.Controller(gens[-1].best_robot)
    obs = sim.reset()
    while not sim.done:
        obs, _ = sim.step(controller.act(obs))
    assert sim.result().fitness == gens[-1].best

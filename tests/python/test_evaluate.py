"""softevo.evaluate / evaluate_many: the fitness bits of `softevo eval --json` on the same
inputs (tasks, closed loop, ablations, integrator, direction, config), results in order from
threads, and bad input as exceptions."""

import json
import struct
import subprocess

import pytest

import softevo
from conftest import SOURCE_DIR, binary, block_robot, champion


def bits(x: float) -> int:
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def cli_eval(robot: softevo.Robot, tmp_path, *flags: str) -> dict:
    path = tmp_path / "robot.json"
    robot.save(path, overwrite=True)
    out = subprocess.run([str(binary("softevo")), "eval", str(path), "--json", *flags],
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out)


CASES = [
    (dict(closed=False), dict(seconds=0.5), ["--seconds", "0.5"]),
    (dict(closed=True), dict(seconds=0.5, ablate="sensors"), ["--seconds", "0.5", "--ablate", "sensors"]),
    (dict(closed=True), dict(seconds=0.5, ablate=["oscillator", "sensors"]),
     ["--seconds", "0.5", "--ablate", "oscillator", "--ablate", "sensors"]),
    (dict(closed=False), dict(seconds=0.5, integrator="symplectic"),
     ["--seconds", "0.5", "--integrator", "symplectic"]),
    (dict(closed=False, directed=True), dict(seconds=0.5, direction=20.0),
     ["--seconds", "0.5", "--direction", "20"]),
    (dict(closed=False), dict(seconds=0.5, task="rotate"), ["--seconds", "0.5", "--task", "rotate"]),
]


@pytest.mark.parametrize("shape,kwargs,flags", CASES, ids=[str(c[1]) for c in CASES])
def test_fitness_bits_equal_softevo_eval(tmp_path, shape, kwargs, flags):
    robot = block_robot(**shape)
    cli = cli_eval(robot, tmp_path, *flags)
    result = softevo.evaluate(robot, **kwargs)
    assert bits(result.fitness) == bits(cli["fitness"])
    assert result.status == cli["status"]
    assert result.steps == cli["steps"]
    assert result.voxels == cli["voxels"] and result.chambers == cli["chambers"]
    assert result.task == cli["task"]
    names = [n for n, _ in result.component_names]
    assert names == [c["name"] for c in cli["component_names"]]
    for ours, theirs in zip(result.components, cli["components"]):
        for name in names:
            assert bits(ours[name]) == bits(theirs[name])


def test_with_a_config_equals_softevo_eval_with_that_config(tmp_path):
    config = softevo.load_config(SOURCE_DIR / "configs/quickstart.toml",
                                 {"task.eval_seconds": 0.5, "physics.global_damping": 0.002})
    config_file = tmp_path / "c.toml"
    config_file.write_text(config.text)
    robot = block_robot()
    cli = cli_eval(robot, tmp_path, "--config", str(config_file))
    assert bits(softevo.evaluate(robot, config=config).fitness) == bits(cli["fitness"])


def test_champion_bits_at_ten_seconds():
    result = softevo.evaluate(champion("gait-open-01"))
    assert result.fitness == 109.2838868090218
    assert result.status == "ok" and not result.killed
    assert result.components[0]["distance"] == result.fitness
    assert result.steps > 0 and result.voxels > 700


def test_evaluate_many_equals_one_by_one_in_order():
    robots = [block_robot(closed=c) for c in (False, True, False, True)]
    serial = [softevo.evaluate(r, seconds=0.25) for r in robots]
    parallel = softevo.evaluate_many(robots, seconds=0.25, workers=2)
    assert [bits(r.fitness) for r in parallel] == [bits(r.fitness) for r in serial]
    with pytest.raises(ValueError, match="workers"):
        softevo.evaluate_many(robots, workers=0)


def test_an_unactuatable_body_is_a_status():
    j = json.loads(block_robot().to_json())
    j["cells"] = [10 if c > 10 else c for c in j["cells"]]
    result = softevo.evaluate(softevo.Robot.from_json(json.dumps(j)), seconds=0.25)
    assert result.status == "invalid body" and result.killed and result.fitness == 0.0
    assert result.message


@pytest.mark.parametrize("kwargs,error,words", [
    (dict(task="swim"), softevo.ConfigError, "swim"),
    (dict(ablate="brain"), ValueError, "brain"),
    (dict(seconds=-1.0), ValueError, "seconds"),
    (dict(seconds=float("nan")), ValueError, "seconds"),
    (dict(integrator="euler"), ValueError, "euler"),
    (dict(direction=float("inf")), ValueError, "direction"),
])
def test_bad_arguments_raise(kwargs, error, words):
    with pytest.raises(error, match=words):
        softevo.evaluate(block_robot(), **kwargs)


def test_docstring_says_how():
    assert "softevo eval" in softevo.evaluate.__doc__
    assert "GIL" in softevo.evaluate.__doc__


def test_an_exported_robot_evaluates_with_its_runs_config_to_the_archived_bits(tiny_run, tmp_path):
    """Issue 22: `softevo export` writes the run's settings into the robot file; evaluate() uses
    them when given no config (config_source 'robot') and gives the archived fitness."""
    out = tmp_path / "best.json"
    subprocess.run([str(binary("softevo")), "export", str(tiny_run), "-o", str(out)],
                   check=True, capture_output=True)
    robot = softevo.load_robot(out)
    assert robot.evaluation is not None
    run = softevo.open_run(tiny_run)
    assert robot.evaluation["config_hash"] == run.info["config_hash"]
    result = softevo.evaluate(robot)
    assert result.config_source == "robot"
    assert bits(result.fitness) == bits(robot.evaluation["fitness"])
    assert softevo.evaluate(robot, config=softevo.default_config("gait")).config_source == "text"


def test_result_as_a_dict():
    import json as _json

    r = softevo.evaluate(block_robot(), seconds=0.2)
    d = r.to_dict()
    assert d["fitness"] == r.fitness and d["status"] == r.status and d["task"] == "gait"
    assert d["components"][0]["fitness"] == r.fitness
    assert set(d) >= {"steps", "voxels", "chambers", "sim_seconds", "wall_seconds", "message"}
    _json.dumps(d)  # plain values


def test_ctrl_c_interrupts_a_long_evaluation(tmp_path):
    # issue 29: a long softevo.evaluate() ignored Ctrl-C for 14 s; it now raises
    # KeyboardInterrupt within a fraction of a second.
    script = tmp_path / "long.py"
    script.write_text(
        "import sys, time, softevo\n"
        "sys.path.insert(0, %r)\n"
        "from conftest import block_robot\n"
        "print('start', flush=True)\n"
        "t = time.monotonic()\n"
        "try:\n"
        "    softevo.evaluate(block_robot(), seconds=3000)\n"
        "    print('finished')\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted after %%.2f' %% (time.monotonic() - t))\n" % str(SOURCE_DIR / "tests" / "python"))
    import os, signal, sys, time
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True,
                         env=os.environ.copy())
    assert p.stdout.readline().strip() == "start"
    time.sleep(1.0)
    t = time.monotonic()
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert "interrupted" in out, out
    assert time.monotonic() - t < 3.0

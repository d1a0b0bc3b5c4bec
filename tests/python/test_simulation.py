"""softevo.Simulation and softevo.Controller: stepping one control frame at a time with the
robot's own controller gives the bits of evaluate(); observations, state hash, time, status;
bad valve commands raise."""

import numpy as np
import pytest

import softevo
from conftest import block_robot, champion


def drive(sim: softevo.Simulation, controller: softevo.Controller) -> softevo.EvalResult:
    obs = sim.reset()
    controller.reset()
    while not sim.done:
        obs, info = sim.step(controller.act(obs))
    return sim.result()


@pytest.mark.parametrize("closed,directed,kwargs", [
    (False, False, dict(seconds=0.5)),
    (True, False, dict(seconds=0.5)),
    (True, True, dict(seconds=0.5, direction=-20.0)),
    (False, False, dict(seconds=0.5, task="rotate")),
])
def test_own_controller_through_step_gives_the_bits_of_evaluate(closed, directed, kwargs):
    robot = block_robot(closed=closed, directed=directed)
    expected = softevo.evaluate(robot, **kwargs)
    got = drive(softevo.Simulation(robot, **kwargs), softevo.Controller(robot))
    assert got.fitness == expected.fitness
    assert got.status == expected.status
    assert got.steps == expected.steps
    assert got.components == expected.components


def test_champion_closed_loop_two_seconds():
    robot = champion("gait-closed-10")
    expected = softevo.evaluate(robot, seconds=2)
    assert drive(softevo.Simulation(robot, seconds=2), softevo.Controller(robot)).fitness == expected.fitness


def test_observation_contents():
    robot = block_robot(closed=True, directed=True)
    sim = softevo.Simulation(robot, seconds=0.25, task="directed", observe_voxels=True)
    obs = sim.reset()
    assert obs["frame"] == 0 and obs["time"] == 0.0
    assert obs["pressures"].shape == (2,) and obs["sensor_pressures"].dtype == np.float32
    assert obs["sensor_pressures"].tolist() == [0.0, 0.0]  # §3.7: the first reading
    assert obs["task_inputs"].shape == (1,) and obs["direction_sensor"] == obs["task_inputs"][0]
    assert obs["centroid"].shape == (3,) and np.all(obs["centroid"] == 0.0)
    assert obs["positions"].shape == (sim.voxels, 3)
    assert obs["orientations"].shape == (sim.voxels, 4)
    obs, info = sim.step(np.ones((2, 2), dtype=np.float32))
    assert info["status"] == "ok" and info["frame"] == 1 and info["steps"] == sim.steps_per_frame
    assert sim.time == pytest.approx(1 / 60, rel=0.05)
    assert obs["sensor_pressures"][0] > 0.9  # now the chamber pressure [bar]


@pytest.mark.parametrize("task", softevo.TASKS)
def test_the_task_reports_its_score_so_far(task):
    """Issue 28: the task itself scores the state so far (fitness_so_far, components by name);
    at the end it is the result, and only a steerable task can be steered."""
    assert softevo.TASKS == ("gait", "directed", "rotate")
    robot = block_robot(closed=True, directed=task == "directed")
    sim = softevo.Simulation(robot, seconds=0.5, task=task)
    controller = softevo.Controller(robot)
    obs = sim.reset()
    names = [name for name in obs["components"]]
    assert len(names) >= 1 and obs["fitness_so_far"] == 0.0
    seen = 0
    while not sim.done:
        obs, info = sim.step(controller.act(obs))
        seen += any(v != 0.0 for v in obs["components"].values())
    assert seen > sim.frames // 2
    result = sim.result()
    assert obs["fitness_so_far"] == result.fitness
    final = result.components[0]
    assert {name: final[name] for name in names} == obs["components"]
    if task == "directed":
        sim.reset()
        sim.steer(90.0)
        obs, _ = sim.step(np.ones((2, 2), dtype=np.float32))
        assert obs["components"]["direction_deg"] == 90.0
        with pytest.raises(ValueError, match="180"):
            sim.steer(200.0)
    else:
        with pytest.raises(ValueError, match="no target direction"):
            sim.steer(90.0)


def test_state_hash_repeats_after_reset():
    sim = softevo.Simulation(block_robot(), seconds=0.25)
    start = sim.state_hash()
    for _ in range(5):
        sim.step([1.0, 0.0, 0.0, 1.0])
    after = sim.state_hash()
    assert after != start
    sim.reset()
    assert sim.state_hash() == start
    for _ in range(5):
        sim.step(np.array([[1.0, 0.0], [0.0, 1.0]]))
    assert sim.state_hash() == after


def test_runs_to_the_end_then_refuses():
    sim = softevo.Simulation(block_robot(), seconds=0.1)
    assert sim.frames == 6 and sim.status == "ok" and not sim.done
    for _ in range(6):
        sim.step(np.full(4, 0.5))
    assert sim.done and sim.frame == 6
    with pytest.raises(ValueError, match="ended"):
        sim.step(np.full(4, 0.5))
    assert sim.result().fitness == sim.result().fitness  # scored once, cached


@pytest.mark.parametrize("valves,words", [
    (np.ones(3), "3 values, expected 4"),
    (np.full(4, 1.5), r"\[0, 1\]"),
    (np.full(4, np.nan), r"\[0, 1\]"),
    ("open", "float"),
])
def test_bad_valves_raise(valves, words):
    sim = softevo.Simulation(block_robot(), seconds=0.1)
    with pytest.raises(ValueError, match=words):
        sim.step(valves)


def test_unactuatable_body_and_bad_unit():
    import json
    j = json.loads(block_robot().to_json())
    j["cells"] = [10 if c > 10 else c for c in j["cells"]]
    with pytest.raises(ValueError, match="chamber"):
        softevo.Simulation(softevo.Robot.from_json(json.dumps(j)))
    with pytest.raises(ValueError, match="unit"):
        softevo.Simulation(block_robot(), unit=3)


def test_controller_act_needs_the_observation_keys():
    controller = softevo.Controller(block_robot())
    with pytest.raises(KeyError, match="sensor_pressures"):
        controller.act({"task_inputs": np.zeros(0, np.float32)})
    valves = controller.act({"task_inputs": np.zeros(0, np.float32),
                             "sensor_pressures": np.zeros(2, np.float32)})
    assert valves.shape == (2, 2) and valves.dtype == np.float32
    assert np.all((valves >= 0) & (valves <= 1))
    assert controller.inputs.shape == (2,)
    with pytest.raises(ValueError, match="chambers need"):
        controller.act({"task_inputs": np.zeros(0, np.float32),
                        "sensor_pressures": np.zeros(11, np.float32)})


def test_every_observed_pressure_in_pa():
    sim = softevo.Simulation(block_robot(closed=True), seconds=0.2)
    obs = sim.reset()
    for _ in range(5):
        obs, _ = sim.step(np.ones((2, 2), dtype=np.float32))
    # sensor_pressures keeps the controller's scale [bar]; sensor_pressures_pa is the same in Pa.
    assert np.array_equal(obs["sensor_pressures_pa"], obs["sensor_pressures"].astype(np.float64) * 1e5)
    assert obs["pressures"].dtype == np.float64 and np.all(obs["pressures"] > 5e4)
    frame = sim.render(64, 48, "iso")
    assert frame.shape == (48, 64, 3)


def test_controller_act_refuses_non_finite_observations():
    # issue 29: a NaN entered the recurrent state and stayed until reset(); now refused, naming
    # the field, with the state unchanged (the next finite observation acts as if it never came).
    fresh, probed = softevo.Controller(block_robot(closed=True)), softevo.Controller(block_robot(closed=True))
    good = {"task_inputs": np.zeros(0, np.float32), "sensor_pressures": np.array([0.1, 0.2], np.float32)}
    for field, bad in [("sensor_pressures", np.array([np.nan, 0.2], np.float32)),
                       ("sensor_pressures", np.array([0.1, np.inf], np.float32))]:
        with pytest.raises(ValueError, match=field):
            probed.act({**good, field: bad})
    assert np.array_equal(probed.act(good), fresh.act(good))
    assert np.all(np.isfinite(probed.act(good)))

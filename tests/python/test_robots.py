"""softevo.load_robot / Robot.save / Robot: the softevo.robot/1 reader and writer from Python,
its strict errors as exceptions naming file and key, the controller parameters, develop()."""

import json
import os

import numpy as np
import pytest

import softevo
from conftest import block_robot, block_robot_json, champion


def test_save_and_load_give_the_same_robot(tmp_path):
    robot = block_robot(closed=True)
    path = tmp_path / "block.robot.json"
    robot.save(path)
    again = softevo.load_robot(path)
    assert again.to_json() == robot.to_json()
    assert again.lattice == (7, 4, 4)
    assert again.cells.shape == (7, 4, 4)
    assert again.chambers == 2
    assert again.voxels == 7 * 4 * 4 - 16
    assert again.closed_loop and not again.directed
    assert again.frequency == 3.0


def test_save_refuses_an_existing_file_unless_asked(tmp_path):
    path = tmp_path / "r.json"
    block_robot().save(path)
    with pytest.raises(softevo.OutputFileError, match="r.json"):
        block_robot().save(path, overwrite=False)
    assert isinstance(softevo.OutputFileError("x"), OSError)


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="robot file not found"):
        softevo.load_robot(tmp_path / "absent.json")


def test_fifos_devices_and_huge_files_are_refused_without_reading(tmp_path):
    # A FIFO used to block forever, /dev/zero and a 10 GB sparse file to grow without bound.
    fifo = tmp_path / "pipe.robot.json"
    os.mkfifo(fifo)
    for path in (fifo, "/dev/zero"):
        with pytest.raises(softevo.RobotFileError, match="not a regular file"):
            softevo.load_robot(path)
    with pytest.raises(softevo.ConfigError, match="not a regular file"):
        softevo.load_config(fifo)
    huge = tmp_path / "huge.robot.json"
    with open(huge, "wb") as f:
        f.write(b"{")
        f.truncate(10_000_000_000)
    with pytest.raises(softevo.RobotFileError, match="larger than the limit of 64 MiB"):
        softevo.load_robot(huge)


def test_unknown_key_names_file_and_key(tmp_path):
    j = block_robot_json()
    j["controller"]["colour"] = "red"
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(j))
    with pytest.raises(softevo.RobotFileError) as e:
        softevo.load_robot(path)
    assert "bad.json" in str(e.value) and "colour" in str(e.value)
    assert isinstance(e.value, ValueError)


def test_wrong_length_and_type_are_errors():
    j = block_robot_json()
    j["controller"]["bias_out"] = [0.0] * 3
    with pytest.raises(softevo.RobotFileError, match="bias_out"):
        softevo.Robot.from_json(json.dumps(j), "short.json")
    j = block_robot_json()
    j["lattice"] = "big"
    with pytest.raises(softevo.RobotFileError, match="lattice"):
        softevo.Robot.from_json(json.dumps(j), "typed.json")
    with pytest.raises(softevo.RobotFileError, match="garbage.json"):
        softevo.Robot.from_json("{not json", "garbage.json")


def test_controller_parameters_round_trip():
    robot = block_robot()
    p = robot.controller_parameters
    assert p.dtype == np.float64 and p.ndim == 1
    assert p[-1] == 3.0  # the oscillator frequency comes last
    changed = robot.with_controller_parameters(p * 0.5)
    assert np.array_equal(changed.controller_parameters, p * 0.5)
    assert np.array_equal(robot.controller_parameters, p)  # the original is unchanged
    with pytest.raises(ValueError, match="values"):
        robot.with_controller_parameters(p[:-1])
    with pytest.raises(ValueError, match="1-D"):
        robot.with_controller_parameters(p.reshape(1, -1))


def test_develop_rebuilds_a_champion_body_from_its_cppn():
    robot = champion("gait-open-01")
    assert robot.has_genome
    developed = softevo.develop(robot)
    assert np.array_equal(developed.cells, robot.cells)
    assert developed.controller_parameters.tolist() == robot.controller_parameters.tolist()


def test_develop_needs_a_genome():
    with pytest.raises(ValueError, match="genome"):
        softevo.develop(block_robot())
    with pytest.raises(TypeError):
        softevo.develop("robot.json")
    with pytest.raises(ValueError, match="config"):
        softevo.develop(b"\x00")


def test_develop_an_archived_genome(tiny_run):
    run = softevo.open_run(tiny_run)
    generation, best = run.best()
    robot = run.genome(best)
    assert robot.has_genome
    again = softevo.develop(robot, run.config)
    assert np.array_equal(again.cells, robot.cells)


def test_every_public_name_and_method_has_a_docstring():
    import inspect
    import softevo.env

    undocumented = []
    for module in (softevo, softevo.env):
        names = getattr(module, "__all__", None) or [n for n in vars(module) if not n.startswith("_")]
        for name in names:
            obj = getattr(module, name)
            if not (inspect.isclass(obj) or callable(obj)) or isinstance(obj, type(softevo)):
                continue
            if not (obj.__doc__ or "").strip():
                undocumented.append(f"{module.__name__}.{name}")
            if inspect.isclass(obj) and not issubclass(obj, BaseException):
                for attr, member in vars(obj).items():
                    if attr.startswith("_") or not (callable(member) or isinstance(member, property)):
                        continue
                    if not (getattr(member, "__doc__", "") or "").strip():
                        undocumented.append(f"{module.__name__}.{name}.{attr}")
    assert undocumented == []


def test_save_refuses_an_existing_file_by_default(tmp_path):
    path = tmp_path / "r.json"
    block_robot().save(path)
    with pytest.raises(softevo.OutputFileError, match="r.json"):
        block_robot(closed=True).save(path)
    assert not softevo.load_robot(path).closed_loop  # left as it was
    block_robot(closed=True).save(path, overwrite=True)
    assert softevo.load_robot(path).closed_loop


def test_a_file_of_another_kind_is_named(tmp_path):
    archive = tmp_path / "run.h5"
    archive.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))
    with pytest.raises(softevo.RobotFileError, match=r"run\.h5: an HDF5 file .*open_run"):
        softevo.load_robot(archive)
    toml = tmp_path / "c.toml"
    toml.write_text("[run]\nseed = 1\n")
    with pytest.raises(softevo.RobotFileError, match=r"c\.toml: not a robot file"):
        softevo.load_robot(toml)


def test_import_error_names_the_interpreter(monkeypatch):
    monkeypatch.setattr("sys.executable", "/home/me/.pyenv/versions/3.12.1/bin/python3")
    e = softevo._import_error(ImportError("No module named 'numpy'"))
    assert "/home/me/.pyenv/versions/3.12.1/bin/python3" in str(e)
    assert softevo._build_info.PYTHON_EXECUTABLE in str(e)
    assert "numpy" in str(e)

"""softevo.load_config / default_config / Config: the strict TOML reader of `softevo config
show` with overrides, the canonical text and the config hash."""

import pathlib
import subprocess

import pytest

import softevo
from conftest import SOURCE_DIR, binary

QUICKSTART = SOURCE_DIR / "configs" / "quickstart.toml"


def test_overrides_as_python_values_and_as_strings():
    c = softevo.load_config(QUICKSTART, overrides={"neat.pop_size": 20, "task.control": "closed",
                                                    "body.lattice": [5, 5, 5], "physics.floor": True})
    assert "pop_size = 20" in c.text
    assert c.control == "closed"
    assert c.experiment == "gait-closed"
    same = softevo.load_config(QUICKSTART, overrides=["neat.pop_size=20", 'task.control="closed"',
                                                      "body.lattice=[5, 5, 5]"])
    assert same.hash == c.hash


def test_hash_and_text_equal_softevo_config_show():
    c = softevo.load_config(QUICKSTART)
    out = subprocess.run([str(binary("softevo")), "config", "show", str(QUICKSTART)],
                         capture_output=True, text=True, check=True).stdout
    assert c.hash in out
    assert len(c.hash) == 16
    assert c.text.strip().splitlines()[0] in out


def test_text_parses_back_to_the_same_config(tmp_path):
    c = softevo.load_config(QUICKSTART)
    path = tmp_path / "canonical.toml"
    path.write_text(c.text)
    assert softevo.load_config(path) == c


def test_default_config_per_task():
    for task in softevo.TASKS:
        c = softevo.default_config(task)
        assert c.task == task
        assert c.eval_seconds == 10.0
    assert softevo.default_config("gait").hash != softevo.default_config("rotate").hash
    with pytest.raises(ValueError, match="swim"):
        softevo.default_config("swim")


def test_unknown_key_names_file_and_key():
    with pytest.raises(softevo.ConfigError) as e:
        softevo.load_config(QUICKSTART, overrides={"neat.pop_sizes": 3})
    assert "pop_sizes" in str(e.value)
    assert isinstance(e.value, ValueError)
    # Python's words, not the command line's (issue 39: it said "--set neat.popsize=4")
    assert str(e.value).startswith('overrides["neat.pop_sizes"] = 3: ')
    assert "--set" not in str(e.value)
    with pytest.raises(softevo.ConfigError, match=r'^overrides\["neat.pop_size"\] = -3: '):
        softevo.parse_config("", overrides={"neat.pop_size": -3})


@pytest.mark.parametrize("bad", sorted((SOURCE_DIR / "tests/data/bad_configs").glob("*.toml")),
                         ids=lambda p: p.name)
def test_every_bad_config_is_a_config_error_naming_the_file(bad: pathlib.Path):
    with pytest.raises(softevo.ConfigError, match=bad.name):
        softevo.load_config(bad)


def test_missing_file_and_bad_override_type(tmp_path):
    with pytest.raises(FileNotFoundError):
        softevo.load_config(tmp_path / "none.toml")
    with pytest.raises(TypeError):
        softevo.load_config(QUICKSTART, overrides={"neat.pop_size": object()})


def test_config_is_a_read_only_mapping_of_resolved_keys():
    import collections.abc
    import tomllib

    c = softevo.load_config(QUICKSTART)
    assert isinstance(c, collections.abc.Mapping)
    assert c["neat.pop_size"] == 12
    assert c["run.generations"] == 10
    assert c["body.lattice"] == [6, 6, 6]
    assert "task.kind" in c and "task.nonsense" not in c
    # Every key of the canonical text, defaults included, as "section.key".
    flat = {f"{s}.{k}" for s, keys in tomllib.loads(c.text).items() for k in keys}
    assert set(c) == flat and len(c) == len(flat)
    assert dict(c.items())["task.control"] == "open"
    assert c.get("neat.nope", 3) == 3
    with pytest.raises(KeyError, match="neat.nope"):
        c["neat.nope"]
    with pytest.raises(TypeError):
        c["neat.pop_size"] = 5


def test_version():
    import tomllib

    project = tomllib.loads((SOURCE_DIR / "pyproject.toml").read_text())["project"]
    assert softevo.__version__ == project["version"]
    out = subprocess.run([str(binary("softevo")), "--version"], capture_output=True, text=True)
    assert softevo.__version__ in out.stdout

"""softevo.open_run: the C++ archive reader from Python: config, info, the flat individuals
table (pandas or numpy), stats, genomes as robots (re-evaluated to their archived bits),
lineages, and bad archives as exceptions."""

import builtins
import os
import struct
import subprocess
import sys

import numpy as np

import pytest

import softevo
import softevo._run
from conftest import binary


def test_config_and_info(tiny_run):
    run = softevo.open_run(tiny_run)
    assert run.info["format"] == "softevo.run/1"
    assert run.info["state"] == "complete"
    assert run.config.hash == run.info["config_hash"]
    assert run.config.task == "gait"
    assert run.generations == [0, 1]
    assert len(run.fitness_digest()) == 16


def test_individuals_as_a_dataframe(tiny_run):
    pandas = pytest.importorskip("pandas")
    table = softevo.open_run(tiny_run).individuals()
    assert isinstance(table, pandas.DataFrame)
    assert len(table) == 12
    for column in ("generation", "id", "parent1", "parent2", "species", "status", "fitness",
                   "voxels", "chambers", "distance"):
        assert column in table.columns
    assert set(table["generation"]) == {0, 1}
    assert set(table["status"]) <= {"ok", "killed: flipped", "killed: exploded", "invalid body"}
    ok = table[table["status"] == "ok"]
    assert np.array_equal(ok["fitness"].to_numpy(), ok["distance"].to_numpy())


def test_individuals_without_pandas_is_a_structured_array(tiny_run, monkeypatch):
    real_import = builtins.__import__

    def no_pandas(name, *args, **kwargs):
        if name == "pandas":
            raise ImportError("no pandas here")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pandas)
    table = softevo.open_run(tiny_run).individuals()
    assert isinstance(table, np.ndarray) and table.dtype.names[:3] == ("generation", "id", "parent1")
    assert len(table) == 12 and table["status"][0] in ("ok", "invalid body", "killed: flipped")
    stats = softevo.open_run(tiny_run).stats()
    assert isinstance(stats, np.ndarray) and len(stats) == 2


def test_stats_match_the_table(tiny_run):
    pytest.importorskip("pandas")
    run = softevo.open_run(tiny_run)
    stats, table = run.stats(), run.individuals()
    for g in (0, 1):
        assert stats["best"][g] == table[table["generation"] == g]["fitness"].max()


def test_genome_re_evaluates_to_the_archived_bits(tiny_run):
    run = softevo.open_run(tiny_run)
    generation, best = run.best()
    robot = run.genome(best)
    table = run.individuals()
    row = table[(table["generation"] == generation) & (table["id"] == best)]
    assert robot.voxels == int(row["voxels"].iloc[0])
    assert softevo.evaluate(robot, config=run.config).fitness == float(row["fitness"].iloc[0])


def test_learning_columns_and_the_learned_robot(learning_run):
    pytest.importorskip("pandas")
    run = softevo.open_run(learning_run)
    table = run.individuals()
    for column in ("reused_from", "fitness_before", "learn_evaluations", "learning_curve"):
        assert column in table.columns
    fresh = table[table["reused_from"] == -1]
    assert (fresh["learn_evaluations"] == 5).all()  # born + 2 iterations of 2
    for _, row in table.iterrows():
        curve = row["learning_curve"]
        assert len(curve) == 3 and curve[0] == row["fitness_before"] and curve[-1] == row["fitness"]
        assert np.all(np.diff(curve) >= 0)
    # The individual is the learned robot: it re-evaluates to the archived (learned) fitness.
    generation, best = run.best()
    row = table[(table["generation"] == generation) & (table["id"] == best)]
    assert softevo.evaluate(run.genome(best), config=run.config).fitness == float(row["fitness"].iloc[0])


def test_a_run_without_learning_has_no_learning_columns(tiny_run):
    pytest.importorskip("pandas")
    table = softevo.open_run(tiny_run).individuals()
    assert "reused_from" in table.columns and "fitness_before" not in table.columns


def test_lineage_follows_the_first_parent(tiny_run):
    run = softevo.open_run(tiny_run)
    table = run.individuals()
    children = table[(table["generation"] == 1) & (table["parent1"] >= 0)]
    child = int(children["id"].iloc[0])
    line = run.lineage(child)
    assert line[0]["id"] == child and line[0]["generation"] == 1
    assert line[1]["id"] == line[0]["parent1"] and line[1]["generation"] == 0
    assert line[-1]["parent1"] == -1


def test_bad_archives_and_ids(tiny_run, tmp_path):
    with pytest.raises(FileNotFoundError):
        softevo.open_run(tmp_path / "none.h5")
    text = tmp_path / "text.h5"
    text.write_text("not hdf5")
    with pytest.raises(softevo.ArchiveError, match="text.h5"):
        softevo.open_run(text)
    assert isinstance(softevo.ArchiveError("x"), OSError)
    # a FIFO is refused, never waited on (issue 39: open_run blocked forever); a directory too
    fifo = tmp_path / "pipe.h5"
    os.mkfifo(fifo)
    with pytest.raises(softevo.ArchiveError, match="is a FIFO"):
        softevo.open_run(fifo)
    with pytest.raises(softevo.ArchiveError, match="is a directory"):
        softevo.open_run(tmp_path)
    run = softevo.open_run(tiny_run)
    with pytest.raises(KeyError, match="999999"):
        run.genome(999999)
    with pytest.raises(KeyError, match="generation 7"):
        run.genome(1, generation=7)
    with pytest.raises(KeyError):
        run.lineage(999999)
    # Arguments that are not whole numbers are named, never truncated (3.7 was read as 3) or
    # passed on to the binding's own "incompatible function arguments".
    for call, message in ((lambda: run.genome(1.7), r"Run\.genome: id must be an int, not float"),
                          (lambda: run.genome("1"), r"Run\.genome: id must be an int, not str"),
                          (lambda: run.genome(1, generation=0.5),
                           r"Run\.genome: generation must be an int or None, not float"),
                          (lambda: run.best("last"), r"Run\.best: generation must be an int"),
                          (lambda: run.lineage(True), r"Run\.lineage: id must be an int, not bool"),
                          (lambda: run.lineage(1, generation=[0]),
                           r"Run\.lineage: generation must be an int or None, not list")):
        with pytest.raises(TypeError, match=message):
            call()
    with pytest.raises(ValueError, match=r"Run\.genome: id = 10+ is beyond 64 bits"):
        run.genome(10**30)
    ids = run.individuals()["id"]
    assert run.genome(np.int64(ids[0])).voxel_size > 0  # numpy integers are integers


def test_run_as_a_context_manager(tiny_run):
    with softevo.open_run(tiny_run) as run:
        assert run.info["state"] == "complete"
    assert run.closed
    with pytest.raises(ValueError, match="closed"):
        run.stats()


def _tampered_copy(tiny_run, tmp_path):
    """A copy of the archive with one robot's fitness changed to 123.456 in place (every copy of
    the float64's bytes: the fitness column and its component): what an edit with h5py does."""
    with softevo.open_run(tiny_run) as run:
        fitness = run.individuals()["fitness"]
    data = bytearray(tiny_run.read_bytes())
    best = float(max(fitness))
    for value in fitness:
        needle = struct.pack("<d", float(value))
        if value != 0 and value != best and data.count(needle) >= 1:
            data = bytearray(bytes(data).replace(needle, struct.pack("<d", 123.456)))
            break
    else:
        pytest.skip("no fitness value found in the archive's bytes")
    bad = tmp_path / "tampered.h5"
    bad.write_bytes(bytes(data))
    return bad


@pytest.mark.parametrize("line", ["seed = " + "7" * 50000, "x = " + "{a=" * 10000 + "1" + "}" * 10000],
                         ids=["50000-digit number", "inline table 10000 deep"])
def test_an_archive_whose_config_holds_a_hostile_line_is_an_error(tiny_run, tmp_path, line):
    """Issue 39: such a /config overflowed the config reader's stack in `softevo info` and
    killed Python's open_run. Both now report the line limit; run in child processes, whose
    exit (not a signal) is what is checked."""
    h5py = pytest.importorskip("h5py")
    bad = tmp_path / "hostile.h5"
    bad.write_bytes(tiny_run.read_bytes())
    with h5py.File(bad, "r+") as f:
        text = f["config"][()].decode() if isinstance(f["config"][()], bytes) else f["config"][()]
        text = text.replace("[run]\n", "[run]\n" + line + "\n", 1)
        del f["config"]
        f.create_dataset("config", data=text.encode())
        # the hash of the new text (FNV-1a 64), so that the reader goes on to parse it
        h = 0xcbf29ce484222325
        for byte in text.encode():
            h = ((h ^ byte) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
        f.attrs["config_hash"] = f"{h:016x}".encode()
    info = subprocess.run([str(binary("softevo")), "info", str(bad)], capture_output=True,
                          text=True)
    assert info.returncode in (1, 2, 3), (info.returncode, info.stderr[-2000:])
    assert ("at most 10000 bytes" in info.stdout + info.stderr
            or "nested more than 8 deep" in info.stdout + info.stderr), info.stdout + info.stderr
    code = ("import softevo, sys\n"
            "try:\n"
            f"    softevo.open_run({str(bad)!r}, verify=False).config\n"
            "except (softevo.ArchiveError, softevo.ConfigError) as e:\n"
            "    print('raised:', str(e)[:300])\n"
            "    sys.exit(0)\n"
            "sys.exit(3)\n")
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert child.returncode == 0, child.stdout + child.stderr[-2000:]
    assert "raised:" in child.stdout


def test_a_tampered_archive_raises_by_default(tiny_run, tmp_path):
    # `softevo info` reported integrity FAILED for such a file, while Python served it silently.
    bad = _tampered_copy(tiny_run, tmp_path)
    with pytest.raises(softevo.ArchiveError, match="integrity FAILED") as e:
        softevo.open_run(bad)
    assert "tampered.h5" in str(e.value) and "digest" in str(e.value)
    with pytest.warns(softevo.ArchiveIntegrityWarning, match="integrity FAILED"):
        run = softevo.open_run(bad, verify="warn")
    assert 123.456 in set(run.individuals()["fitness"].tolist())
    run = softevo.open_run(bad, verify=False)
    report = run.verify(raise_error=False)
    assert not report["ok"] and report["problems"][0]["check"] == "digest"
    with pytest.raises(softevo.ArchiveError, match="integrity FAILED"):
        run.verify()
    with pytest.raises(ValueError, match="verify must be"):
        softevo.open_run(tiny_run, verify="sometimes")


def test_an_intact_archive_verifies(tiny_run):
    with softevo.open_run(tiny_run) as run:
        report = run.verify()
        assert report["ok"] and report["problems"] == []
        assert report["generations_checked"] == 2 and report["generations_with_digest"] == 2
        assert run.info["stop_reason"] == ""

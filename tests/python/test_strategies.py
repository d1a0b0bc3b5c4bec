"""Search strategies from Python (docs/model.md §8.12): softevo.evolve(strategy=...) writes the
archive of `softevo evolve` for MAP-Elites and AFPO, Run.map() is the elite map, and
Run.strategy_stats() the per-generation metrics."""

import json
import subprocess

import numpy as np
import pytest

import softevo
from conftest import SOURCE_DIR, binary

TINY = SOURCE_DIR / "tests" / "data" / "tiny-run.toml"
MAP = {"map_elites.descriptors": ["voxels", "height"], "map_elites.min": [0, 0],
       "map_elites.max": [125, 0.05], "map_elites.bins": [5, 5]}


def fitness_digest(path):
    out = subprocess.run([str(binary("softevo")), "info", str(path), "--json"], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)["fitness_digest"], json.loads(out)["strategy"]


@pytest.mark.parametrize("strategy", ["map_elites", "afpo"])
def test_evolve_takes_a_strategy_and_writes_the_archive_of_the_command_line(strategy, tmp_path):
    overrides = MAP if strategy == "map_elites" else {"afpo.age": "body"}
    seen = []
    run = softevo.evolve(TINY, workers=2, out=tmp_path / "py.h5", strategy=strategy,
                         overrides=overrides, callback=seen.append)
    assert run.strategy == strategy
    sets = [f"--set={k}={json.dumps(v)}" for k, v in overrides.items()]
    subprocess.run([str(binary("softevo")), "evolve", "--config", str(TINY), "--workers", "1",
                    "--out", str(tmp_path / "cli.h5"), "-q", f"--set=search.strategy={strategy}",
                    *sets], check=True)
    assert fitness_digest(tmp_path / "py.h5") == fitness_digest(tmp_path / "cli.h5")
    assert fitness_digest(tmp_path / "cli.h5")[1] == strategy
    stats = run.strategy_stats()
    assert list(stats["generation"]) == [0, 1, 2]
    assert [g.strategy_metrics["max_fitness"] for g in seen] == list(stats["max_fitness"])


def test_map_is_the_elite_table_of_the_last_generation(tmp_path):
    run = softevo.evolve(TINY, workers=2, out=tmp_path / "m.h5", strategy="map_elites",
                         overrides=MAP)
    m = run.map()
    stats = run.strategy_stats()
    last = {k: np.asarray(stats[k])[-1] for k in ("num_elites", "coverage", "qd_score")}
    assert len(m) == int(last["num_elites"])
    assert float(last["coverage"]) == len(m) / 25
    assert float(last["qd_score"]) == pytest.approx(float(np.sum(m["fitness"])), abs=1e-12)
    cells = np.asarray(m["cell"])
    assert list(cells) == sorted(set(cells))
    assert list(cells) == list(np.asarray(m["bin_voxels"]) * 5 + np.asarray(m["bin_height"]))
    # Each elite is an archived individual with its fitness (export --id works for it).
    ind = run.individuals()
    for row in range(len(m)):
        i, f = int(m["id"][row]), float(m["fitness"][row])
        assert f in set(ind["fitness"][ind["id"] == i])
    first = run.map(0)
    assert len(first) == int(np.asarray(stats["num_elites"])[0])


def test_bad_strategies_are_refused(tmp_path):
    with pytest.raises(ValueError, match="strategy must be one of"):
        softevo.evolve(TINY, out=tmp_path / "x.h5", strategy="cma")
    run = softevo.evolve(TINY, workers=1, out=tmp_path / "n.h5", generations=1)
    assert run.strategy == "neat"
    with pytest.raises(ValueError, match="has no map"):
        run.map()
    assert len(run.strategy_stats()) == 0


def test_export_and_view_pick_an_elite_by_cell(tmp_path):
    run = softevo.evolve(TINY, workers=2, out=tmp_path / "m.h5", strategy="map_elites",
                         overrides=MAP)
    m = run.map()
    i, j = int(np.asarray(m["bin_voxels"])[0]), int(np.asarray(m["bin_height"])[0])
    out = subprocess.run([str(binary("softevo")), "export", str(tmp_path / "m.h5"), "--cell",
                          f"{i},{j}", "-o", str(tmp_path / "e.json"), "--json"],
                         check=True, capture_output=True, text=True).stdout
    exported = json.loads(out)
    assert exported["id"] == int(np.asarray(m["id"])[0])
    assert exported["generation"] == int(np.asarray(m["generation"])[0])
    assert exported["fitness"] == float(np.asarray(m["fitness"])[0])
    # The exported elite re-evaluates to its archived fitness.
    assert softevo.evaluate(softevo.load_robot(tmp_path / "e.json")).fitness == exported["fitness"]
    empty = next(c for c in range(25) if c not in set(np.asarray(m["cell"])))
    for cell, needle in ((f"{empty // 5},{empty % 5}", "the cell is empty"),
                         ("5,0", "give one bin per descriptor"), ("1", "give one bin")):
        for command, output in (("export", ["-o", str(tmp_path / "x.json")]),
                                ("view", ["--port", "0"]),
                                ("render", ["-o", str(tmp_path / "x.png")]),
                                ("fabricate", ["-o", str(tmp_path / "x.stl")])):
            args = [str(binary("softevo")), command, str(tmp_path / "m.h5"), "--cell", cell]
            args += output
            p = subprocess.run(args, capture_output=True, text=True, timeout=60)
            assert p.returncode == 2 and needle in p.stderr and "--cell" in p.stderr, p.stderr
    # render and fabricate take the elite of a cell as export does (its generation and id).
    done = subprocess.run([str(binary("softevo")), "render", str(tmp_path / "m.h5"), "--cell",
                           f"{i},{j}", "-o", str(tmp_path / "e.png")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and (tmp_path / "e.png").stat().st_size > 1000, done.stderr
    done = subprocess.run([str(binary("softevo")), "fabricate", str(tmp_path / "m.h5"), "--cell",
                           f"{i},{j}", "-o", str(tmp_path / "e.stl"), "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["robot"].endswith(
        f" gen {exported['generation']} id {exported['id']}"), done.stdout
    # The empty cell's message lists the cells that hold an elite, as bins.
    first = f"{int(np.asarray(m['bin_voxels'])[0])},{int(np.asarray(m['bin_height'])[0])}"
    p = subprocess.run([str(binary("softevo")), "export", str(tmp_path / "m.h5"), "--cell",
                        f"{empty // 5},{empty % 5}", "-o", str(tmp_path / "x.json")],
                       capture_output=True, text=True, timeout=60)
    assert f"; cells with an elite: {first}" in p.stderr, p.stderr
    assert "(voxels 0..4, height 0..4)" in subprocess.run(
        [str(binary("softevo")), "export", str(tmp_path / "m.h5"), "--cell", "9,9", "-o",
         str(tmp_path / "x.json")], capture_output=True, text=True, timeout=60).stderr


def test_analysis_places_every_run_in_the_map_of_a_map_elites_run(tmp_path):
    """analysis/strategies.py: the grid filled afterwards from a MAP-Elites run's ok robots is
    its archived map (same coverage and QD score); a NEAT run gets the same figures."""
    import sys
    me = softevo.evolve(TINY, workers=2, out=tmp_path / "me.h5", strategy="map_elites",
                        overrides=MAP)
    softevo.evolve(TINY, workers=2, out=tmp_path / "neat.h5")
    done = subprocess.run([sys.executable, str(SOURCE_DIR / "analysis" / "strategies.py"),
                           str(tmp_path / "me.h5"), str(tmp_path / "neat.h5"), "-o",
                           str(tmp_path / "fig"), "--qd-offset", "0"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "warning" not in done.stderr
    import csv
    rows = {r["strategy"]: r for r in csv.DictReader(open(tmp_path / "fig" / "strategies.csv"))}
    stats = me.strategy_stats()
    assert float(rows["map_elites"]["coverage"]) == float(np.asarray(stats["coverage"])[-1])
    assert float(rows["map_elites"]["qd_score"]) == pytest.approx(
        float(np.asarray(stats["qd_score"])[-1]), abs=1e-9)
    assert set(rows) == {"map_elites", "neat"}
    for name in ("qd_curves.png", "heatmap_me.png", "heatmap_neat.png"):
        assert (tmp_path / "fig" / name).stat().st_size > 1000


def test_individuals_carry_the_strategys_columns_instead_of_species(tmp_path):
    for strategy, overrides, names in (("map_elites", MAP, ["cell", "placed", "voxels", "height"]),
                                       ("afpo", {}, ["age", "pareto_rank", "survived"])):
        run = softevo.evolve(TINY, workers=2, out=tmp_path / f"{strategy}.h5", strategy=strategy,
                             overrides=overrides)
        ind = run.individuals()
        assert "species" not in ind.columns
        cols = list(ind.columns)
        assert cols[4:4 + len(names)] == names, cols
        assert run.lineage(int(ind["id"].iloc[-1]))[0]["id"] == int(ind["id"].iloc[-1])
    m = softevo.open_run(tmp_path / "map_elites.h5")
    ind = m.individuals()
    last = ind[ind["generation"] == ind["generation"].max()]
    placed = ind[ind["placed"] == 1]
    assert set(m.map()["id"]) <= set(placed["id"])
    assert (last["cell"] >= -1).all()


def test_analysis_refuses_bad_arguments_by_name_and_writes_nothing(tmp_path):
    """analysis/strategies.py: a named file that is not a run archive, a missing path, a
    non-finite number, a bad --grid and an -o that is a file are exit 2 naming them, with no
    traceback and no output written; a folder's non-archive .h5 files are skipped, saying so."""
    import sys
    softevo.evolve(TINY, workers=2, out=tmp_path / "runs" / "neat.h5")
    (tmp_path / "runs" / "notes.h5").write_text("not an archive")
    (tmp_path / "file").write_text("")
    script = str(SOURCE_DIR / "analysis" / "strategies.py")
    run = str(tmp_path / "runs" / "neat.h5")
    for args, message in (([str(tmp_path / "runs" / "notes.h5")], "notes.h5: /: open file: not an HDF5"),
                          ([run, str(tmp_path / "none.h5")], "none.h5: no such file or folder"),
                          ([run, "--qd-offset", "nan"], "--qd-offset nan: give a finite number"),
                          ([run, "--walk-cm", "inf"], "--walk-cm inf: give a finite number"),
                          ([run, "--grid", "voxels,size"], "('size' is not one)"),
                          ([run, "--grid", "voxels"], "--grid voxels: give two descriptors")):
        done = subprocess.run([sys.executable, script, *args, "-o", str(tmp_path / "out")],
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 2 and message in done.stderr, (args, done.stderr)
        assert "Traceback" not in done.stderr, done.stderr
        assert not (tmp_path / "out").exists()
    done = subprocess.run([sys.executable, script, run, "-o", str(tmp_path / "file")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "exists and is not a folder" in done.stderr, done.stderr
    done = subprocess.run([sys.executable, script, str(tmp_path / "runs"), "-o",
                           str(tmp_path / "out")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "strategies: skipped" in done.stderr and "notes.h5" in done.stderr, done.stderr
    assert (tmp_path / "out" / "strategies.csv").read_text().count("\n") == 2  # header, neat

"""Tests of tools/dev/schedule_model.py, the discrete-event model of softevo-mpi's schedule
(docs/scaling.md): schedules small enough to work out by hand, and the reading of an archive's
unit times (a synthetic softevo.run/1 archive written with h5py, docs/archive.md).

Run: python3 -m pytest tests/tools/test_schedule_model.py   (ctest does this)
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from tool_loader import load_tool

model = load_tool("schedule_model")


def generation(seconds, costs=None):
    costs = costs if costs is not None else seconds
    return model.Generation([model.Unit(s, c) for s, c in zip(seconds, costs)], 0.0)


def run(gens, ranks, longest_first, message=0.0, barrier=0.0, latency=0.0):
    return model.simulate(gens, ranks, message, barrier, longest_first, latency)


def test_one_rank_evaluates_everything_itself():
    # The master alone: the sum of the units plus one barrier per generation.
    r = run([[generation([1.0, 2.0]), generation([3.0])]], 1, True, barrier=0.5)
    assert r.wall == pytest.approx(1.0 + 2.0 + 0.5 + 3.0 + 0.5)
    assert r.generation_walls == pytest.approx([3.5, 3.5])
    assert r.work == pytest.approx(6.0)


def test_equal_units_fill_the_workers_in_rounds():
    # 6 units of 1 s on 3 workers (4 ranks): two rounds, 2 s, whatever the order.
    for longest_first in (False, True):
        r = run([[generation([1.0] * 6)]], 4, longest_first)
        assert r.wall == pytest.approx(2.0)
        assert r.efficiency(4) == pytest.approx(6.0 / (4 * 2.0))


def test_longest_first_shortens_a_generation_whose_long_unit_comes_last():
    # Member order [1, 1, 1, 3] on 2 workers: 1 | 1, then 1 | 3 from t = 1: ends at 4 s.
    # Longest first: 3 | 1, 1, 1: ends at 3 s (the best possible, the long unit alone).
    units = generation([1.0, 1.0, 1.0, 3.0])
    assert run([[units]], 3, False).wall == pytest.approx(4.0)
    assert run([[units]], 3, True).wall == pytest.approx(3.0)


def test_equal_costs_keep_member_order():
    # Costs tie: the stable sort keeps member order, so both orders give the same schedule.
    units = generation([1.0, 1.0, 1.0, 3.0], costs=[5, 5, 5, 5])
    assert run([[units]], 3, True).wall == pytest.approx(run([[units]], 3, False).wall)


def test_messages_latency_and_barrier_are_paid_where_the_model_says():
    # One worker, two units of 1 s: each unit costs its hand-out and its result on the master
    # (2 messages) and the latency on the worker; the barrier follows the last result.
    r = run([[generation([1.0, 1.0])]], 2, True, message=0.1, barrier=0.5, latency=0.01)
    # hand-out 0.1 -> done 1.11 -> result 1.21 -> hand-out 1.31 -> done 2.32 -> result 2.42
    assert r.wall == pytest.approx(2.42 + 0.5)
    assert r.generation_walls == pytest.approx([2.92])


def test_a_second_run_keeps_the_pool_busy_across_the_generation_tail():
    # Two workers; each generation is a 3 s and a 1 s unit. Alone, a generation ends at 3 s with
    # one worker idle for 2 s: two generations take 6 s. With a second run, the idle worker takes
    # that run's units: two runs of two generations (16 s of units) take 8 s, the bound of 16 s
    # on 2 workers, instead of 2 x 6 s.
    one = [generation([3.0, 1.0]), generation([3.0, 1.0])]
    assert run([one], 3, True).wall == pytest.approx(6.0)
    assert run([one, one], 3, True).wall == pytest.approx(8.0)


def test_directed_runs_five_units_per_gait_unit():
    d = model.directed_from_gait([generation([2.0, 3.0], costs=[10, 20])])
    assert [u.seconds for u in d[0].units] == [2.0] * 5 + [3.0] * 5
    assert [u.cost for u in d[0].units] == [10] * 5 + [20] * 5


def write_archive(path, generations):
    """A minimal archive: per generation the columns the model reads (docs/archive.md)."""
    with h5py.File(path, "w") as f:
        gs = f.create_group("generations")
        for index, (ids, wall, voxels, reused, units, eval_wall) in enumerate(generations):
            g = gs.create_group(f"{index:05d}")
            g["id"] = np.asarray(ids, dtype=np.int64)
            g["wall_seconds"] = np.asarray(wall, dtype=float)
            g["voxels"] = np.asarray(voxels, dtype=np.int64)
            g["reused_from"] = np.asarray(reused, dtype=np.int64)
            g["components"] = np.zeros((len(ids), units, 1))
            g.attrs["eval_wall_seconds"] = eval_wall


def test_reads_unit_times_and_reused_rows(tmp_path):
    path = tmp_path / "run.h5"
    # Generation 1's id 7 reuses id 2 of generation 0 (an elite): wall 0 in the archive.
    write_archive(path, [
        ([1, 2], [4.0, 6.0], [100, 200], [-1, -1], 2, 5.5),
        ([7, 8], [0.0, 8.0], [200, 300], [2, -1], 2, 4.2),
    ])
    gens = model.read_generations(str(path))
    # A genome's wall time is summed over its units: each unit gets its share.
    assert [(u.seconds, u.cost) for u in gens[0].units] == [(2.0, 100), (2.0, 100), (3.0, 200), (3.0, 200)]
    assert [(u.seconds, u.cost) for u in gens[1].units] == [(4.0, 300), (4.0, 300)]
    assert gens[1].measured_wall == pytest.approx(4.2)
    # Without reuse the reused row costs what its origin cost.
    old = model.read_generations(str(path), include_reused=True)
    assert [u.seconds for u in old[1].units] == [3.0, 3.0, 4.0, 4.0]

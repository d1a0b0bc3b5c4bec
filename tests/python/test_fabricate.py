"""Robot.fabricate and `softevo fabricate` (docs/fabrication.md), checked with readers that share
no code with the writer: numpy-stl (Debian python3-stl) and admesh for the STLs, `fabricate
--check` (lib3mf's reader) for the 3MF. Every mesh is closed with outward normals and the volume
of its voxels minus the inlet channels; the mold's pieces fill the box; bad input is refused
naming the option, with no file left behind."""

import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

import softevo
from conftest import BINARY_DIR, SOURCE_DIR

mesh = pytest.importorskip("stl.mesh", reason="numpy-stl (Debian python3-stl) is not installed")

ROBOT = SOURCE_DIR / "robots" / "gait-open-walker.robot.json"
SOFTEVO = BINARY_DIR / "bin" / "softevo"


def stl_volume_closed(path):
    """Volume [mm^3] of a binary STL by numpy-stl, after checking it is closed and its stored
    normals agree with the winding (outward for a positive volume)."""
    m = mesh.Mesh.from_file(str(path))
    assert m.is_closed(), path
    computed = np.cross(m.v1 - m.v0, m.v2 - m.v0)
    computed /= np.linalg.norm(computed, axis=1)[:, None]
    stored = m.normals / np.linalg.norm(m.normals, axis=1)[:, None]
    assert np.all(np.einsum("ij,ij->i", computed, stored) > 0.999)
    volume, _, _ = m.get_mass_properties()
    assert volume > 0, path
    return volume


def admesh_clean(path):
    """admesh's own checks: nothing disconnected, reversed, degenerate or fixed."""
    if shutil.which("admesh") is None:
        return
    out = subprocess.run(["admesh", str(path)], capture_output=True, text=True, check=True).stdout
    for field in ("Total disconnected facets", "Degenerate facets", "Edges fixed",
                  "Facets reversed", "Backwards edges", "Normals fixed"):
        value = re.search(field + r"\s*:\s*(\d+)", out)
        assert value and int(value.group(1)) == 0, f"{path}: admesh {field}\n{out}"


def test_stl_per_group_closed_outward_with_the_voxel_volume_minus_channels(tmp_path):
    robot = softevo.load_robot(ROBOT)
    result = robot.fabricate(tmp_path / "walker.stl")
    assert result["voxels"] == robot.voxels and result["chambers"] == robot.chambers
    s = robot.voxel_size * 1e3
    total = 0.0
    for f in result["files"]:
        total += stl_volume_closed(f)
        admesh_clean(f)
    assert total == pytest.approx(robot.voxels * s**3 - result["channel_volume_mm3"], rel=1e-6)
    # Each group's file holds its voxels (minus the channel part through them).
    for group, f in zip(result["groups"], result["files"]):
        assert f.endswith(f"walker-{group['name']}.stl")
        assert group["voxels"] * s**3 - stl_volume_closed(f) < robot.chambers * s * 1.5**2 + 1e-6


def test_mold_pieces_are_closed_and_fill_the_box_minus_pour_hole_and_vents(tmp_path):
    robot = softevo.load_robot(ROBOT)
    result = robot.fabricate(tmp_path / "w.stl", mold=tmp_path / "mold", wall=4)
    info = json.loads((tmp_path / "mold" / "mold.json").read_text())
    pieces = sum(stl_volume_closed(tmp_path / "mold" / f["file"]) for f in info["files"])
    body = sum(stl_volume_closed(f) for f in result["files"] if "/mold/" not in f)
    box = np.prod(np.subtract(info["box"]["max_mm"], info["box"]["min_mm"]))
    holes = sum(np.prod(np.subtract(b["max_mm"], b["min_mm"]))
                for b in [info["pour_hole"], *info["vents"]])
    assert pieces + body + holes == pytest.approx(box, rel=1e-6)
    assert info["box"]["min_mm"][0] == pytest.approx(-4.0)
    assert {f["file"] for f in info["files"]} >= {"mold-lower.stl", "mold-upper.stl", "core-0.stl"}


def test_options_in_the_cli_units_and_bad_input_names_the_argument(tmp_path):
    # The messages name Robot.fabricate's keyword arguments, never the CLI's options.
    robot = softevo.load_robot(ROBOT)
    with pytest.raises(softevo.FabricateError,
                       match=r"^Robot\.fabricate: channel_diameter 10 mm is not narrower .*"
                             r"lower channel_diameter or raise scale$"):
        robot.fabricate(tmp_path / "a.stl", channel_diameter=robot.voxel_size * 1e3)
    with pytest.raises(softevo.FabricateError, match=r"^Robot\.fabricate: split z=-5 mm"):
        robot.fabricate(tmp_path / "a.stl", mold=tmp_path / "m", split=-5)
    with pytest.raises(softevo.FabricateError,
                       match=r"slices at dpi 6000,6000 and layer_um 1 would be .*"
                             r"lower dpi or raise layer_um$"):
        robot.fabricate(slices=tmp_path / "s", dpi=(6000, 6000), layer_um=1)
    with pytest.raises(softevo.FabricateError, match=r"path .*a\.obj: .*\(by the extension or "
                                                     r"format\)"):
        robot.fabricate(tmp_path / "a.obj")
    with pytest.raises(softevo.FabricateError, match=r"^Robot\.fabricate: scale must be"):
        robot.fabricate(tmp_path / "a.stl", scale=float("nan"))
    assert list(tmp_path.iterdir()) == []  # nothing written, not even the directories
    robot.fabricate(tmp_path / "a.stl", scale=2)
    with pytest.raises(softevo.OutputFileError) as existing:
        robot.fabricate(tmp_path / "a.stl")
    assert "pass force=True to replace it" in str(existing.value)
    assert "--" not in str(existing.value)
    robot.fabricate(tmp_path / "a.stl", force=True)
    # The extension in capitals is the same format, and the group's name replaces it.
    upper = robot.fabricate(tmp_path / "B.STL")
    assert [os.path.basename(f) for f in upper["files"]] == [
        f"B-{g['name']}.stl" for g in upper["groups"]]


@pytest.mark.skipif(not SOFTEVO.exists(), reason="the softevo CLI is not built")
def test_cli_writes_3mf_that_check_reads_back_and_leaves_nothing_on_error(tmp_path):
    out = tmp_path / "w.3mf"
    run = subprocess.run([SOFTEVO, "fabricate", ROBOT, "-o", out, "--json"], capture_output=True,
                         text=True)
    if "without lib3mf" in run.stderr:
        pytest.skip("built without lib3mf")
    assert run.returncode == 0, run.stderr
    written = json.loads(run.stdout)
    check = subprocess.run([SOFTEVO, "fabricate", "--check", out, "--json"], capture_output=True,
                           text=True)
    assert check.returncode == 0, check.stdout + check.stderr
    report = json.loads(check.stdout)
    assert [o["name"] for o in report["objects"]] == [g["name"] for g in written["groups"]]
    assert all(o["manifold_and_oriented"] for o in report["objects"])
    for o, g in zip(report["objects"], written["groups"]):
        assert o["volume_mm3"] == pytest.approx(g["volume_mm3"], rel=1e-6)
    assert report["metadata"]["Title"] == softevo.load_robot(ROBOT).name
    assert "inlet 0: chamber 0" in report["metadata"]["Description"]
    # A split plane above the body: refused, and neither the 3MF nor the mold appears.
    bad = subprocess.run([SOFTEVO, "fabricate", ROBOT, "-o", tmp_path / "x.3mf", "--mold",
                          tmp_path / "mold", "--split", "z=999"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--split" in bad.stderr
    assert not (tmp_path / "x.3mf").exists() and not (tmp_path / "mold").exists()
    assert sorted(os.listdir(tmp_path)) == ["w.3mf"]


@pytest.mark.skipif(not SOFTEVO.exists(), reason="the softevo CLI is not built")
def test_cli_takes_an_archived_individual_and_records_where_it_came_from(tiny_run, tmp_path):
    best = subprocess.run([SOFTEVO, "fabricate", tiny_run, "--best", "-o", tmp_path / "b.stl",
                           "--json"], capture_output=True, text=True)
    assert best.returncode == 0, best.stderr
    written = json.loads(best.stdout)
    for f in written["files"]:
        stl_volume_closed(f)
    out = tmp_path / "b.3mf"
    run = subprocess.run([SOFTEVO, "fabricate", tiny_run, "--best", "-o", out],
                         capture_output=True, text=True)
    if "without lib3mf" in run.stderr:
        pytest.skip("built without lib3mf")
    assert run.returncode == 0, run.stderr
    check = subprocess.run([SOFTEVO, "fabricate", "--check", out, "--json"], capture_output=True,
                           text=True)
    description = json.loads(check.stdout)["metadata"]["Description"]
    table = softevo.open_run(tiny_run).individuals()
    fitness = np.asarray(table["fitness"])
    best_id = int(np.asarray(table["id"])[np.argmax(fitness)])
    assert f"genome_id: {best_id}" in description
    assert f"run: {tiny_run}" in description
    assert re.search(r"config_hash: [0-9a-f]{16}", description)
    # --id of a robot file is a usage error naming the options.
    bad = subprocess.run([SOFTEVO, "fabricate", ROBOT, "--id", "3", "-o", tmp_path / "x.stl"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "--id" in bad.stderr

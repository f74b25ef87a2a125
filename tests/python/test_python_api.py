"""The `efsi` Python package (python/, installed into the suite's venv by `cargo xtask test`):
scenes and their overrides, simulations, fields, probes, snapshots, VTK output, the exceptions,
the same numbers as `efsi run` of the same scene, and Ctrl-C.

Law libraries are found on efsi's law search path; the tests point it at the binary's folder
(`$EFSI_BIN`, else target/debug/efsi), where the suite's build puts them.
"""

import csv
import json
import math
import os
import pickle
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import efsi

from efsi_test_support import BIN_DIR, EFSI, REPO, SPHERE, law_library, nan_law_scene  # noqa: F401

CAVITY = """Scene(
    name: "py_api_cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 2.0)),
    grid: (nx: 12, ny: 24),
    time: (end: 1.0),
    fluid: (density: 2.0, viscosity: 0.05),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (vtk_every: 0.25, probe_every: 0.05, probes: [KineticEnergy, Point(name: "u_c", field: "u", at: (0.5, 1.0))]),
)
"""

# A 32² cavity long enough (≈ 2500 steps) to be interrupted.
# Long enough that a run to its end outlasts any wait of the tests (a release build steps it at
# ≈ 35 time units per second: to t = 40 it once finished before the Ctrl-C test's signal).
LONG = """Scene(
    name: "py_long_cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 32, ny: 32),
    time: (end: 4000.0, cfl: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (probe_every: 0.1, probes: [Point(name: "u_c", field: "u", at: (0.5, 0.5)), KineticEnergy]),
)
"""


def test_scene_overrides_are_the_cli_paths():
    scene = efsi.Scene.load(SPHERE)
    assert scene.name == "sphere_impact"
    assert scene.get("solid.law.parameters.G") == 0.18e6
    # A stage's setting the file leaves out reads as the stage's default.
    assert scene.get("numerics.viscous.max_iterations") == 10000
    assert scene.get("numerics.elastic.coupling") == "Auto"
    scene.set("solid.law.parameters.G", 1e6)
    scene.set("numerics.projection.solver", "IncompleteCholesky")  # absent from the file: added
    scene.set("solid.shape.center", "(0.0, 0.05)")  # RON text, as on the command line
    scene.refine(0.5)
    assert scene.get("solid.law.parameters.G") == 1e6
    assert scene.get("numerics.projection.solver") == "IncompleteCholesky"
    assert scene.get("solid.shape.center[1]") == 0.05
    assert (scene.get("grid.nx"), scene.get("grid.nz")) == (41, 82)  # 82 × 164 halved; alias nz
    assert scene.overrides == [
        "set solid.law.parameters.G=1000000.0",
        "set numerics.projection.solver=IncompleteCholesky",
        "set solid.shape.center=(0.0, 0.05)",
        "refine 0.5",
    ]
    # A copy is independent; a pickled scene comes back equal (Dask sends scenes so).
    other = scene.copy()
    other.set("grid.nx", 10)
    assert scene.get("grid.nx") == 41
    back = pickle.loads(pickle.dumps(scene))
    assert back.to_ron() == scene.to_ron() and back.overrides == scene.overrides


def test_scene_errors_name_the_setting_and_leave_the_scene_unchanged(tmp_path):
    bad = tmp_path / "bad.ron"
    bad.write_text("Scene(\n    name: \"x\",\n    grid: (nx: 4, ny: 4, nq: 3),\n)\n")
    with pytest.raises(efsi.SceneError) as e:
        efsi.Scene.load(bad)
    assert f"{bad}:3:" in str(e.value), str(e.value)
    with pytest.raises(efsi.SceneError):
        efsi.Scene.load(tmp_path / "missing.ron")
    scene = efsi.Scene.from_str(CAVITY)
    before = scene.to_ron()
    with pytest.raises(efsi.SceneError) as e:
        scene.set("grid.nx", 0)
    assert "set grid.nx=0: grid.nx: must be at least 1 cell, got 0" in str(e.value), str(e.value)
    with pytest.raises(efsi.SceneError) as e:
        scene.set("grid.nq", 3)
    assert "grid.nq" in str(e.value)
    with pytest.raises(efsi.SceneError) as e:
        scene.set("grid.nx", 1.5)
    assert "grid.nx" in str(e.value)
    with pytest.raises(efsi.SceneError):
        scene.refine(-1.0)
    with pytest.raises(TypeError):
        scene.set("grid.nx", [1, 2])
    assert scene.to_ron() == before and scene.overrides == []
    # SceneError is also a ValueError, and an EfsiError.
    assert issubclass(efsi.SceneError, ValueError) and issubclass(efsi.SceneError, efsi.EfsiError)


def test_simulation_time_steps_fields_and_probes():
    sim = efsi.Simulation(efsi.Scene.from_str(CAVITY))
    assert (sim.time, sim.steps, sim.end) == (0.0, 0, 1.0)
    assert sim.advance_to(0.25) is True
    assert sim.time == 0.25 and sim.steps > 0
    steps = sim.steps
    u, x, y = sim.field("u")
    assert u.shape == (24, 13) and x.shape == (13,) and y.shape == (24,)
    np.testing.assert_allclose(x, np.linspace(0.0, 1.0, 13), rtol=0, atol=1e-15)
    np.testing.assert_allclose(y, (np.arange(24) + 0.5) / 12, rtol=0, atol=1e-15)
    assert np.all(u[:, 0] == 0.0) and np.all(u[:, -1] == 0.0)  # walls
    assert u[-1, 6] > 0.1  # dragged by the lid
    v, xv, yv = sim.field("v")
    assert v.shape == (25, 12) and yv[0] == 0.0 and yv[-1] == 2.0
    rho, _, _ = sim.field("density")
    assert rho.shape == (24, 12) and np.all(rho == 2.0)
    with pytest.raises(ValueError, match="unknown field `w`"):
        sim.field("w")
    with pytest.raises(ValueError, match="no solid"):
        sim.field("solid_fraction")
    table = sim.probes(frame=False)
    assert list(table) == ["t", "kinetic_energy", "u_c"]
    np.testing.assert_allclose(table["t"], np.arange(6) * 0.05, rtol=1e-12, atol=0)
    assert table["kinetic_energy"][0] == 0.0 and table["kinetic_energy"][-1] > 0.0
    frame = sim.probes()
    pandas = pytest.importorskip("pandas")
    assert isinstance(frame, pandas.DataFrame) and list(frame.columns) == list(table)
    # A time before the simulation's, or not finite, is refused and changes nothing.
    for t in (0.1, math.nan, math.inf):
        with pytest.raises(efsi.SceneError, match="cannot advance to t"):
            sim.advance_to(t)
    assert (sim.time, sim.steps) == (0.25, steps)
    # Past the scene's end: allowed, no more probe rows after the end.
    assert sim.advance_to(1.2) and sim.time == 1.2
    assert sim.probes(frame=False)["t"][-1] == 1.0


def test_snapshot_restore_gives_the_same_bits():
    sim = efsi.Simulation(efsi.Scene.from_str(CAVITY))
    sim.advance_to(0.2)
    snap = sim.snapshot()
    assert (snap.time, snap.steps) == (0.2, sim.steps)
    sim.advance_to(0.6)
    u1, p1, rows1, steps1 = sim.field("u")[0], sim.field("p")[0], sim.probes(frame=False), sim.steps
    sim.restore(snap)
    assert sim.time == 0.2 and sim.steps == snap.steps
    assert len(sim.probes(frame=False)["t"]) == 5
    sim.advance_to(0.6)
    assert sim.steps == steps1
    assert np.array_equal(sim.field("u")[0], u1) and np.array_equal(sim.field("p")[0], p1)
    rows2 = sim.probes(frame=False)
    assert all(np.array_equal(rows1[c], rows2[c]) for c in rows1)
    # A snapshot of another grid is refused.
    small = efsi.Scene.from_str(CAVITY)
    small.refine(0.5)
    other = efsi.Simulation(small)
    with pytest.raises(efsi.SceneError):
        other.restore(snap)


def test_write_vtk_is_efsi_runs_file(tmp_path):
    vtk = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    sim = efsi.Simulation(efsi.Scene.from_str(CAVITY))
    sim.advance_to(0.3)
    path = Path(sim.write_vtk(tmp_path / "out"))
    assert path == tmp_path / "out/fields" / f"py_api_cavity_{sim.steps:06d}.vtr" and path.is_file()
    assert (tmp_path / "out/fields.pvd").is_file()
    r = vtk.vtkXMLRectilinearGridReader()
    r.SetFileName(str(path))
    r.Update()
    grid = r.GetOutput()
    p = vtk_to_numpy(grid.GetCellData().GetArray("pressure"))
    assert np.array_equal(p, sim.field("p")[0].ravel())
    with pytest.raises(efsi.EfsiError):
        sim.write_vtk(path)  # a file, not a folder
    # A folder with earlier outputs is refused, as efsi run refuses it, unless overwrite.
    sim.advance_to(0.4)
    with pytest.raises(efsi.SceneError, match="holds the outputs of an earlier run"):
        sim.write_vtk(tmp_path / "out")
    later = Path(sim.write_vtk(tmp_path / "out", overwrite=True))
    assert later.is_file() and not path.exists()


def test_an_unstable_run_raises_unstable_error_with_stage_field_and_cell():
    lib = law_library("efsi_test_law_nan")
    scene = efsi.Scene.from_str(nan_law_scene(lib))
    sim = efsi.Simulation(scene)
    with pytest.raises(efsi.UnstableError) as e:
        sim.advance_to(0.6)
    err = e.value
    assert "stage `elastic`: law `test_nan`: non-finite stress" in str(err), str(err)
    assert err.stage == "elastic" and err.field == "stress"
    assert isinstance(err.cell, tuple) and len(err.cell) == 2 and all(isinstance(c, int) for c in err.cell)
    # A cell of the grid or of its ghost layers (the x direction is periodic here).
    assert -3 <= err.cell[0] <= 6 and 0 <= err.cell[1] < 16
    assert sim.steps > 10
    # The exception survives pickling (Dask sends exceptions between processes).
    back = pickle.loads(pickle.dumps(err))
    assert (back.stage, back.field, back.cell, str(back)) == (err.stage, err.field, err.cell, str(err))


def test_a_scene_that_cannot_run_raises_scene_error():
    scene = efsi.Scene.load(SPHERE)
    scene.set("solid.law.name", "no_such_law")
    with pytest.raises(efsi.SceneError, match="no_such_law"):
        efsi.Simulation(scene)


def read_probes(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    header, values = rows[0], np.array([[float(v) for v in r] for r in rows[1:]])
    return header, values


def test_the_same_bits_as_efsi_run(tmp_path):
    """The sphere impact at 8.75 cells per radius through the impact, by `efsi run --set
    --refine` and by the package with the same overrides: every probe value identical."""
    out = tmp_path / "run"
    subprocess.run(
        [EFSI, "run", str(SPHERE), "--set", "time.end=0.035", "--refine", "0.25", "--out", str(out), "-q"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    header, values = read_probes(out / "probes.csv")
    scene = efsi.Scene.load(SPHERE)
    scene.set("time.end", 0.035)
    scene.refine(0.25)
    sim = efsi.Simulation(scene)
    assert sim.advance_to(sim.end)
    rows = sim.probes(frame=False)
    assert list(rows) == header
    mine = np.column_stack([rows[c] for c in header])
    assert mine.shape == values.shape and mine.shape[0] == 176
    assert np.array_equal(mine, values)
    assert json.loads((out / "run.json").read_text())["steps"] == sim.steps
    # It went through the impact: the contact force rose and the sphere slowed.
    assert rows["contact_force"].max() > 0.0 and rows["solid_v"][-1] > rows["solid_v"].min()


def test_a_scene_of_several_bodies_names_its_columns_per_body_as_efsi_run(tmp_path):
    """`cases/two_drops.ron` to t = 0.25 by `efsi run` and by the package: the same columns,
    named per body (`light.solid_y`, …, `light.heavy.shared_volume`), the same bits; each drop
    keeps its volume to 1e-10, the two never share a cell, the heavy one falls faster."""
    two = REPO / "cases/two_drops.ron"
    out = tmp_path / "run"
    subprocess.run(
        [EFSI, "run", str(two), "--set", "time.end=0.25", "--out", str(out), "-q"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    header, values = read_probes(out / "probes.csv")
    scene = efsi.Scene.load(two)
    scene.set("time.end", 0.25)
    sim = efsi.Simulation(scene)
    assert sim.advance_to(sim.end)
    rows = sim.probes(frame=False)
    assert list(rows) == header
    for body in ("light", "heavy"):
        for column in ("solid_volume", "solid_x", "solid_y", "solid_v", "solid_pieces"):
            assert f"{body}.{column}" in header
    assert "solid_y" not in header and "light.heavy.shared_volume" in header
    mine = np.column_stack([rows[c] for c in header])
    assert mine.shape == values.shape and np.array_equal(mine, values)
    for body in ("light", "heavy"):
        v = rows[f"{body}.solid_volume"]
        assert np.max(np.abs(v / v[0] - 1.0)) <= 1e-10
        assert np.all(rows[f"{body}.solid_pieces"] == 1.0)
    assert np.max(rows["max_solid_fraction_sum"]) <= 1.0 + 1e-12
    assert np.all(rows["light.heavy.shared_volume"] == 0.0)
    fall = {b: rows[f"{b}.solid_y"][0] - rows[f"{b}.solid_y"][-1] for b in ("light", "heavy")}
    assert fall["heavy"] > 2.0 * fall["light"] > 0.0


def test_soft_bodies_by_the_package_give_the_bits_of_efsi_run_and_a_strain_energy_each(tmp_path):
    """`cases/two_soft_disks.ron` (two neo-Hookean bodies, each with its own deformation) to
    t = 0.3, through their first contact, by `efsi run` and by the package: the same columns
    and bits, a strain energy per body (`left.elastic_energy`), equal for the mirror images and
    rising as the disks press on each other; no shared cell."""
    two = REPO / "cases/two_soft_disks.ron"
    out = tmp_path / "run"
    subprocess.run(
        [EFSI, "run", str(two), "--set", "time.end=0.3", "--out", str(out), "-q"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    header, values = read_probes(out / "probes.csv")
    scene = efsi.Scene.load(two)
    scene.set("time.end", 0.3)
    sim = efsi.Simulation(scene)
    assert sim.advance_to(sim.end)
    rows = sim.probes(frame=False)
    assert list(rows) == header
    mine = np.column_stack([rows[c] for c in header])
    assert mine.shape == values.shape and np.array_equal(mine, values)
    assert "elastic_energy" not in header
    left, right = rows["left.elastic_energy"], rows["right.elastic_energy"]
    assert np.max(np.abs(left - right)) <= 1e-10 * np.max(left)
    t = rows["t"]
    assert abs(t[10] - 0.1) < 1e-12 and left[-1] > 5.0 * left[10] > 0.0
    assert np.all(rows["left.right.shared_cells"] == 0.0)
    assert np.max(rows["max_solid_fraction_sum"]) <= 1.0 + 1e-12


def test_a_three_dimensional_scene_gives_w_z_and_the_same_bits_as_efsi_run(tmp_path):
    """The 3-D drop (cases/falling_drop_3d.ron, two symmetry planes) at 2 cells per radius,
    by `efsi run --set` and by the package with the same overrides: every probe value
    identical; the fields come as [k, j, i] with their z coordinates, `w` among them; a
    snapshot rewinds the 3-D state bit for bit."""
    drop = REPO / "cases/falling_drop_3d.ron"
    sets = {"grid.nx": 8, "grid.ny": 16, "grid.nz": 8, "time.end": 0.25}
    out = tmp_path / "run"
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
    subprocess.run([EFSI, "run", str(drop), *args, "--out", str(out), "-q"], check=True,
                   stdout=subprocess.DEVNULL)
    header, values = read_probes(out / "probes.csv")
    scene = efsi.Scene.load(drop)
    for k, v in sets.items():
        scene.set(k, v)
    assert scene.get("grid.nz") == 8
    sim = efsi.Simulation(scene)
    sim.advance_to(0.125)
    snap = sim.snapshot()
    assert sim.advance_to(sim.end)
    rows = sim.probes(frame=False)
    assert list(rows) == header
    assert {"solid_z", "solid_w"} <= set(header)
    mine = np.column_stack([rows[c] for c in header])
    assert mine.shape == values.shape and mine.shape[0] == 9
    assert np.array_equal(mine, values)
    assert json.loads((out / "run.json").read_text())["steps"] == sim.steps == 32
    # The drop falls (v < 0); x and z are alike but for the order of the directional splits.
    assert rows["solid_v"][-1] < -0.1
    assert rows["solid_x"][-1] == pytest.approx(rows["solid_z"][-1], rel=1e-6)
    # Fields: cells are 0.25 wide; w lives on z faces, 0 on the symmetry plane z = 0 and on the
    # no-slip wall z = 2; the drop's downflow drags fluid round it, so w is not 0 inside.
    w, x, y, z = sim.field("w")
    assert w.shape == (9, 16, 8) and (x.shape, y.shape, z.shape) == ((8,), (16,), (9,))
    np.testing.assert_allclose(x, (np.arange(8) + 0.5) / 4, rtol=0, atol=1e-15)
    np.testing.assert_allclose(z, np.linspace(0.0, 2.0, 9), rtol=0, atol=1e-15)
    assert np.all(w[0] == 0.0) and np.all(w[-1] == 0.0) and np.abs(w[1:-1]).max() > 1e-3
    u, _, _, zu = sim.field("u")
    assert u.shape == (8, 16, 9) and np.all(u[:, :, 0] == 0.0)
    np.testing.assert_allclose(zu, (np.arange(8) + 0.5) / 4, rtol=0, atol=1e-15)
    phi = sim.field("solid_fraction")[0]
    assert phi.shape == (8, 16, 8)
    assert phi.sum() * 0.25**3 == pytest.approx(rows["solid_volume"][-1], rel=1e-12)
    # x and z mirror each other (to the splitting's order): phi(i, j, k) = phi(k, j, i).
    np.testing.assert_allclose(phi, phi.transpose(2, 1, 0), rtol=0, atol=1e-5)
    w_end, p_end = w, sim.field("p")[0]
    sim.restore(snap)
    assert sim.time == 0.125
    sim.advance_to(sim.end)
    assert np.array_equal(sim.field("w")[0], w_end) and np.array_equal(sim.field("p")[0], p_end)


def test_a_three_dimensional_elastic_sphere_gives_the_same_bits_as_efsi_run(tmp_path):
    """The 3-D sphere impact (cases/sphere_impact_3d.ron, a quarter domain with two symmetry
    planes, neo-Hookean) at 6 cells per radius, released 5.8 mm above the substrate, through
    the impact: `efsi run --set` and the package with the same overrides give every probe value
    identical; a snapshot rewinds the elastic state (B̃ of six components) bit for bit."""
    sphere = REPO / "cases/sphere_impact_3d.ron"
    sets = {"grid.nx": 14, "grid.ny": 28, "grid.nz": 14, "solid.shape.center[1]": 0.025,
            "time.end": 0.008, "output.vtk_every": 0.008}
    out = tmp_path / "run"
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
    subprocess.run([EFSI, "run", str(sphere), *args, "--out", str(out), "-q"], check=True,
                   stdout=subprocess.DEVNULL)
    header, values = read_probes(out / "probes.csv")
    scene = efsi.Scene.load(sphere)
    for k, v in sets.items():
        scene.set(k, v)
    sim = efsi.Simulation(scene)
    sim.advance_to(0.004)
    snap = sim.snapshot()
    assert sim.advance_to(sim.end)
    rows = sim.probes(frame=False)
    assert list(rows) == header
    mine = np.column_stack([rows[c] for c in header])
    assert mine.shape == values.shape and mine.shape[0] == 41
    assert np.array_equal(mine, values)
    assert json.loads((out / "run.json").read_text())["steps"] == sim.steps
    # It went through the impact: the contact force rose and the sphere slowed.
    assert rows["contact_force"].max() > 0.0 and rows["solid_v"][-1] > rows["solid_v"].min()
    v_end, p_end = sim.field("v")[0], sim.field("p")[0]
    sim.restore(snap)
    assert sim.time == 0.004
    sim.advance_to(sim.end)
    assert np.array_equal(sim.field("v")[0], v_end) and np.array_equal(sim.field("p")[0], p_end)


CHILD = textwrap.dedent(
    """
    import math, signal, sys, time
    import efsi
    # A process started in the background of a shell without job control (nohup …, a CI
    # runner) inherits SIGINT ignored, and Python then installs no KeyboardInterrupt for it.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    sim = efsi.Simulation(efsi.Scene.from_str(sys.argv[1]))
    print("ready", flush=True)
    try:
        sim.advance_to(sim.end)
        print("not interrupted", flush=True)
        sys.exit(1)
    except KeyboardInterrupt:
        print(f"interrupted {time.monotonic()!r} {sim.steps} {sim.time!r}", flush=True)
    target = math.floor(sim.time) + 1.0
    sim.advance_to(target)
    rows = sim.probes(frame=False)
    print("final", sim.steps, repr(target), *[rows[c][-1].hex() for c in rows], len(rows["t"]), flush=True)
    """
)


def test_ctrl_c_stops_at_a_step_boundary_and_the_run_goes_on_identically():
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, LONG],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ),
    )
    assert child.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=300)
    assert child.returncode == 0, out + err
    lines = out.splitlines()
    _, at, steps, t = lines[0].split()
    assert float(at) - sent < 1.0, "the stop should come within a step"
    steps, t = int(steps), float(t)
    assert steps > 0 and 0.0 < t < 4000.0
    final = lines[1].split()
    # Continued to the next whole time, the interrupted run is bit for bit an uninterrupted one.
    sim = efsi.Simulation(efsi.Scene.from_str(LONG))
    target = float(final[2])
    sim.advance_to(target)
    rows = sim.probes(frame=False)
    assert int(final[1]) == sim.steps
    assert final[3:] == [rows[c][-1].hex() for c in rows] + [str(len(rows["t"]))]


def test_a_simulation_advancing_in_another_thread_is_busy_not_deadlocked():
    import threading

    sim = efsi.Simulation(efsi.Scene.from_str(LONG))
    worker = threading.Thread(target=sim.advance_to, args=(2.0,))
    worker.start()
    deadline = time.monotonic() + 60
    busy = None
    while worker.is_alive() and time.monotonic() < deadline:
        try:
            sim.time
        except RuntimeError as e:
            busy = str(e)
            break
        time.sleep(0.001)
    worker.join()
    assert busy == "the simulation is busy: advance_to is running on it in another thread"
    assert sim.time == 2.0


def test_after_an_unstable_step_the_simulation_is_back_at_its_last_good_state():
    """A failed step puts back the state at its start (as efsi run and the FMU do) and says so;
    retrying fails the same step again from the same state, never from a corrupted one."""
    lib = law_library("efsi_test_law_nan")
    sim = efsi.Simulation(efsi.Scene.from_str(nan_law_scene(lib)))
    with pytest.raises(efsi.UnstableError) as e:
        sim.advance_to(0.6)
    steps, t = sim.steps, sim.time
    assert steps > 10 and 0 < t < 0.6, (steps, t)
    message = str(e.value)
    assert "stage `elastic`: law `test_nan`: non-finite stress" in message, message
    import re

    said = re.search(r"the simulation is back at its last good state \(step (\d+), t = ([0-9.e+-]+)\)", message)
    assert said, message
    assert int(said[1]) == steps and abs(float(said[2]) - t) <= 1e-6 * t, message
    fields = {name: sim.field(name)[0] for name in ("u", "v", "p", "solid_fraction")}
    assert all(np.all(np.isfinite(f)) for f in fields.values())
    rows = sim.probes(frame=False)
    assert rows["t"][-1] <= t
    for _ in range(3):
        with pytest.raises(efsi.UnstableError) as again:
            sim.advance_to(0.6)
        assert (sim.steps, sim.time) == (steps, t)
        assert str(again.value) == message
        for name, f in fields.items():
            assert np.array_equal(sim.field(name)[0], f), name
        assert len(sim.probes(frame=False)["t"]) == len(rows["t"])
    # The state is a good one: a snapshot of it restores and fails the same step again.
    snap = sim.snapshot()
    assert (snap.time, snap.steps) == (t, steps)


def test_restore_refuses_a_snapshot_of_another_scene():
    sim = efsi.Simulation(efsi.Scene.from_str(CAVITY))
    sim.advance_to(0.2)
    snap = sim.snapshot()
    thicker = efsi.Scene.from_str(CAVITY)
    thicker.set("fluid.viscosity", 0.06)
    other = efsi.Simulation(thicker)
    other.advance_to(0.1)
    with pytest.raises(efsi.SceneError) as e:
        other.restore(snap)
    assert "the snapshot is of another scene (py_api_cavity): fluid.viscosity: 0.05 → 0.06" in str(e.value), str(e.value)
    assert other.time == 0.1 and other.steps > 0
    # A simulation of the same scene takes it, and goes on as the one it was taken from.
    same = efsi.Simulation(efsi.Scene.from_str(CAVITY))
    same.restore(snap)
    assert (same.time, same.steps) == (0.2, snap.steps)
    sim.advance_to(0.4)
    same.advance_to(0.4)
    assert np.array_equal(same.field("u")[0], sim.field("u")[0])

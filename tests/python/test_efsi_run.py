"""`efsi run` output read by the official VTK library: names, shapes and values.

Drives the real binary (`$EFSI_BIN`, set by `cargo xtask test`; else target/debug/efsi) on a
small planar cavity and on an axisymmetric Hagen–Poiseuille pipe whose steady solution is known,
then reads `fields.pvd` and the `.vtr` files with `vtkXMLRectilinearGridReader`.
"""

import csv
import subprocess

import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy

import paraview_support  # noqa: F401 (puts tools/ on the path)
from efsi_test_support import EFSI, REPO
from efsi_vtk import output_times, read_vtr  # noqa: E402


CAVITY = """Scene(
    name: "py_cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 2.0)),
    grid: (nx: 12, ny: 24),
    time: (end: 0.5),
    fluid: (density: 2.0, viscosity: 0.05),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (vtk_every: 0.25, probes: [KineticEnergy],
             profiles: [Line(name: "top", from: (0.0, 1.9583333333333333), to: (1.0, 1.9583333333333333), points: 13, fields: ["u"])]),
)
"""

PIPE = """Scene(
    name: "py_pipe",
    geometry: Axisymmetric,
    domain: (r: (0.0, 1.0), z: (0.0, 0.5)),
    grid: (nr: 16, nz: 4),
    time: (end: 20.0, dt_max: 0.05, steady: 1e-11),
    fluid: (density: 1.0, viscosity: 1.0),
    gravity: (0.0, 4.0),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: Periodic, z_max: Periodic),
    output: (vtk_every: 10.0),
)
"""


def run(tmp_path, text, name):
    scene = tmp_path / f"{name}.ron"
    scene.write_text(text)
    out = tmp_path / name
    subprocess.run([EFSI, "run", str(scene), "--out", str(out), "-q"], check=True)
    return out


def test_planar_run_round_trips(tmp_path):
    out = run(tmp_path, CAVITY, "cavity")
    sets = output_times(out)
    assert [t for t, _ in sets] == [0.0, 0.25, 0.5]
    g = read_vtr(sets[-1][1])
    assert g.GetDimensions() == (13, 25, 1)
    assert g.GetNumberOfCells() == 12 * 24
    cd = g.GetCellData()
    names = {cd.GetArrayName(k) for k in range(cd.GetNumberOfArrays())}
    assert {"velocity", "pressure", "density", "viscosity", "divergence"} <= names
    vel = vtk_to_numpy(cd.GetArray("velocity"))
    assert vel.shape == (12 * 24, 3)
    assert np.all(vel[:, 2] == 0.0)
    assert np.all(vtk_to_numpy(cd.GetArray("density")) == 2.0)
    assert np.all(vtk_to_numpy(cd.GetArray("viscosity")) == 0.05)
    # Divergence-free to the default projection tolerance of a scene of one fluid,
    # max|div|·Δt ≤ 1e-4, with every Δt ≥ 1/30 (the first step from rest, 0.4·h/U; the interior
    # velocities allow longer ones).
    assert np.abs(vtk_to_numpy(cd.GetArray("divergence"))).max() <= 1e-4 * 30.0
    # The top row of cells moves with the lid; compare with the profile through their centres,
    # sampled by efsi itself at the same points (cell centres of the top row).
    top = vel.reshape(24, 12, 3)[-1, :, 0]
    with open(next((out / "profiles").glob("top_t0.5.csv"))) as f:
        rows = list(csv.DictReader(f))
    xs = np.array([float(r["x"]) for r in rows])
    us = np.array([float(r["u"]) for r in rows])
    centres = (np.arange(12) + 0.5) / 12
    assert top.mean() > 0.3 and np.all(top > 0.0)
    # The profile's points are the x-faces of that row, so it holds the face values; the VTK
    # cell-centre velocity is their average: the two agree to round-off.
    assert np.allclose(np.interp(centres, xs, us), top, rtol=0, atol=1e-12)


def test_axisymmetric_slice_in_xz_plane_holds_hagen_poiseuille(tmp_path):
    out = run(tmp_path, PIPE, "pipe")
    g = read_vtr(output_times(out)[-1][1])
    assert g.GetDimensions() == (17, 1, 5), "r–z slice lies in the X–Z plane"
    x = vtk_to_numpy(g.GetXCoordinates())
    assert x[0] == 0.0 and abs(x[-1] - 1.0) < 1e-15
    vel = vtk_to_numpy(g.GetCellData().GetArray("velocity")).reshape(4, 16, 3)
    r = (np.arange(16) + 0.5) / 16
    exact = 4.0 / 4.0 * (1.0 - r**2)
    # Second-order accurate: the error is g h²/(16ν) ≈ 1e-3 here.
    assert np.abs(vel[:, :, 2] - exact).max() < 2e-3
    assert np.all(vel[:, :, 1] == 0.0)
    assert np.abs(vel[:, :, 0]).max() < 1e-12


def test_elastic_run_writes_the_deformation_tensor(tmp_path):
    """A planar scene with a neo-Hookean layer writes `B` (B̃ = φ^{1/2} B) as a VTK symmetric
    tensor: B̃ = I in the solid and 0 in the fluid at t = 0; after shearing, B̃_xy ≠ 0 in the
    solid only."""
    text = (REPO / "cases/oscillating_couette.ron").read_text()
    text = text.replace("ny: 64", "ny: 16").replace("end: 4.8", "end: 0.5").replace("vtk_every: 0.4", "vtk_every: 0.5")
    text = text.replace("at: [0.5, 1.0, 2.0, 2.8, 4.0, 4.8]", "at: [0.5]")
    out = run(tmp_path, text.replace('name: "oscillating_couette"', 'name: "py_couette"'), "couette")
    sets = output_times(out)
    b0 = vtk_to_numpy(read_vtr(sets[0][1]).GetCellData().GetArray("B")).reshape(16, 4, 6)
    assert np.all(b0[:8] == np.array([1, 1, 1, 0, 0, 0]))
    assert np.all(b0[8:] == 0.0)
    b1 = vtk_to_numpy(read_vtr(sets[-1][1]).GetCellData().GetArray("B")).reshape(16, 4, 6)
    assert np.abs(b1[2:8, :, 3]).min() > 1e-3, "sheared solid"
    assert np.all(b1[8:] == 0.0)

"""`tools/paraview_revolve.py` with the official VTK wheel: the sphere impact at 15 cells per
radius, its t = 0 output mirrored and its phi = 1/2 surface revolved; the surface must enclose the
sphere's volume 4/3 pi R^3 within 2 %, and both halves of the mirrored slice face the same way.
Then ParaView itself (`xvfb-run -a pvpython`, headless) runs the script on a short sphere run and
saves a screenshot of the revolved surface, which must show it; where ParaView is not installed
that test is skipped, saying so."""

import subprocess
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

from efsi_test_support import EFSI, REPO
from paraview_support import TOOLS, boundary_edges, read_surface, render_screenshot, sphere_volume_error

import paraview_revolve as tool  # noqa: E402 (from TOOLS, which paraview_support puts on the path)
from efsi_vtk import read_pvd  # noqa: E402

TOOL = TOOLS / "paraview_revolve.py"
R = 0.0192  # cases/sphere_impact.ron


def test_revolved_sphere_encloses_its_volume(tmp_path):
    out = tmp_path / "sphere"
    # 15 cells per radius (35 × 15/35), a few steps: the t = 0 output is the initial sphere.
    subprocess.run([EFSI, "run", str(REPO / "cases/sphere_impact.ron"), "--refine",
                    str(15 / 35), "--set", "time.end=0.0005", "--out", str(out), "-q"],
                   check=True)
    slices, surfaces = tool.process(out, tmp_path / "revolved", time=0.0, resolution=128)
    entries = read_pvd(surfaces)
    assert [t for t, _ in entries] == [0.0]

    surface = read_surface(entries[0][1])
    assert surface.GetPointData().GetArray("pressure") is not None, "arrays carried"
    assert boundary_edges(surface) == 0, "the revolved surface has holes"
    assert abs(sphere_volume_error(surface, R)) < 0.02
    # The extent is the sphere's: radius R about the axis.
    x0, x1, y0, y1, z0, z1 = surface.GetBounds()
    assert abs(x1 - R) < 0.05 * R and abs(x0 + R) < 0.05 * R and abs(y1 - R) < 0.05 * R

    # The mirrored slice covers r in [-0.045, 0.045] with the cell data.
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(read_pvd(slices)[0][1]))
    reader.Update()
    grid = reader.GetOutput()
    bx0, bx1 = grid.GetBounds()[:2]
    assert abs(bx0 + 0.045) < 1e-6 and abs(bx1 - 0.045) < 1e-6  # float32 points
    assert grid.GetCellData().GetArray("solid_fraction") is not None
    assert grid.GetNumberOfCells() == 2 * 35 * 70
    # Every quad faces -Y, the mirrored ones too: (p1 - p0) x (p3 - p0) along -Y.
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(float)
    quads = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    p0, p1, p3 = points[quads[:, 0]], points[quads[:, 1]], points[quads[:, 3]]
    normal_y = np.cross(p1 - p0, p3 - p0)[:, 1]
    assert np.all(normal_y < 0), f"{np.sum(normal_y >= 0)} of {len(quads)} quads face the other way"
    # The mirror's values are the original's, its r velocity reversed.
    velocity = vtk_to_numpy(grid.GetCellData().GetArray("velocity")).reshape(2, 70, 35, 3)
    phi = vtk_to_numpy(grid.GetCellData().GetArray("solid_fraction")).reshape(2, 70, 35)
    assert np.array_equal(phi[0], phi[1])
    assert np.array_equal(velocity[0, ..., 0], -velocity[1, ..., 0])
    assert np.array_equal(velocity[0, ..., 2], velocity[1, ..., 2])
    centres = vtk_to_numpy(grid.GetPoints().GetData())[quads].mean(axis=1)[:, 0].reshape(2, 70, 35)
    assert np.allclose(centres[0], -centres[1])


def test_command_line(tmp_path):
    """The script's command line (as pvpython or python runs it) writes both collections."""
    out = tmp_path / "sphere"
    subprocess.run([EFSI, "run", str(REPO / "cases/sphere_impact.ron"), "--refine", "0.2",
                    "--set", "time.end=0.0005", "--out", str(out), "-q"], check=True)
    r = subprocess.run([sys.executable, str(TOOL), str(out),
                        "--resolution", "16"], capture_output=True, text=True, check=True)
    assert "surface.pvd" in r.stdout, r.stdout
    assert (out / "revolved/slice.pvd").is_file() and (out / "revolved/surface.pvd").is_file()
    bad = subprocess.run([sys.executable, str(TOOL), str(out),
                          "--resolution", "2"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--resolution must be at least 3" in bad.stderr


def test_paraview_renders_the_revolved_sphere(tmp_path):
    """ParaView itself, headless: `xvfb-run -a pvpython tools/paraview_revolve.py RUN
    --screenshot` on a short sphere run writes a screenshot of the revolved phi = 1/2 surface
    (coloured by pressure) over the mirrored section, which must show the sphere."""
    out = tmp_path / "sphere"
    subprocess.run([EFSI, "run", str(REPO / "cases/sphere_impact.ron"), "--refine", "0.3",
                    "--set", "time.end=0.001", "--out", str(out), "-q"], check=True)
    drawn, colours = render_screenshot("paraview_revolve.py", [out, "--resolution", "48"],
                                       tmp_path / "shot.png")
    assert (out / "revolved/surface.pvd").is_file()
    # The section and the sphere fill a good part of the view, shaded in many colours.
    assert drawn > 0.05 and colours > 50, (drawn, colours)

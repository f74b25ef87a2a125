"""`tools/paraview_contour.py` with the official VTK wheel: the phi = 1/2 surface of a sphere's
volume fractions in a box (a run folder as efsi writes it: fields.pvd and a Float64 .vtr of the
box) must be closed and enclose the sphere's volume 4/3 pi R^3 within 3 %; on a three-dimensional
efsi run the level set of its pressure carries the run's arrays, and bad requests are refused
(exit code 2). Then ParaView itself (`xvfb-run -a pvpython`, headless) runs the script and saves
a screenshot of the surface, which must show it; where ParaView is not installed that test is
skipped, saying so."""

import subprocess
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkRectilinearGrid
from vtkmodules.vtkIOXML import vtkXMLRectilinearGridWriter

from efsi_test_support import EFSI, REPO
from paraview_support import TOOLS, boundary_edges, read_surface, render_screenshot, sphere_volume_error

import paraview_contour as tool  # noqa: E402 (from TOOLS, which paraview_support puts on the path)
from efsi_vtk import read_pvd  # noqa: E402

TOOL = TOOLS / "paraview_contour.py"
R = 0.25  # the sphere's radius, centred in the unit box


def sphere_run(folder, n=32, centre=(0.5, 0.5, 0.5)):
    """A run folder holding one output (t = 0) of an n^3 box whose `solid_fraction` is a sphere's
    volume fraction (4^3 samples per cell), with a `pressure` = z."""
    nodes = np.linspace(0.0, 1.0, n + 1)
    sub = (np.arange(4) + 0.5) / 4 / n
    x = (nodes[:-1, None] + sub[None, :]).ravel()
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    inside = (X - centre[0]) ** 2 + (Y - centre[1]) ** 2 + (Z - centre[2]) ** 2 < R * R
    phi = inside.reshape(n, 4, n, 4, n, 4).mean(axis=(1, 3, 5))  # (i, j, k)
    phi = np.ascontiguousarray(phi.transpose(2, 1, 0)).ravel()  # x fastest
    grid = vtkRectilinearGrid()
    grid.SetDimensions(n + 1, n + 1, n + 1)
    for setter in (grid.SetXCoordinates, grid.SetYCoordinates, grid.SetZCoordinates):
        setter(numpy_to_vtk(nodes.copy(), deep=True))
    centres = 0.5 * (nodes[1:] + nodes[:-1])
    for name, values in (("solid_fraction", phi),
                         ("pressure", np.repeat(centres, n * n))):
        a = numpy_to_vtk(np.ascontiguousarray(values, dtype=np.float64), deep=True)
        a.SetName(name)
        grid.GetCellData().AddArray(a)
    (folder / "fields").mkdir(parents=True)
    w = vtkXMLRectilinearGridWriter()
    w.SetFileName(str(folder / "fields/sphere_000000.vtr"))
    w.SetInputData(grid)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    assert w.Write()
    (folder / "fields.pvd").write_text(
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0">\n  <Collection>\n'
        '    <DataSet timestep="0" group="" part="0" file="fields/sphere_000000.vtr"/>\n'
        "  </Collection>\n</VTKFile>\n")
    return folder


def test_the_sphere_surface_encloses_its_volume(tmp_path):
    run = sphere_run(tmp_path / "sphere")
    collection = tool.process(run)
    entries = read_pvd(collection)
    assert [t for t, _ in entries] == [0.0]
    surface = read_surface(entries[0][1])
    assert boundary_edges(surface) == 0, "the surface has holes"
    assert surface.GetPointData().GetArray("pressure") is not None, "arrays carried"
    assert abs(sphere_volume_error(surface, R)) < 0.03  # at 8 cells per radius
    # Its points lie on the sphere, within a cell's diagonal fraction of R.
    points = vtk_to_numpy(surface.GetPoints().GetData()).astype(float)
    radius = np.linalg.norm(points - 0.5, axis=1)
    assert np.all(np.abs(radius - R) < 0.25 / 32 * 2), (radius.min(), radius.max())
    # The pressure (= z at the centres, linear) is interpolated onto it exactly.
    pressure = vtk_to_numpy(surface.GetPointData().GetArray("pressure"))
    assert np.allclose(pressure, points[:, 2], atol=1e-6)


def test_a_body_on_a_wall_is_cut_by_it(tmp_path):
    """A sphere centred on the face z = 0: the surface reaches the face (not half a cell above
    it), open there."""
    run = sphere_run(tmp_path / "wall", centre=(0.5, 0.5, 0.0))
    surface = read_surface(read_pvd(tool.process(run))[0][1])
    z0 = surface.GetBounds()[4]
    assert z0 == 0.0, z0
    assert boundary_edges(surface) > 0


def test_command_line_on_an_efsi_run(tmp_path):
    """On a three-dimensional efsi run (a lid-driven cube): the level set of the pressure,
    carrying the run's arrays; a missing array, a vector or a planar run is refused."""
    out = tmp_path / "cube"
    scene = tmp_path / "cube.ron"
    scene.write_text(
        (REPO / "cases/lid_driven_cube_re1000.ron").read_text()
        .replace("nx: 32, ny: 32, nz: 32", "nx: 8, ny: 8, nz: 8"))
    subprocess.run([EFSI, "run", str(scene), "--set", "time.end=0.2", "--set",
                    "output.vtk_every=0.1", "--out", str(out), "-q"], check=True)
    command = [sys.executable, str(TOOL), str(out)]
    r = subprocess.run(command + ["--field", "pressure", "--level", "0.0", "--time", "0.2"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "surface.pvd" in r.stdout
    entries = read_pvd(out / "contour/surface.pvd")
    assert [t for t, _ in entries] == [0.2]
    surface = read_surface(entries[0][1])
    assert surface.GetNumberOfCells() > 0
    for name in ("velocity", "density", "divergence"):
        assert surface.GetPointData().GetArray(name) is not None, name
    x0, x1, y0, y1, z0, z1 = surface.GetBounds()
    assert 0.0 <= x0 and x1 <= 1.0 and 0.0 <= y0 and y1 <= 1.0 and 0.0 <= z0 and z1 <= 1.0
    pressure = vtk_to_numpy(surface.GetPointData().GetArray("pressure"))
    assert np.all(np.abs(pressure) < 1e-9), "points on the level"
    for args, needle in [
        ([], "no cell array `solid_fraction`"),
        (["--field", "velocity"], "has 3 components"),
        (["--field", "pressure", "--level", "1e9"], "at no output time"),
    ]:
        r = subprocess.run(command + args, capture_output=True, text=True)
        assert r.returncode == 2 and needle in r.stderr, r.stderr
    planar = tmp_path / "square"
    subprocess.run([EFSI, "run", str(REPO / "cases/lid_driven_cavity_re100.ron"), "--set",
                    "time.end=0.05", "--set", "output.vtk_every=0.05", "--out", str(planar), "-q"],
                   check=True)
    r = subprocess.run([sys.executable, str(TOOL), str(planar), "--field", "pressure"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "paraview_revolve.py" in r.stderr, r.stderr


def test_paraview_renders_the_surface(tmp_path):
    """ParaView itself, headless: `xvfb-run -a pvpython tools/paraview_contour.py RUN
    --screenshot` writes a screenshot of the sphere's surface (coloured by pressure) in the box's
    outline, which must show it."""
    run = sphere_run(tmp_path / "sphere", n=24)
    drawn, colours = render_screenshot("paraview_contour.py", [run], tmp_path / "shot.png")
    # The sphere (about 5 % of the view, the outline alone under 1 %), shaded in many colours.
    assert drawn > 0.03 and colours > 50, (drawn, colours)

"""Open an efsi run's VTK output in 3-D: the slice mirrored about the axis, and the solid's
surface (phi = 1/2) revolved about it.

    pvpython tools/paraview_revolve.py out/sphere_impact            # ParaView: opens the results
    python3  tools/paraview_revolve.py out/sphere_impact [--time T] [--resolution N] [--out DIR]

efsi's axisymmetric files hold the r-z half-plane at theta = 0 in the X-Z plane: X = r, Z = z
(the axis), Y = theta. For every output time of RUN/fields.pvd (or the one nearest --time) this
script writes into --out (default RUN/revolved/):

- ``slice_<k>.vtu``: the slice and its mirror image about the axis (X -> -X), the full meridian
  section, with every array as cell data (mirrored: the X component of vectors and the XY, XZ
  components of symmetric tensors change sign); every quad of both halves is ordered
  counter-clockwise seen from -Y, so the whole section faces one way and renders evenly (a
  reflection alone turns the mirrored cells inside out); in a planar run, the slice itself;
- ``surface_<k>.vtp`` (runs with a solid): the phi = 1/2 contour of the solid fraction
  (interpolated linearly between the cell centres, the axis included), revolved about Z through 360 degrees in --resolution steps
  (default 128) - a closed surface carrying every array interpolated from the nodes (colour it
  by pressure, velocity, ...); in a planar run, the contour lines;
- ``slice.pvd`` and ``surface.pvd``: the collections of those files with their times.

It uses only VTK's Python modules (``vtkmodules``), which both the VTK wheel (``pip install
vtk``) and ParaView's pvpython provide; under pvpython it then opens the two collections in
ParaView (``paraview.simple``) and shows them (the slice coloured by the speed, the
surface by the pressure), and with ``--screenshot FILE.png`` saves the view of the last output
time to FILE.png (headless, with a 24-bit virtual screen: ``xvfb-run -a -s "-screen 0
1280x1024x24" pvpython tools/paraview_revolve.py RUN --screenshot shot.png``). ``revolved_surface`` and ``mirrored_slice`` can be
imported and used on a ``vtkRectilinearGrid`` directly.

At t = 0 the revolved surface of the sphere impact encloses 98.2 % of 4/3 pi R^3 at 15 cells per
radius (tests/python/test_revolve.py): the 1/2 level of a linear interpolation of volume
fractions lies slightly inside a convex body.
"""

import sys
from pathlib import Path

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import VTK_QUAD, vtkCellArray, vtkRectilinearGrid, vtkUnstructuredGrid
from vtkmodules.vtkFiltersCore import (
    vtkAppendFilter,
    vtkCleanPolyData,
    vtkContourFilter,
    vtkTriangleFilter,
)
from vtkmodules.vtkFiltersModeling import vtkRotationalExtrusionFilter
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter, vtkXMLUnstructuredGridWriter

sys.path.insert(0, str(Path(__file__).resolve().parent))
from efsi_vtk import Refused, arguments, output_times, read_vtr  # noqa: E402
from efsi_vtk import show_in_paraview, write, write_pvd  # noqa: E402


def is_axisymmetric(grid):
    """Whether the grid is an axisymmetric slice (X = r, Z = z: one node along Y)."""
    return grid.GetDimensions()[1] == 1 and grid.GetDimensions()[2] > 1


def mirrored_slice(grid):
    """The slice and its mirror image about the axis X = 0 (axisymmetric), as an unstructured
    grid of quads with the cell data (the mirror's first); a planar slice as it is.

    Every quad's normal (p1 - p0) x (p3 - p0) points along -Y: the mirror image of a quad is
    reordered, not only reflected (a reflection alone turns it inside out), so that both halves
    face the same way."""
    if not is_axisymmetric(grid):
        append = vtkAppendFilter()
        append.AddInputData(grid)
        append.Update()
        return append.GetOutput()
    x = vtk_to_numpy(grid.GetXCoordinates()).astype(np.float64)
    z = vtk_to_numpy(grid.GetZCoordinates()).astype(np.float64)
    n1, n2 = len(x) - 1, len(z) - 1
    # Nodes: the mirror's columns (-x, outermost first), then the original's; x[0] = 0 on the
    # axis is shared.
    xs = np.concatenate([-x[:0:-1], x]) if x[0] == 0.0 else np.concatenate([-x[::-1], x])
    m = len(xs)
    X, Z = np.meshgrid(xs, z)
    points = np.column_stack([X.ravel(), np.zeros(X.size), Z.ravel()])
    first = m - (n1 + 1)  # the node column of x[0]
    cells = []
    for k in range(n2):
        for i in range(n1):
            # Mirror of cell (i, k): between columns first - i - 1 and first - i, reordered so
            # that it is counter-clockwise like the original.
            a = first - i - 1
            cells.append((k * m + a, k * m + a + 1, (k + 1) * m + a + 1, (k + 1) * m + a))
    for k in range(n2):
        for i in range(n1):
            a = first + i
            cells.append((k * m + a, k * m + a + 1, (k + 1) * m + a + 1, (k + 1) * m + a))
    out = vtkUnstructuredGrid()
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(points), deep=True))
    out.SetPoints(pts)
    conn = np.asarray(cells, dtype=np.int64)
    ids = vtkCellArray()
    ids.SetData(numpy_to_vtkIdTypeArray(np.arange(0, 4 * len(cells) + 1, 4, dtype=np.int64), deep=True),
                numpy_to_vtkIdTypeArray(conn.ravel(), deep=True))
    out.SetCells(VTK_QUAD, ids)
    cd = grid.GetCellData()
    for k in range(cd.GetNumberOfArrays()):
        array = cd.GetArray(k)
        c = array.GetNumberOfComponents()
        values = vtk_to_numpy(array).reshape(n2, n1, c).astype(np.float64)
        mirror = values.copy()
        # The mirror of cell (i, k) is listed in the order of the originals (row by row, i
        # increasing): the same values, reflected.
        if c == 3:
            mirror[..., 0] *= -1.0  # vectors: X -> -X
        elif c == 6:
            mirror[..., 3] *= -1.0  # symmetric tensors (XX, YY, ZZ, XY, YZ, XZ)
            mirror[..., 5] *= -1.0
        both = np.concatenate([mirror.reshape(-1, c), values.reshape(-1, c)])
        v = numpy_to_vtk(np.ascontiguousarray(both), deep=True)
        v.SetName(array.GetName())
        out.GetCellData().AddArray(v)
    return out


def centre_grid(grid):
    """A grid whose nodes are the cell centres of `grid`, with every cell array as point data
    - the values efsi computed, not averages. An axisymmetric grid gains a node column on the
    axis holding the first column's values (the fields are even in r), so that contours reach
    the axis."""
    x, y, z = (vtk_to_numpy(c) for c in (grid.GetXCoordinates(), grid.GetYCoordinates(),
                                          grid.GetZCoordinates()))
    axi = is_axisymmetric(grid)
    second = z if axi else y
    n1, n2 = len(x) - 1, len(second) - 1
    centres = (0.5 * (x[1:] + x[:-1]), 0.5 * (second[1:] + second[:-1]))
    c1 = np.concatenate([[x[0]], centres[0]]) if axi else centres[0]
    out = vtkRectilinearGrid()
    coords = [c1, np.array([0.0]), centres[1]] if axi else [c1, centres[1], np.array([0.0])]
    out.SetDimensions(*(len(c) for c in coords))
    for setter, c in zip((out.SetXCoordinates, out.SetYCoordinates, out.SetZCoordinates), coords):
        setter(numpy_to_vtk(np.ascontiguousarray(c, dtype=np.float64), deep=True))
    cd = grid.GetCellData()
    for k in range(cd.GetNumberOfArrays()):
        array = cd.GetArray(k)
        m = array.GetNumberOfComponents()
        values = vtk_to_numpy(array).reshape(n2, n1, m)
        if axi:
            values = np.concatenate([values[:, :1], values], axis=1)
        v = numpy_to_vtk(np.ascontiguousarray(values.reshape(-1, m)), deep=True)
        v.SetName(array.GetName())
        out.GetPointData().AddArray(v)
    return out


def revolved_surface(grid, resolution=128, level=0.5):
    """The level set phi = `level` of the solid fraction (interpolated linearly between the cell
    centres, see `centre_grid`), revolved about Z through 360 degrees in `resolution` steps: a
    closed triangulated surface with every array interpolated onto it. Planar grids: the contour
    lines. None if the grid has no solid fraction or the contour is empty."""
    if grid.GetCellData().GetArray("solid_fraction") is None:
        return None
    contour = vtkContourFilter()
    contour.SetInputData(centre_grid(grid))
    contour.SetInputArrayToProcess(0, 0, 0, 0, "solid_fraction")  # point data
    contour.SetValue(0, level)
    contour.Update()
    if contour.GetOutput().GetNumberOfPoints() == 0:
        return None
    if not is_axisymmetric(grid):
        return contour.GetOutput()
    # Merge the contour's duplicate points so the profile is one polyline per piece.
    clean = vtkCleanPolyData()
    clean.SetInputConnection(contour.GetOutputPort())
    revolve = vtkRotationalExtrusionFilter()
    revolve.SetInputConnection(clean.GetOutputPort())
    revolve.SetResolution(resolution)
    revolve.SetAngle(360.0)
    revolve.CappingOff()
    triangles = vtkTriangleFilter()
    triangles.SetInputConnection(revolve.GetOutputPort())
    # The last copy of the profile (at 360 degrees, to round-off) is the first: merge points
    # closer than 1e-9 of the size; the triangles this collapses on the axis become lines and
    # points, which the second triangle filter drops. The result is closed.
    merge = vtkCleanPolyData()
    merge.SetInputConnection(triangles.GetOutputPort())
    merge.SetTolerance(1e-9)
    closed = vtkTriangleFilter()
    closed.SetInputConnection(merge.GetOutputPort())
    closed.PassLinesOff()
    closed.PassVertsOff()
    closed.Update()
    return closed.GetOutput()


def process(run, out=None, time=None, resolution=128):
    """Write the mirrored slices and revolved surfaces of the run in folder `run` (every output
    time, or the one nearest `time`) into `out`; returns the paths of the two collections (the
    surface's None without a solid)."""
    run = Path(run)
    out = Path(out) if out is not None else run / "revolved"
    out.mkdir(parents=True, exist_ok=True)
    entries = output_times(run, time)
    slices, surfaces = [], []
    for k, (t, file) in enumerate(entries):
        grid = read_vtr(file)
        write(vtkXMLUnstructuredGridWriter(), mirrored_slice(grid), out / f"slice_{k:04}.vtu")
        slices.append((t, f"slice_{k:04}.vtu"))
        surface = revolved_surface(grid, resolution)
        if surface is not None:
            write(vtkXMLPolyDataWriter(), surface, out / f"surface_{k:04}.vtp")
            surfaces.append((t, f"surface_{k:04}.vtp"))
    write_pvd(out / "slice.pvd", slices)
    if surfaces:
        write_pvd(out / "surface.pvd", surfaces)
    return out / "slice.pvd", (out / "surface.pvd" if surfaces else None)


def main(argv=None):
    p = arguments(__doc__, "revolved")
    p.add_argument("--resolution", type=int, default=128,
                   help="steps of the revolution through 360 degrees (default 128)")
    a = p.parse_args(argv)
    if a.resolution < 3:
        p.error(f"--resolution must be at least 3, got {a.resolution}")
    try:
        slices, surfaces = process(a.run, a.out, a.time, a.resolution)
    except Refused as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {slices}" + (f" and {surfaces}" if surfaces else " (no solid: no surface)"))
    layers = [(slices, ("CELLS", "velocity", "Magnitude"))]
    if surfaces is not None:
        layers.append((surfaces, ("POINTS", "pressure")))
    # Looking at the section from -Y (its quads face that way), Z up, a little from above.
    return show_in_paraview(layers, camera=(0.6, -3.0, 1.2), png=a.screenshot)


if __name__ == "__main__":
    sys.exit(main())

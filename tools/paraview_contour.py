"""Open a three-dimensional efsi run's VTK output in 3-D: the solid's surface (phi = 1/2), or
any level set of a scalar array, over the time series.

    pvpython tools/paraview_contour.py out/drop3d                  # ParaView: opens the results
    python3  tools/paraview_contour.py out/drop3d [--time T] [--field NAME] [--level V] [--out DIR]

efsi's three-dimensional files hold the box: X = x, Y = y, Z = z, cell data at the cell centres.
For every output time of RUN/fields.pvd (or the one nearest --time) this script writes into --out
(default RUN/contour/):

- ``surface_<k>.vtp``: the level set ``--field`` = ``--level`` (default ``solid_fraction`` = 1/2,
  the solid's surface) of the cell values, interpolated trilinearly between the cell centres and,
  within half a cell of a face of the box, holding the next layer's values up to that face (so a
  body touching a wall is cut by it, not half a cell short of it); a triangulated surface with
  every array interpolated onto it (colour it by pressure, velocity, ...), closed where the body
  touches no wall. A time without the level (no solid there) writes no file;
- ``surface.pvd``: the collection of those files with their times.

It uses only VTK's Python modules (``vtkmodules``), which both the VTK wheel (``pip install
vtk``) and ParaView's pvpython provide; under pvpython it then opens the collection and the box's
outline (``fields.pvd``) in ParaView (``paraview.simple``) and shows the surface coloured by the
pressure, and with ``--screenshot FILE.png`` saves the view of the last output time to FILE.png
(headless, with a 24-bit virtual screen: ``xvfb-run -a -s "-screen 0 1280x1024x24" pvpython
tools/paraview_contour.py RUN --screenshot shot.png``). ``contour_surface`` can be imported and
used on a ``vtkRectilinearGrid`` directly. A two-dimensional run (planar or axisymmetric) is
refused: ``tools/paraview_revolve.py`` shows those.
"""

import sys
from pathlib import Path

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkDataObject, vtkRectilinearGrid
from vtkmodules.vtkFiltersCore import vtkContourFilter
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

sys.path.insert(0, str(Path(__file__).resolve().parent))
from efsi_vtk import Refused, arguments, output_times, read_vtr  # noqa: E402
from efsi_vtk import show_in_paraview, write, write_pvd  # noqa: E402


def is_three_dimensional(grid):
    """Whether the grid is a box (no flat axis), as a Cartesian3D run writes."""
    return all(d > 1 for d in grid.GetDimensions())


def centre_grid(grid):
    """A grid whose nodes are the cell centres of the box `grid` and the box's faces, with every
    cell array as point data: at the centres the values efsi computed, on a face those of the
    layer next to it."""
    coords = [vtk_to_numpy(c).astype(np.float64)
              for c in (grid.GetXCoordinates(), grid.GetYCoordinates(), grid.GetZCoordinates())]
    n = [len(c) - 1 for c in coords]
    nodes = [np.concatenate([[c[0]], 0.5 * (c[1:] + c[:-1]), [c[-1]]]) for c in coords]
    out = vtkRectilinearGrid()
    out.SetDimensions(*(len(c) for c in nodes))
    for setter, c in zip((out.SetXCoordinates, out.SetYCoordinates, out.SetZCoordinates), nodes):
        setter(numpy_to_vtk(np.ascontiguousarray(c), deep=True))
    cd = grid.GetCellData()
    for k in range(cd.GetNumberOfArrays()):
        array = cd.GetArray(k)
        m = array.GetNumberOfComponents()
        values = vtk_to_numpy(array).astype(np.float64).reshape(n[2], n[1], n[0], m)
        values = np.pad(values, ((1, 1), (1, 1), (1, 1), (0, 0)), mode="edge")
        v = numpy_to_vtk(np.ascontiguousarray(values.reshape(-1, m)), deep=True)
        v.SetName(array.GetName())
        out.GetPointData().AddArray(v)
    return out


def contour_surface(grid, field="solid_fraction", level=0.5):
    """The level set `field` = `level` of the box `grid`'s cell array `field` (a scalar),
    interpolated between the cell centres (see `centre_grid`), as triangles carrying every array
    and the normals; None where the level is not reached. Refuses (`Refused`) a two-dimensional
    grid, a missing array or one that is not a scalar."""
    if not is_three_dimensional(grid):
        raise Refused("the file is two-dimensional (planar or axisymmetric): "
                      "tools/paraview_revolve.py shows such runs")
    cd = grid.GetCellData()
    array = cd.GetArray(field)
    if array is None:
        names = [cd.GetArrayName(k) for k in range(cd.GetNumberOfArrays())]
        raise Refused(f"no cell array `{field}` (the run has no solid?); it has: {', '.join(names)}")
    if array.GetNumberOfComponents() != 1:
        raise Refused(f"`{field}` has {array.GetNumberOfComponents()} components: "
                      "a level set is of a scalar array")
    contour = vtkContourFilter()
    contour.SetInputData(centre_grid(grid))
    contour.SetInputArrayToProcess(0, 0, 0, vtkDataObject.FIELD_ASSOCIATION_POINTS, field)
    contour.SetValue(0, level)
    contour.ComputeNormalsOn()
    contour.Update()
    surface = contour.GetOutput()
    return surface if surface.GetNumberOfCells() > 0 else None


def process(run, out=None, time=None, field="solid_fraction", level=0.5):
    """Write the level set surfaces of the run in folder `run` (every output time, or the one
    nearest `time`) into `out`; returns the path of their collection (None if no time reaches
    the level)."""
    run = Path(run)
    out = Path(out) if out is not None else run / "contour"
    entries = output_times(run, time)
    out.mkdir(parents=True, exist_ok=True)
    surfaces = []
    for k, (t, file) in enumerate(entries):
        try:
            surface = contour_surface(read_vtr(file), field, level)
        except Refused as e:
            raise Refused(f"{file}: {e}") from None
        if surface is not None:
            write(vtkXMLPolyDataWriter(), surface, out / f"surface_{k:04}.vtp")
            surfaces.append((t, f"surface_{k:04}.vtp"))
    if not surfaces:
        return None
    write_pvd(out / "surface.pvd", surfaces)
    return out / "surface.pvd"


def main(argv=None):
    p = arguments(__doc__, "contour")
    p.add_argument("--field", default="solid_fraction",
                   help="the scalar cell array whose level set is drawn (default solid_fraction)")
    p.add_argument("--level", type=float, default=0.5, help="its level (default 0.5)")
    a = p.parse_args(argv)
    try:
        surfaces = process(a.run, a.out, a.time, a.field, a.level)
    except Refused as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if surfaces is None:
        print(f"error: `{a.field}` = {a.level} at no output time: no surface to show",
              file=sys.stderr)
        return 2
    print(f"wrote {surfaces}")
    # The box's outline and the surface, in an oblique view, Z up.
    layers = [(Path(a.run) / "fields.pvd", None), (surfaces, ("POINTS", "pressure"))]
    return show_in_paraview(layers, camera=(2.5, -2.0, 1.8), png=a.screenshot)


if __name__ == "__main__":
    sys.exit(main())

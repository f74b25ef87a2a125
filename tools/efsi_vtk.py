"""What the ParaView tools share: reading efsi's VTK output, writing VTK XML files and their
collections, and showing collections in ParaView.

``tools/paraview_revolve.py`` (planar and axisymmetric runs) and ``tools/paraview_contour.py``
(three-dimensional runs) import it from their own folder: run as scripts (``pvpython``,
``pvbatch``, ``python3``) or loaded by file path (the tests in ``tests/python``), each puts
``tools/`` on ``sys.path`` first. Reading and writing use only VTK's Python modules
(``vtkmodules``, from the VTK wheel or ParaView); showing needs ParaView's ``paraview.simple``,
which only ``pvpython``/``pvbatch`` provide, and is imported when called.
"""

import argparse
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from vtkmodules.vtkCommonCore import vtkCommand
from vtkmodules.vtkIOXML import vtkXMLRectilinearGridReader

# The render view's and the screenshot's size in pixels.
VIEW_SIZE = (1000, 800)


class Refused(Exception):
    """A run or a request a tool cannot show (the message says why): exit code 2."""


class VtkEvents:
    """Collects the VTK events it observes (errors, warnings), which VTK otherwise only prints:
    ``reader.AddObserver(vtkCommand.ErrorEvent, events)``, then ``events.messages``."""

    def __init__(self):
        self.messages = []

    def __call__(self, obj, event):
        self.messages.append(f"{event} from {obj.GetClassName()}")


def read_pvd(path):
    """The (time, file) entries of a .pvd collection, files resolved against its folder."""
    root = ET.parse(path).getroot()
    return [(float(ds.get("timestep")), Path(path).parent / ds.get("file"))
            for ds in root.iter("DataSet")]


def write_pvd(path, entries):
    """A .pvd collection of the (time, file) `entries`, file names relative to its folder;
    `read_pvd` reads the times back exactly (they are written with `repr`)."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="1.0" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file="{f}"/>' for t, f in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    Path(path).write_text("\n".join(lines))


def output_times(run, time=None):
    """The (time, file) entries of the run's collection ``RUN/fields.pvd``, or only the one
    nearest to `time`; refuses (`Refused`) a collection without entries."""
    entries = read_pvd(Path(run) / "fields.pvd")
    if not entries:
        raise Refused(f"{Path(run) / 'fields.pvd'}: no output times")
    if time is not None:
        entries = [min(entries, key=lambda e: abs(e[0] - time))]
    return entries


def read_vtr(path):
    """A .vtr file as a vtkRectilinearGrid (any efsi output format: Float32/64, zlib)."""
    reader = vtkXMLRectilinearGridReader()
    errors = VtkEvents()
    reader.AddObserver(vtkCommand.ErrorEvent, errors)
    reader.SetFileName(str(path))
    reader.Update()
    if errors.messages or reader.GetErrorCode():
        raise RuntimeError(f"{path}: cannot read: {errors.messages}")
    return reader.GetOutput()


def write(writer, data, path):
    """Write `data` to `path` with the XML `writer`: appended binary, zlib-compressed."""
    writer.SetFileName(str(path))
    writer.SetInputData(data)
    writer.SetDataModeToAppended()
    writer.SetCompressorTypeToZLib()
    if not writer.Write():
        raise RuntimeError(f"cannot write {path}")


def arguments(doc, out):
    """The tools' command line: the run's folder, ``--time``, ``--out`` (default ``RUN/<out>``)
    and ``--screenshot``; the tool adds its own options to the parser returned. ``doc`` is the
    module docstring, whose first paragraph describes the tool."""
    p = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    p.add_argument("run", help="the run's output folder (holding fields.pvd)")
    p.add_argument("--time", type=float, help="only the output time nearest to this")
    p.add_argument("--out", help=f"output folder (default RUN/{out})")
    p.add_argument("--screenshot", metavar="PNG",
                   help="under pvpython: save the view of the last output time to this PNG")
    return p


def show(simple, layers, camera):
    """Open each layer ``(path, colour)`` of ``layers`` in one render view of ParaView's
    ``simple`` module and look at them from ``camera`` towards the origin, Z up, zoomed to fit.
    ``colour`` is the ``ColorBy`` argument (``("POINTS", "pressure")``, ...), its range rescaled
    to the data; ``None`` shows the layer as its outline (a frame, e.g. the box). The view's time
    is the last of the coloured layers' times. Returns the view and the opened sources."""
    view = simple.GetActiveViewOrCreate("RenderView")
    view.ViewSize = list(VIEW_SIZE)
    sources, times = [], []
    for path, colour in layers:
        source = simple.OpenDataFile(str(path))
        sources.append(source)
        shown = simple.Show(source, view)
        if colour is None:
            shown.SetRepresentationType("Outline")
            continue
        times += list(getattr(source, "TimestepValues", None) or [])
        simple.ColorBy(shown, colour)
        shown.RescaleTransferFunctionToDataRange(True, False)
    if times:
        view.ViewTime = max(times)
    view.CameraPosition = list(camera)
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    simple.ResetCamera(view)
    simple.Render(view)
    return view, sources


def screenshot(simple, view, sources, png):
    """Save ``view`` to ``png`` at ``VIEW_SIZE``, then release ``sources`` and the view: headless,
    there is nothing more to show (ParaView 5.11's pvpython can crash tearing the pipeline down
    at exit otherwise)."""
    simple.SaveScreenshot(str(png), view, ImageResolution=list(VIEW_SIZE))
    for source in sources:
        simple.Delete(source)
    simple.Delete(view)


def show_in_paraview(layers, camera, png=None):
    """The tools' last step: under pvpython, `show` the layers and, with `png`, save the
    `screenshot` there; the exit code of the script — 0, or 2 when a screenshot was asked for
    outside pvpython (no ``paraview.simple``), with a message on stderr. Without `png` outside
    pvpython there is nothing to do: 0."""
    try:
        from paraview import simple  # noqa: PLC0415 (only pvpython has it)
    except ImportError:
        simple = None
    if simple is None:
        if png is None:
            return 0
        print("--screenshot needs ParaView: run the script with pvpython", file=sys.stderr)
        return 2
    view, sources = show(simple, layers, camera)
    if png is not None:
        screenshot(simple, view, sources, png)
        print(f"wrote {png}")
    return 0

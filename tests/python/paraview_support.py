"""What the ParaView tools' tests share (test_contour.py, test_revolve.py, test_efsi_vtk.py):
the tools' folder on ``sys.path`` (the tools import ``efsi_vtk`` from it, as ``pvpython`` runs
them), the surfaces' checks, and ParaView itself, headless, rendering a tool's screenshot."""

import math
import shutil
import subprocess
import sys

import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkFiltersCore import vtkFeatureEdges, vtkMassProperties
from vtkmodules.vtkIOImage import vtkPNGReader
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

from efsi_test_support import REPO

TOOLS = REPO / "tools"
sys.path.insert(0, str(TOOLS))


def read_surface(path):
    """A .vtp file as vtkPolyData."""
    reader = vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    return reader.GetOutput()


def boundary_edges(surface):
    """The number of edges of `surface` that belong to one polygon only (0: closed)."""
    edges = vtkFeatureEdges()
    edges.SetInputData(surface)
    edges.BoundaryEdgesOn()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.NonManifoldEdgesOff()
    edges.Update()
    return edges.GetOutput().GetNumberOfCells()


def sphere_volume_error(surface, radius):
    """The relative error of the volume the closed `surface` encloses against the sphere's
    4/3 pi R^3 (printed with both volumes)."""
    mass = vtkMassProperties()
    mass.SetInputData(surface)
    mass.Update()
    exact = 4.0 / 3.0 * math.pi * radius**3
    volume = mass.GetVolume()
    print(f"enclosed volume {volume:.6e} vs 4/3 pi R^3 = {exact:.6e} "
          f"({100 * (volume / exact - 1):+.3f} %)")
    return volume / exact - 1.0


def render_screenshot(tool, args, shot):
    """Run ``xvfb-run -a pvpython tools/<tool> ARGS --screenshot SHOT`` (headless, 24-bit screen)
    and return the fraction of the screenshot's pixels not of its background colour and the
    number of its colours. Skips the test, saying how to install them, where ParaView or
    xvfb-run is missing."""
    missing = [t for t in ("pvpython", "xvfb-run") if shutil.which(t) is None]
    if missing:
        pytest.skip(
            f"ParaView is not installed here ({', '.join(missing)} not found): "
            "apt-get install --no-install-recommends paraview python3-paraview xvfb xauth "
            "(.ci/run installs it)"
        )
    r = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", "pvpython",
                        str(TOOLS / tool), *map(str, args), "--screenshot", str(shot)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"wrote {shot}" in r.stdout, r.stdout + r.stderr
    reader = vtkPNGReader()
    reader.SetFileName(str(shot))
    reader.Update()
    image = reader.GetOutput()
    w, h, _ = image.GetDimensions()
    assert (w, h) == (1000, 800)
    rgb = vtk_to_numpy(image.GetPointData().GetScalars())[:, :3].astype(int)
    packed = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    drawn = np.mean(packed != np.bincount(packed).argmax())
    colours = len(np.unique(rgb, axis=0))
    print(f"screenshot {shot}: {100 * drawn:.1f} % of the pixels drawn, {colours} colours")
    return drawn, colours

"""Independent-reader test of efsi's VTK output.

Runs the `vtk_fixture` example of efsi-run, which writes planar and axisymmetric `.vtr` files,
their `.pvd` collections and `expected.json`, then reads every file back with the official VTK
library (not with efsi's own code) and checks it against `expected.json` bit for bit.

    python3 -m venv /tmp/venv-vtk && /tmp/venv-vtk/bin/pip install -r tests/python/requirements.txt
    /tmp/venv-vtk/bin/pytest tests/python -q
"""

import json
import os
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkCommand, vtkDoubleArray, vtkFloatArray
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkIOXML import vtkXMLRectilinearGridReader

import paraview_support  # noqa: F401 (puts tools/ on the path)
from efsi_vtk import VtkEvents  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def fixture_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("vtk_fixture")
    subprocess.run(
        ["cargo", "run", "-q", "-p", "efsi-run", "--example", "vtk_fixture", "--", str(out)],
        cwd=REPO,
        check=True,
    )
    return out


@pytest.fixture(scope="module")
def expected(fixture_dir):
    return json.loads((fixture_dir / "expected.json").read_text())


def read_vtr(path):
    reader = vtkXMLRectilinearGridReader()
    catcher = VtkEvents()
    reader.AddObserver(vtkCommand.ErrorEvent, catcher)
    reader.AddObserver(vtkCommand.WarningEvent, catcher)
    reader.SetFileName(str(path))
    reader.Update()
    assert not catcher.messages, f"{path}: {catcher.messages}"
    assert reader.GetErrorCode() == 0, path
    return reader


def as_f64(values):
    return np.asarray(values, dtype=np.float64)


def assert_bit_equal(got, want, what):
    assert got.dtype == np.float64, f"{what}: dtype {got.dtype}"
    assert got.shape == want.shape, f"{what}: shape {got.shape} != {want.shape}"
    # Compare bit patterns: exact f64 round trip, and -0.0 != 0.0.
    assert np.array_equal(got.view(np.uint64), want.view(np.uint64)), what


def test_fixture_lists_both_geometries(expected):
    geometries = {f["geometry"] for f in expected["files"]}
    assert geometries == {"Planar", "Axisymmetric"}
    assert len(expected["files"]) == 10
    assert sum(f["float32"] and f["zlib"] and f["point_data"] for f in expected["files"]) == 6


def test_vtr_grid_and_arrays(fixture_dir, expected):
    for f in expected["files"]:
        name = f["file"]
        grid = read_vtr(fixture_dir / name).GetOutput()

        assert list(grid.GetDimensions()) == f["dims"], name
        assert list(grid.GetExtent()) == f["extent"], name
        assert grid.GetNumberOfCells() == f["cells"], name
        if f["geometry"] == "Axisymmetric":
            # The r–z slice lies in the X–Z plane, ready for Rotational Extrusion about Z.
            assert f["dims"][1] == 1 and f["extent"][2:4] == [0, 0], name
        else:
            assert f["dims"][2] == 1 and f["extent"][4:6] == [0, 0], name

        axes = (grid.GetXCoordinates(), grid.GetYCoordinates(), grid.GetZCoordinates())
        for axis, coords in zip("xyz", axes):
            assert isinstance(coords, vtkDoubleArray), f"{name}: {axis} coordinates"
            assert_bit_equal(vtk_to_numpy(coords), as_f64(f[axis]), f"{name}: {axis} coordinates")

        cd = grid.GetCellData()
        got_names = [cd.GetArrayName(k) for k in range(cd.GetNumberOfArrays())]
        assert got_names == [a["name"] for a in f["arrays"]], name
        pd = grid.GetPointData()
        assert pd.GetNumberOfArrays() == (len(f["arrays"]) if f["point_data"] else 0), name
        for a in f["arrays"]:
            arr = cd.GetArray(a["name"])
            what = f"{name}: {a['name']}"
            assert arr.GetNumberOfComponents() == a["components"], what
            assert arr.GetNumberOfTuples() == f["cells"], what
            got = vtk_to_numpy(arr).reshape(f["cells"], a["components"])
            want = as_f64(a["values"]).reshape(f["cells"], a["components"])
            if f["float32"]:
                # Float32: the values rounded to single precision, exactly.
                assert isinstance(arr, vtkFloatArray), what
                assert got.dtype == np.float32, what
                assert np.array_equal(got.view(np.uint32), want.astype(np.float32).view(np.uint32)), what
            else:
                assert isinstance(arr, vtkDoubleArray), what
                assert_bit_equal(got, want, what)
            if f["point_data"]:
                # Each node: the mean of the (up to four) cells around it.
                nx, ny = (d - 1 for d in f["dims"] if d > 1)
                cells = want.reshape(ny, nx, a["components"])
                padded = np.full((ny + 2, nx + 2, a["components"]), np.nan)
                padded[1:-1, 1:-1] = cells
                around = np.stack([padded[:-1, :-1], padded[:-1, 1:], padded[1:, :-1], padded[1:, 1:]])
                nodes = np.nanmean(around, axis=0).reshape(-1, a["components"])
                parr = pd.GetArray(a["name"])
                assert parr.GetNumberOfComponents() == a["components"], what
                got_p = vtk_to_numpy(parr).reshape(-1, a["components"])
                assert np.allclose(got_p, nodes, rtol=1e-6, atol=1e-6), what


def test_vtr_text_field_data(fixture_dir, expected):
    """The geometry and units notes come back as one-tuple string arrays."""
    for f in expected["files"]:
        fd = read_vtr(fixture_dir / f["file"]).GetOutput().GetFieldData()
        for note in f["notes"]:
            arr = fd.GetAbstractArray(note["name"])
            assert arr is not None, f"{f['file']}: no {note['name']}"
            assert arr.GetNumberOfTuples() == 1
            assert arr.GetValue(0) == note["text"], f["file"]
        if f["geometry"] == "Axisymmetric" and f["notes"]:
            assert "X = r" in fd.GetAbstractArray("geometry").GetValue(0)


def test_zlib_files_name_the_compressor(fixture_dir, expected):
    for f in expected["files"]:
        header = (fixture_dir / f["file"]).read_bytes()[:300]
        assert (b'compressor="vtkZLibDataCompressor"' in header) == f["zlib"], f["file"]


def test_vtr_time(fixture_dir, expected):
    for f in expected["files"]:
        name = f["file"]
        reader = read_vtr(fixture_dir / name)
        fd = reader.GetOutput().GetFieldData()
        time = fd.GetArray("TIME")
        assert time is not None, f"{name}: no TIME field data"
        assert time.GetNumberOfTuples() == 1 and time.GetNumberOfComponents() == 1, name
        assert time.GetValue(0) == f["time"], name
        # VTK's XML readers report a `TimeValue` field array as the file's time step.
        info = reader.GetOutputInformation(0)
        key = vtkStreamingDemandDrivenPipeline.TIME_STEPS()
        assert info.Has(key), f"{name}: the reader reports no time step"
        assert [info.Get(key, k) for k in range(info.Length(key))] == [f["time"]], name


def test_pvd_collections(fixture_dir, expected):
    for c in expected["collections"]:
        pvd = fixture_dir / c["file"]
        root = ET.parse(pvd).getroot()
        assert root.tag == "VTKFile" and root.get("type") == "Collection", pvd
        (collection,) = root.findall("Collection")
        sets = collection.findall("DataSet")
        assert len(sets) == len(c["entries"]) == 2, pvd
        times = [float(ds.get("timestep")) for ds in sets]
        assert times == [e["time"] for e in c["entries"]], pvd
        assert times == sorted(times), pvd
        for ds, e in zip(sets, c["entries"]):
            assert ds.get("file") == e["file"], pvd
            target = pvd.parent / ds.get("file")
            assert target.is_file(), target
            # The time in the .pvd matches the TIME stored in the file it names.
            fd = read_vtr(target).GetOutput().GetFieldData()
            assert fd.GetArray("TIME").GetValue(0) == float(ds.get("timestep")), target


def test_no_temporary_files_left(fixture_dir):
    leftovers = [p for p in os.listdir(fixture_dir) if p.endswith(".tmp")]
    assert not leftovers

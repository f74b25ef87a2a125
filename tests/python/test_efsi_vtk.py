"""`tools/efsi_vtk.py`, the ParaView tools' shared part, without ParaView: a collection written
and read back, the output times chosen, and what `show` and `screenshot` ask of ParaView's
`simple` module, recorded by a stand-in for it."""

import pytest

import paraview_support  # noqa: F401 (puts tools/ on the path)
from efsi_vtk import Refused, VIEW_SIZE, output_times, read_pvd, screenshot, show, show_in_paraview, write_pvd


def test_a_collection_reads_back_its_times_and_files(tmp_path):
    times = [0.0, 2.5e-7, 0.1, 1.0 / 3.0]
    write_pvd(tmp_path / "fields.pvd", [(t, f"fields/f_{k}.vtr") for k, t in enumerate(times)])
    entries = read_pvd(tmp_path / "fields.pvd")
    assert [t for t, _ in entries] == times  # bit for bit: written with repr
    assert [f for _, f in entries] == [tmp_path / f"fields/f_{k}.vtr" for k in range(4)]
    assert output_times(tmp_path, time=0.09) == [entries[2]]
    assert output_times(tmp_path, time=7.0) == [entries[3]]
    assert output_times(tmp_path) == entries
    write_pvd(tmp_path / "fields.pvd", [])
    with pytest.raises(Refused, match="no output times"):
        output_times(tmp_path)


class Recorder:
    """Stands in for `paraview.simple`: records each call as (name, args) and hands out
    objects that record the attributes set on them."""

    class Thing:
        def __init__(self, name, **attributes):
            self.name = name
            self.__dict__.update(attributes)
            self.calls = []

        def SetRepresentationType(self, kind):
            self.calls.append(("SetRepresentationType", kind))

        def RescaleTransferFunctionToDataRange(self, *args):
            self.calls.append(("Rescale", args))

    def __init__(self, times):
        self.times = times
        self.calls = []
        self.shown = []

    def GetActiveViewOrCreate(self, kind):
        self.view = self.Thing(kind)
        return self.view

    def OpenDataFile(self, path):
        return self.Thing(path, TimestepValues=self.times[path])

    def Show(self, source, view):
        self.shown.append(self.Thing(source.name))
        return self.shown[-1]

    def __getattr__(self, name):  # ColorBy, ResetCamera, Render, SaveScreenshot, Delete
        return lambda *args, **kwargs: self.calls.append((name, args, kwargs))


def test_show_and_screenshot_ask_paraview_for_the_view(tmp_path):
    # The box's times run past the surfaces': the view's time is the surfaces' last.
    simple = Recorder({"box.pvd": [0.0, 1.0, 2.0], "surface.pvd": [0.0, 0.5]})
    layers = [("box.pvd", None), ("surface.pvd", ("POINTS", "pressure"))]
    view, sources = show(simple, layers, camera=(2.5, -2.0, 1.8))
    assert view.ViewSize == list(VIEW_SIZE) and view.ViewTime == 0.5
    assert (view.CameraPosition, view.CameraFocalPoint, view.CameraViewUp) == (
        [2.5, -2.0, 1.8], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    box, surface = simple.shown
    assert box.calls == [("SetRepresentationType", "Outline")]
    assert surface.calls == [("Rescale", (True, False))]
    assert [c[0] for c in simple.calls] == ["ColorBy", "ResetCamera", "Render"]
    assert simple.calls[0][1][1] == ("POINTS", "pressure")
    assert [s.name for s in sources] == ["box.pvd", "surface.pvd"]
    simple.calls.clear()
    screenshot(simple, view, sources, tmp_path / "shot.png")
    (name, args, kwargs), *deleted = simple.calls
    assert (name, args[0], kwargs) == (
        "SaveScreenshot", str(tmp_path / "shot.png"), {"ImageResolution": [1000, 800]})
    assert [d[1][0] for d in deleted] == [*sources, view]


def test_outside_pvpython_a_screenshot_is_refused(tmp_path, capsys):
    try:
        import paraview.simple  # noqa: F401, PLC0415
    except ImportError:
        pass
    else:
        pytest.skip("paraview.simple is importable here: the tools would show the view")
    assert show_in_paraview([(tmp_path / "x.pvd", None)], (1.0, 0.0, 0.0)) == 0
    assert show_in_paraview([(tmp_path / "x.pvd", None)], (1.0, 0.0, 0.0), tmp_path / "s.png") == 2
    assert "--screenshot needs ParaView" in capsys.readouterr().err
    assert not (tmp_path / "s.png").exists()

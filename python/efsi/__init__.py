"""efsi from Python: scenes, simulations, parameter sweeps on Dask.

>>> import efsi
>>> scene = efsi.Scene.load("cases/sphere_impact.ron")
>>> scene.set("solid.law.parameters.G", 1e6)      # the paths of `efsi run --set`
>>> scene.refine(0.5)                            # `efsi run --refine`
>>> sim = efsi.Simulation(scene)
>>> sim.advance_to(0.01)                         # Ctrl-C stops at a step boundary
True
>>> u, x, y = sim.field("u")                     # numpy arrays: values [y, x] and coordinates
>>> probes = sim.probes()                        # the rows of efsi run's probes.csv

The solver is efsi's own (the extension module ``efsi._efsi``): a simulation advanced to the
scene's end holds the probe rows of ``efsi run`` of the same scene bit for bit. Laws are
found on efsi's law search path (``EFSI_LAW_PATH``, the build's ``target/release`` and
``target/debug``); see ``efsi laws``.
"""

import numpy as _np

from . import _efsi
from .errors import EfsiError, SceneError, UnstableError

__all__ = [
    "Scene",
    "Simulation",
    "Snapshot",
    "EfsiError",
    "SceneError",
    "UnstableError",
    "sweep",
]
__version__ = _efsi.__version__

Scene = _efsi.Scene
Snapshot = _efsi.Snapshot


class Simulation(_efsi.Simulation):
    """A running simulation of a :class:`Scene` (see ``help(efsi._efsi.Simulation)``)."""

    def field(self, name):
        """The field ``name`` (``u``, ``v``, ``p``, ``density``, ``viscosity``,
        ``solid_fraction``; ``w`` in a ``Cartesian3D`` scene) as ``(values, x, y)``:
        ``values[j, i]`` at ``(x[i], y[j])``; in a ``Cartesian3D`` scene as
        ``(values, x, y, z)``: ``values[k, j, i]`` at ``(x[i], y[j], z[k])``."""
        data, shape, x, y, z = self._field(name)
        values = _np.frombuffer(data, dtype="<f8").reshape(shape).copy()
        if z is None:
            return values, _np.asarray(x), _np.asarray(y)
        return values, _np.asarray(x), _np.asarray(y), _np.asarray(z)

    def probes(self, frame=None):
        """The probe rows recorded so far — those of ``efsi run``'s ``probes.csv`` — as a
        pandas DataFrame when pandas is installed (``frame=None``) or asked for
        (``frame=True``), else a dict of numpy columns (``frame=False``)."""
        columns, flat = self._probes()
        table = _np.asarray(flat, dtype=float).reshape(-1, len(columns))
        data = {c: table[:, k].copy() for k, c in enumerate(columns)}
        if frame is False:
            return data
        try:
            import pandas
        except ImportError:
            if frame:
                raise
            return data
        return pandas.DataFrame(data)

from .sweeps import sweep  # noqa: E402  (needs Simulation)

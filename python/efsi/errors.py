"""The exceptions efsi raises, each carrying efsi's own message.

- :class:`EfsiError`: the base class; also what I/O failures and internal errors raise (a panic
  inside efsi is caught and raised as ``EfsiError("internal error: efsi panicked: …")``).
- :class:`SceneError`: bad input — a scene that does not parse or is out of range, an override
  with a bad path, type or value, a scene that cannot be run as it is, a snapshot of another
  simulation, a time to advance to that is before the simulation's time. (``efsi run``'s exit
  code 2.)
- :class:`UnstableError`: a run that failed numerically — a NaN or infinity after a stage, a
  solver that did not converge, a collapsing time step, energy growth. ``stage``, ``field`` and
  ``cell`` name where, when efsi's message says. (``efsi run``'s exit code 3.) The simulation
  is then back at the start of the failed step, its last good state (time, step count, fields,
  probe rows), as the message's last line says; it can be advanced again (after changing what
  made it fail, it fails the same way) or restored to a snapshot.
"""


class EfsiError(Exception):
    """An efsi error; ``str(e)`` is efsi's message."""


class SceneError(EfsiError, ValueError):
    """A scene, setting or argument efsi refuses (the message names it and says why)."""


class UnstableError(EfsiError, ArithmeticError):
    """A run that failed numerically.

    Attributes: ``stage`` (the stage that failed, e.g. ``"projection"``, or None), ``field``
    (the field with the non-finite value, e.g. ``"u"``, or None), ``cell`` (``(i, j)`` or None).
    """

    def __init__(self, message, stage=None, field=None, cell=None):
        super().__init__(message)
        self.stage = stage
        self.field = field
        self.cell = tuple(cell) if cell is not None else None

    def __reduce__(self):
        return (UnstableError, (str(self), self.stage, self.field, self.cell))

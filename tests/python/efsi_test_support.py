"""Paths and scenes shared by the Python package's tests (test_python_api.py, test_python_sweep.py)."""

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
EFSI = os.environ.get("EFSI_BIN", str(REPO / "target/debug/efsi"))
BIN_DIR = Path(EFSI).parent
os.environ.setdefault("EFSI_LAW_PATH", os.pathsep.join([str(BIN_DIR), str(BIN_DIR / "deps")]))
SPHERE = REPO / "cases/sphere_impact.ron"


def law_library(stem):
    """The law plugin `lib<stem>.so` built next to efsi (or in its deps/)."""
    for d in (BIN_DIR, BIN_DIR / "deps"):
        p = d / f"lib{stem}.so"
        if p.is_file():
            return p
    pytest.fail(f"lib{stem}.so is not built next to {EFSI}")


def nan_law_scene(lib):
    """A small box with an elastic block whose law (the test_nan library `lib`, G = 5, limit
    1.01) returns NaN once the wall has sheared it past its limit."""
    return f"""Scene(
    name: "solid",
    domain: (x: (0.0, 0.0625), y: (0.0, 1.0)),
    grid: (nx: 4, ny: 16),
    time: (end: 0.6, dt_max: 0.01),
    fluid: (density: 1.0, viscosity: 1.0),
    solid: (shape: HalfPlane(normal: (0.0, 1.0), offset: 0.5), density: 1.0, viscosity: 0.0,
            law: (name: "{lib}", parameters: {{"G": 5.0, "limit": 1.01}})),
    boundaries: (x_min: Periodic, x_max: Periodic, y_min: NoSlip,
                 y_max: MovingWall(speed: 1.0, motion: Sin(omega: 3.141592653589793))),
    output: (probe_every: 0.05, probes: [KineticEnergy]),
)"""

"""efsi.sweep on a real Dask cluster: a `dask scheduler` and two `dask worker` processes on
localhost, a 6-run sweep of the sphere impact at low resolution (shear modulus × cells per
radius) through `Client(address)`, one worker killed mid-sweep; every row comes back, with the
numbers of the same six runs made one after the other in this process. Also the outcomes of
refused and unstable runs, the table's files, and `efsi sweep` from the command line.
"""

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import efsi

pandas = pytest.importorskip("pandas")
distributed = pytest.importorskip("distributed")

from efsi_test_support import BIN_DIR, EFSI, REPO, SPHERE, law_library, nan_law_scene  # noqa: F401

# Shear modulus × refinement (8.75 and 10.5 cells per radius of the scene's 35), to t = 0.03:
# through the impact (≈ 0.027 s).
GRID = {"solid.law.parameters.G": [1e5, 1.8e5, 1e6], "refine": [0.25, 0.3]}
UNTIL = 0.03


def summary(sim):
    """The figures of a run (the workers import it from this module: see `start`)."""
    rows = sim.probes(frame=False)
    return {
        "min_solid_v": float(rows["solid_v"].min()),
        "final_solid_v": float(rows["solid_v"][-1]),
        "max_contact_force": float(rows["contact_force"].max()),
    }


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start(args):
    # The cluster's environment is this one's, with this folder importable (as a cluster's
    # workers must import the code of the functions they run).
    path = os.pathsep.join(p for p in [str(Path(__file__).parent), os.environ.get("PYTHONPATH")] if p)
    env = dict(os.environ, RAYON_NUM_THREADS="1", PYTHONPATH=path)
    return subprocess.Popen(
        [sys.executable, "-m", "dask", *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
        start_new_session=True,
    )


@pytest.fixture
def cluster():
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [start(["scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"])]
    try:
        for _ in range(2):
            procs.append(
                start(["worker", address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1"])
            )
        yield address, procs
    finally:
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def test_a_sweep_on_two_workers_survives_a_killed_worker_and_matches_serial(cluster, tmp_path):
    address, procs = cluster
    client = distributed.Client(address, timeout=60)
    try:
        client.wait_for_workers(2, timeout=120)
        result = {}

        def run():
            result["table"] = efsi.sweep(
                SPHERE, GRID, client=client, summary=summary, until=UNTIL, out=tmp_path / "t.parquet", progress=False
            )

        sweeper = threading.Thread(target=run)
        sweeper.start()
        # Once both workers are running a task, kill one (its nanny and its worker process).
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and sweeper.is_alive():
            busy = [w for w, tasks in client.processing().items() if tasks]
            if len(busy) == 2:
                break
            time.sleep(0.05)
        else:
            pytest.fail("the two workers never ran tasks at once")
        victim = procs[2]
        os.killpg(victim.pid, signal.SIGKILL)
        victim.wait()
        sweeper.join(timeout=600)
        assert not sweeper.is_alive(), "the sweep did not finish"
    finally:
        client.close()
    table = result["table"]
    assert len(table) == 6 and list(table["outcome"]) == ["ok"] * 6, table.to_string()
    assert list(table.columns) == [
        "solid.law.parameters.G",
        "refine",
        "wall_time",
        "steps",
        "t",
        "min_solid_v",
        "final_solid_v",
        "max_contact_force",
        "outcome",
    ]
    assert list(zip(table["solid.law.parameters.G"], table["refine"])) == [
        (g, r) for g in GRID["solid.law.parameters.G"] for r in GRID["refine"]
    ]
    # The same six runs one after the other in this process: the same numbers, bit for bit.
    serial = efsi.sweep(SPHERE, GRID, client=False, summary=summary, until=UNTIL)
    same = [c for c in table.columns if c != "wall_time"]
    pandas.testing.assert_frame_equal(table[same], serial[same], check_exact=True)
    assert np.all(table["t"] == UNTIL) and np.all(table["wall_time"] > 0)
    # The sphere hit the wall and bounced in every run; the stiffer it is, the harder it hits.
    assert np.all(table["max_contact_force"] > 0) and np.all(table["final_solid_v"] > table["min_solid_v"])
    fine = table[table["refine"] == 0.3]
    assert np.all(np.diff(fine["max_contact_force"].to_numpy()) > 0)
    written = pandas.read_parquet(tmp_path / "t.parquet")
    pandas.testing.assert_frame_equal(written, table, check_exact=True)


def test_refused_and_unstable_runs_are_rows():
    lib = law_library("efsi_test_law_nan")
    scene = efsi.Scene.from_str(nan_law_scene(lib))
    runs = [
        {"solid.law.parameters.limit": 100.0},  # never reached: ok
        {"solid.law.parameters.limit": 1.01},  # NaN stress after some shearing: unstable
        {"grid.nx": 0},  # refused
    ]
    table = efsi.sweep(
        scene,
        runs,
        client=False,
        summary=lambda sim: sim.probes(frame=False)["kinetic_energy"][-1],
    )
    outcome = list(table["outcome"])
    assert outcome[0] == "ok" and table["summary"][0] > 0
    assert outcome[1].startswith("unstable: stage `elastic`: law `test_nan`: non-finite stress"), outcome[1]
    assert outcome[2].startswith("refused: ") and "grid.nx: must be at least 1 cell, got 0" in outcome[2]
    assert table["steps"][2] == 0 and np.isnan(table["summary"][1])


def test_efsi_sweep_from_the_command_line(tmp_path):
    out = tmp_path / "sweep.csv"
    done = subprocess.run(
        [
            EFSI,
            "sweep",
            str(SPHERE),
            "--grid",
            "solid.law.parameters.G=1e5,1e6",
            "--grid",
            "refine=0.2",
            "--grid",
            "time.end=0.005",
            "--serial",
            "--out",
            str(out),
            "-q",
        ],
        capture_output=True,
        text=True,
        env=dict(os.environ, EFSI_PYTHON=sys.executable),
    )
    assert done.returncode == 0, done.stdout + done.stderr
    table = pandas.read_csv(out)
    assert list(table["solid.law.parameters.G"]) == [1e5, 1e6]
    assert list(table["outcome"]) == ["ok", "ok"] and np.all(table["t"] == 0.005)
    assert "final_solid_v" in table.columns
    # The same run through the package.
    scene = efsi.Scene.load(SPHERE)
    for path, value in (("solid.law.parameters.G", 1e5), ("refine", 0.2), ("time.end", 0.005)):
        scene.refine(value) if path == "refine" else scene.set(path, value)
    sim = efsi.Simulation(scene)
    sim.advance_to(sim.end)
    assert table["final_solid_v"][0] == sim.probes(frame=False)["solid_v"][-1]
    bad = subprocess.run(
        [EFSI, "sweep", str(SPHERE), "--grid", "nonsense"],
        capture_output=True,
        text=True,
        env=dict(os.environ, EFSI_PYTHON=sys.executable),
    )
    assert bad.returncode == 2 and "PATH=V1,V2" in bad.stderr, bad.stderr

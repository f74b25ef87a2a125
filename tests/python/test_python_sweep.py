"""efsi.sweep on a real Dask cluster: a `dask scheduler` and two `dask worker` processes on
localhost, a 6-run sweep of the sphere impact at low resolution (shear modulus × cells per
radius) through `Client(address)`, one worker killed mid-sweep; every row comes back, with the
numbers of the same six runs made one after the other in this process. Also the outcomes of
refused and unstable runs, the table's files, and `efsi sweep` from the command line; arguments
refused before any run, rows written as they arrive, a run that kills its worker as a row.
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


def crash_at_high_g(sim):
    """A summary that kills its process (as a crashing law library would) for G = 1.8e5."""
    if sim.scene.get("solid.law.parameters.G") == 1.8e5:
        os.kill(os.getpid(), signal.SIGKILL)
    return {"final_solid_v": float(sim.probes(frame=False)["solid_v"][-1])}


def test_a_run_that_kills_its_worker_is_a_row_and_the_others_survive(tmp_path):
    out = tmp_path / "crash.csv"
    grid = {"solid.law.parameters.G": [1e5, 1.8e5, 1e6], "refine": [0.2]}
    table = efsi.sweep(SPHERE, grid, summary=crash_at_high_g, until=0.002, out=out, progress=False, workers=2)
    outcome = list(table["outcome"])
    assert outcome[0] == "ok" and outcome[2] == "ok", outcome
    assert outcome[1].startswith("crashed: the run killed its worker process"), outcome[1]
    assert np.isnan(table["final_solid_v"][1]) and np.all(np.isfinite(table["final_solid_v"][[0, 2]]))
    written = pandas.read_csv(out)
    assert list(written["outcome"]) == outcome
    serial = efsi.sweep(SPHERE, {"solid.law.parameters.G": [1e5, 1e6], "refine": [0.2]}, client=False,
                        summary=crash_at_high_g, until=0.002, progress=False)
    assert list(serial["final_solid_v"]) == [table["final_solid_v"][0], table["final_solid_v"][2]]


def test_rows_are_written_as_they_arrive(tmp_path):
    out = tmp_path / "rows.csv"
    seen = []

    def summary(sim):
        # Each run's summary sees the rows of the runs before it already in the file.
        seen.append(len(pandas.read_csv(out)) if out.exists() else 0)
        return {"steps_seen": sim.steps}

    runs = [{"time.end": 0.001, "refine": 0.2}] * 3
    table = efsi.sweep(SPHERE, runs, client=False, summary=summary, out=out, progress=False)
    assert seen == [0, 1, 2]
    assert list(table["outcome"]) == ["ok"] * 3
    pandas.testing.assert_frame_equal(pandas.read_csv(out), table, check_exact=False)


@pytest.mark.parametrize(
    "kwargs, error, needle",
    [
        ({"grid": {"refine": ["abc"]}}, ValueError, "`refine` must be a finite number > 0, got 'abc'"),
        ({"grid": {"refine": [0.0]}}, ValueError, "`refine` must be a finite number > 0, got 0.0"),
        ({"grid": []}, ValueError, "the grid has no runs"),
        ({"grid": {}}, ValueError, "the grid has no settings"),
        ({"grid": [1, 2]}, TypeError, "run 0 must be a dict of settings"),
        ({"grid": [{"grid.nx": [1, 2]}]}, TypeError, "run 0: `grid.nx` must be one value"),
        ({"grid": {"grid.nx": 8}}, TypeError, "the values of `grid.nx` must be a list"),
        ({"until": float("nan")}, ValueError, "until must be a finite time ≥ 0, got nan"),
        ({"until": -1.0}, ValueError, "until must be a finite time ≥ 0, got -1.0"),
        ({"workers": -3}, ValueError, "workers must be a whole number ≥ 1, got -3"),
        ({"threads_per_run": 0}, ValueError, "threads_per_run must be a whole number ≥ 1, got 0"),
        ({"out": "/nonexistent-efsi-folder/t.csv"}, ValueError, "the folder /nonexistent-efsi-folder does not exist"),
        ({"out": "t.xlsx"}, ValueError, "the output must end in .csv, .parquet or .json"),
    ],
)
def test_sweep_arguments_are_refused_before_any_run(kwargs, error, needle, tmp_path):
    ran = []
    args = dict(grid={"refine": [0.2]}, client=False, summary=lambda sim: ran.append(1), progress=False)
    args.update(kwargs)
    with pytest.raises(error) as e:
        efsi.sweep(SPHERE, **args)
    assert needle in str(e.value), str(e.value)
    assert ran == []


def test_an_existing_folder_as_out_is_refused(tmp_path):
    folder = tmp_path / "d.csv"
    folder.mkdir()
    with pytest.raises(ValueError, match="cannot write the table: it is a folder"):
        efsi.sweep(SPHERE, {"refine": [0.2]}, client=False, out=folder)


def efsi_sweep(*args):
    return subprocess.run(
        [EFSI, "sweep", str(SPHERE), *args, "-q"],
        capture_output=True,
        text=True,
        env=dict(os.environ, EFSI_PYTHON=sys.executable),
        timeout=120,
    )


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--grid", "refine=abc"], "`refine` must be a finite number > 0, got 'abc'"),
        (["--runs", "{missing}"], "No such file or directory"),
        (["--runs", "[]"], "the list has no runs"),
        (["--runs", "{}"], "expected a JSON list of objects"),
        (["--runs", "[1, 2]"], "run 0 must be a dict of settings"),
        (["--runs", '[{"grid.nx": [8, 16]}]'], "run 0: `grid.nx` must be one value"),
        (["--runs", "not json"], "not JSON"),
        (["--grid", "refine=0.2", "--workers", "-3"], "--workers: must be at least 1, got -3"),
        (["--grid", "refine=0.2", "--until", "NaN"], "--until: must be a finite time ≥ 0, got NaN"),
        (["--grid", "refine=0.2", "--out", "/nonexistent-efsi-folder/t.csv"], "does not exist"),
    ],
)
def test_efsi_sweep_refuses_bad_arguments_with_exit_code_2(args, needle, tmp_path):
    args = list(args)
    if "--runs" in args:
        k = args.index("--runs") + 1
        if args[k] == "{missing}":
            args[k] = str(tmp_path / "missing.json")
        else:
            (tmp_path / "runs.json").write_text(args[k])
            args[k] = str(tmp_path / "runs.json")
    if "--out" not in args:
        args += ["--out", str(tmp_path / "t.csv")]
    done = efsi_sweep(*args)
    assert done.returncode == 2, done.stdout + done.stderr
    assert needle in done.stderr, done.stderr
    assert "Traceback" not in done.stderr, done.stderr
    assert not (tmp_path / "t.csv").exists()

"""Parameter sweeps: one scene over a grid of settings, each run a Dask task.

>>> table = efsi.sweep("cases/sphere_impact.ron",
...                    {"solid.law.parameters.G": [1e5, 1e6], "refine": [0.25, 0.5]},
...                    summary=lambda sim: {"v_end": sim.probes(frame=False)["solid_v"][-1]})

**The runs.** ``grid`` is a dict of setting paths (those of ``efsi run --set``; ``"refine"``
for ``--refine``) to lists of values, run as their Cartesian product, or a list of dicts, one
per run. Each run applies its settings to the scene in the order given, builds the simulation
and advances it to the scene's end (or ``until``); ``summary(sim)`` then returns its figures
(a dict, or one number).

**The table.** One row per run, in the order of the grid: the settings, ``wall_time`` (s, the
stepping alone), ``steps``, ``t``, the summary's figures, and ``outcome``: ``ok``,
``refused: <message>`` (a setting or scene efsi refuses: the run never started),
``unstable: <message>`` (the run failed numerically) or ``failed: <message>`` (anything else,
a summary that raised included). A refused or unstable run is a row, never a failed sweep.

**Where it runs.** On a ``distributed.LocalCluster`` made for the sweep (``workers`` processes
of one thread each, default one per core; closed afterwards), or on the cluster of ``client``
when one is given (``distributed.Client(address)``, a dask-jobqueue cluster's client, …): the
runs are tasks, so a worker lost mid-sweep has its tasks run again elsewhere by Dask. With
``client=False`` the runs are made one after the other in this process (no Dask). Each run's
result depends only on its settings, so every way gives the same numbers.

Progress is Dask's progress bar (``progress=False`` for none); ``out`` writes the table as CSV
(``.csv``), Parquet (``.parquet``, needs pyarrow) or JSON records (``.json``).
"""

import itertools
import math
import os
import time

REFINE = "refine"


def runs(grid):
    """The runs of ``grid`` as a list of dicts (settings in the order given)."""
    if isinstance(grid, dict):
        keys = list(grid)
        for k in keys:
            if isinstance(grid[k], (str, bytes)) or not hasattr(grid[k], "__iter__"):
                raise TypeError(f"sweep: the values of `{k}` must be a list, got {grid[k]!r}")
        return [dict(zip(keys, values)) for values in itertools.product(*(list(grid[k]) for k in keys))]
    out = [dict(r) for r in grid]
    if not out:
        raise ValueError("sweep: the grid has no runs")
    return out


def final_probes(sim):
    """A summary: the last probe row's values, as ``final_<column>``."""
    rows = sim.probes(frame=False)
    return {f"final_{c}": float(v[-1]) for c, v in rows.items() if c != "t" and len(v)}


class SaveProbes:
    """A summary that writes each run's probe rows (those of ``efsi run``'s ``probes.csv``, the
    same format) to ``<folder>/<run id>/probes.csv`` and returns that run folder as
    ``probes_dir``, with the final probe values (:func:`final_probes`). For clusters that share
    the folder with the caller (a LocalCluster; a cluster's shared file system)."""

    def __init__(self, folder):
        self.folder = os.path.abspath(os.fspath(folder))

    def __call__(self, sim):
        import uuid

        import numpy as np

        rows = sim.probes(frame=False)
        run = os.path.join(self.folder, uuid.uuid4().hex)
        os.makedirs(run, exist_ok=True)
        table = np.column_stack([rows[c] for c in rows])
        with open(os.path.join(run, "probes.csv"), "w") as f:
            f.write(",".join(rows) + "\n")
            for r in table:
                f.write(",".join(f"{v:.17e}" for v in r) + "\n")
        return {"probes_dir": run, **final_probes(sim)}


def _scene(scene):
    from . import Scene

    if isinstance(scene, Scene):
        return scene
    return Scene.load(os.fspath(scene))


def run_one(scene, settings, summary=None, until=None):
    """Make one run (what each task does): the row of the table, without the index."""
    from . import Simulation
    from .errors import EfsiError, SceneError, UnstableError

    row = dict(settings)
    row.update(wall_time=math.nan, steps=0, t=math.nan)
    try:
        s = _scene(scene).copy()
        for path, value in settings.items():
            if path == REFINE:
                s.refine(float(value))
            else:
                s.set(path, value)
        sim = Simulation(s)
    except SceneError as e:
        row["outcome"] = f"refused: {e}"
        return row
    except EfsiError as e:
        row["outcome"] = f"failed: {e}"
        return row
    start = time.perf_counter()
    try:
        sim.advance_to(sim.end if until is None else until)
        outcome = "ok"
    except UnstableError as e:
        outcome = f"unstable: {e}"
    except EfsiError as e:
        outcome = f"failed: {e}"
    row.update(wall_time=time.perf_counter() - start, steps=sim.steps, t=sim.time)
    if outcome == "ok" and summary is not None:
        try:
            figures = summary(sim)
            if not isinstance(figures, dict):
                figures = {"summary": figures}
            row.update(figures)
        except Exception as e:  # the summary is the caller's code: its failure is a row too
            outcome = f"failed: summary: {type(e).__name__}: {e}"
    row["outcome"] = outcome
    return row


def sweep(
    scene,
    grid,
    client=None,
    summary=None,
    until=None,
    out=None,
    progress=True,
    workers=None,
    threads_per_run=1,
):
    """Run ``scene`` (an ``efsi.Scene`` or a path) over ``grid`` and return the table as a
    pandas DataFrame (see the module's documentation)."""
    import pandas

    scene = _scene(scene)
    todo = runs(grid)
    if client is False:
        rows = [run_one(scene, r, summary, until) for r in todo]
    else:
        rows = _on_dask(scene, todo, client, summary, until, progress, workers, threads_per_run)
    table = pandas.DataFrame(rows)
    columns = list(todo[0]) + [c for c in table.columns if c not in todo[0] and c != "outcome"]
    table = table[columns + ["outcome"]]
    if out is not None:
        write(table, out)
    return table


def _on_dask(scene, todo, client, summary, until, progress, workers, threads_per_run):
    from distributed import Client, LocalCluster, wait
    from distributed import progress as bar

    own = None
    if client is None:
        n = workers or os.cpu_count() or 1
        # One thread per worker process; each run's stages use `threads_per_run` threads.
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            env={"RAYON_NUM_THREADS": str(threads_per_run)},
        )
        own = (cluster, Client(cluster))
        client = own[1]
    try:
        futures = [
            client.submit(run_one, scene, r, summary, until, pure=False, key=f"efsi-run-{k}-{os.urandom(4).hex()}")
            for k, r in enumerate(todo)
        ]
        if progress:
            bar(futures)
        wait(futures)
        return client.gather(futures)
    finally:
        if own is not None:
            own[1].close()
            own[0].close()


def write(table, path):
    """Write the table as CSV (``.csv``), Parquet (``.parquet``) or JSON records (``.json``)."""
    path = os.fspath(path)
    if path.endswith(".parquet"):
        table.to_parquet(path, index=False)
    elif path.endswith(".json"):
        table.to_json(path, orient="records", double_precision=15)
    elif path.endswith(".csv"):
        table.to_csv(path, index=False)
    else:
        raise ValueError(f"sweep: {path}: the output must end in .csv, .parquet or .json")

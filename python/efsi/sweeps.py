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
``unstable: <message>`` (the run failed numerically), ``crashed: <message>`` (the run killed
its worker process) or ``failed: <message>`` (anything else, a summary that raised included).
Every run is a row, never a failed sweep.

**Where it runs.** On a ``distributed.LocalCluster`` made for the sweep (``workers`` processes
of one thread each, default one per core; closed afterwards), or on the cluster of ``client``
when one is given (``distributed.Client(address)``, a dask-jobqueue cluster's client, …): the
runs are tasks, so a worker lost mid-sweep has its tasks run again elsewhere by Dask. With
``client=False`` the runs are made one after the other in this process (no Dask). Each run's
result depends only on its settings, so every way gives the same numbers.

**Arguments are checked before the first run**: a grid that is not a dict of lists or a list of
dicts of single values, a ``refine`` value that is not a positive number, an ``until`` that is
not a finite time ≥ 0, ``workers`` or ``threads_per_run`` below 1, and an ``out`` that cannot
be written raise ``ValueError`` / ``TypeError`` naming what is wrong, nothing run.

**Rows are kept as they arrive.** ``out`` (CSV ``.csv``, Parquet ``.parquet`` — needs pyarrow —,
or JSON records ``.json``) is rewritten (atomically) each time a run finishes, with the rows
finished so far in the grid's order: a sweep stopped half way leaves the finished half. A run
that kills its worker process (a crash inside a law library, the operating system's
out-of-memory killer) is a row, ``crashed: <why>``; on the sweep's own LocalCluster a task is
not given to a second worker after it killed one (Dask's ``allowed-failures`` = 0), so one bad
run costs one worker restart. On a cluster of the caller's, Dask's own ``allowed-failures``
decides (default 3) before the run becomes that row. Progress is a line on stderr
(``progress=False`` for none). With ``client=False`` a crash takes this process with it.
"""

import itertools
import math
import numbers
import os
import sys
import time

REFINE = "refine"


def _is_value(v):
    """Whether ``v`` is a single setting value (bool, number or str; numpy scalars too)."""
    if getattr(v, "shape", None) == () and hasattr(v, "item"):
        v = v.item()
    return isinstance(v, (bool, numbers.Number, str))


def runs(grid):
    """The runs of ``grid`` as a list of dicts (settings in the order given), checked: every
    key a setting path (str), every value a single bool, number or str, ``refine`` a finite
    positive number. Raises ``TypeError`` / ``ValueError`` naming the run and the setting."""
    if isinstance(grid, dict):
        keys = list(grid)
        if not keys:
            raise ValueError("sweep: the grid has no settings (give PATH: [values, …])")
        for k in keys:
            if isinstance(grid[k], (str, bytes, dict)) or not hasattr(grid[k], "__iter__"):
                raise TypeError(f"sweep: the values of `{k}` must be a list, got {grid[k]!r}")
        out = [dict(zip(keys, values)) for values in itertools.product(*(list(grid[k]) for k in keys))]
        where = lambda n: "grid"  # noqa: E731
    elif isinstance(grid, (str, bytes)) or not hasattr(grid, "__iter__"):
        raise TypeError(f"sweep: the grid must be a dict of lists or a list of dicts, got {grid!r}")
    else:
        out = []
        for n, r in enumerate(grid):
            if not isinstance(r, dict):
                raise TypeError(f"sweep: run {n} must be a dict of settings {{PATH: VALUE}}, got {r!r}")
            out.append(dict(r))
        where = lambda n: f"run {n}"  # noqa: E731
    if not out:
        raise ValueError("sweep: the grid has no runs")
    for n, r in enumerate(out):
        for k, v in r.items():
            if not isinstance(k, str) or not k.strip():
                raise TypeError(f"sweep: {where(n)}: a setting path must be a non-empty str, got {k!r}")
            if not _is_value(v):
                raise TypeError(
                    f"sweep: {where(n)}: `{k}` must be one value (a bool, number or str), got {v!r}"
                )
            if k == REFINE and (
                isinstance(v, (bool, str)) or not math.isfinite(float(v)) or float(v) <= 0
            ):
                raise ValueError(f"sweep: {where(n)}: `refine` must be a finite number > 0, got {v!r}")
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
    except (SceneError, TypeError, ValueError) as e:
        # efsi's refusal, or a value of a type no setting takes.
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


def check(until=None, workers=None, threads_per_run=1, out=None):
    """Check a sweep's arguments (see the module's documentation) before any run; raises
    ``ValueError`` naming the argument."""
    if until is not None:
        if isinstance(until, bool) or not isinstance(until, numbers.Real) or not math.isfinite(until) or until < 0:
            raise ValueError(f"sweep: until must be a finite time ≥ 0, got {until!r}")
    for name, n in (("workers", workers), ("threads_per_run", threads_per_run)):
        if n is None and name == "workers":
            continue
        if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
            raise ValueError(f"sweep: {name} must be a whole number ≥ 1, got {n!r}")
    if out is not None:
        writable(out)


def writable(path):
    """Refuse an output path the table cannot be written to (its suffix, its folder, the file),
    without creating anything."""
    path = os.path.abspath(os.fspath(path))
    if not path.endswith((".csv", ".parquet", ".json")):
        raise ValueError(f"sweep: {path}: the output must end in .csv, .parquet or .json")
    folder = os.path.dirname(path)
    if not os.path.isdir(folder):
        raise ValueError(f"sweep: {path}: cannot write the table: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"sweep: {path}: cannot write the table: the folder {folder} is not writable")
    if os.path.isdir(path):
        raise ValueError(f"sweep: {path}: cannot write the table: it is a folder")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise ValueError(f"sweep: {path}: cannot write the table: the file is not writable")


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
    import pandas  # noqa: F401  (needed for the table: fail before any run without it)

    todo = runs(grid)
    check(until, workers, threads_per_run, out)
    scene = _scene(scene)
    rows = [None] * len(todo)
    state = {"done": 0, "start": time.monotonic()}

    def arrived(k, row):
        rows[k] = row
        state["done"] += 1
        if out is not None:
            write(_table(todo, [r for r in rows if r is not None]), out)
        if progress:
            print(
                f"\refsi sweep: {state['done']}/{len(todo)} runs ({time.monotonic() - state['start']:.0f} s)",
                end="\n" if state["done"] == len(todo) else "",
                file=sys.stderr,
                flush=True,
            )

    if client is False:
        for k, r in enumerate(todo):
            arrived(k, run_one(scene, r, summary, until))
    else:
        _on_dask(scene, todo, client, summary, until, workers, threads_per_run, arrived)
    return _table(todo, rows)


def _table(todo, rows):
    """The table of ``rows`` (settings first, in the grid's order of keys; outcome last)."""
    import pandas

    table = pandas.DataFrame(rows)
    keys = list(dict.fromkeys(k for r in todo for k in r))
    columns = keys + [c for c in table.columns if c not in keys and c != "outcome"]
    return table.reindex(columns=columns + ["outcome"])


def _crashed(settings, exc):
    """The row of a run whose task failed outside ``run_one`` (its worker died)."""
    row = dict(settings)
    row.update(wall_time=math.nan, steps=0, t=math.nan)
    name = type(exc).__name__
    if name == "KilledWorker":
        row["outcome"] = f"crashed: the run killed its worker process ({exc})"
    else:
        row["outcome"] = f"failed: {name}: {exc}"
    return row


def _on_dask(scene, todo, client, summary, until, workers, threads_per_run, arrived):
    import dask
    from distributed import Client, LocalCluster, as_completed

    own = None
    if client is None:
        n = workers or os.cpu_count() or 1
        # One thread per worker process; each run's stages use `threads_per_run` threads. A
        # task that killed its worker is not retried (it would kill the next one), and a
        # worker holds one task at a time (so a crash takes no other run with it).
        with dask.config.set(
            {"distributed.scheduler.allowed-failures": 0, "distributed.scheduler.worker-saturation": 1.0}
        ):
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
        futures = {
            client.submit(run_one, scene, r, summary, until, pure=False, key=f"efsi-run-{k}-{os.urandom(4).hex()}"): k
            for k, r in enumerate(todo)
        }
        for future in as_completed(list(futures)):
            k = futures[future]
            if future.status == "finished":
                row = future.result()
            else:
                row = _crashed(todo[k], future.exception())
            future.release()
            arrived(k, row)
    finally:
        if own is not None:
            own[1].close()
            own[0].close()


def write(table, path):
    """Write the table as CSV (``.csv``), Parquet (``.parquet``) or JSON records (``.json``),
    atomically (a temporary file beside it, renamed)."""
    path = os.path.abspath(os.fspath(path))
    writable(path)
    folder, name = os.path.split(path)
    tmp = os.path.join(folder, f".{name}.{os.getpid()}.tmp")
    try:
        if path.endswith(".parquet"):
            table.to_parquet(tmp, index=False)
        elif path.endswith(".json"):
            table.to_json(tmp, orient="records", double_precision=15)
        else:
            table.to_csv(tmp, index=False)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)

"""``python -m efsi sweep SCENE --grid PATH=v1,v2 … [--scheduler ADDRESS]`` (what
``efsi sweep`` runs): a sweep from the command line; the table is printed and written to
``--out`` (CSV, Parquet or JSON) as its rows arrive, the summary of each run being its final
probe values.

Exit codes: 0 the table is complete (whatever the runs' outcomes); 2 an argument refused
before any run — a malformed ``--grid`` or ``--runs`` (not a JSON list of objects of single
values), a ``refine`` value that is not a positive number, ``--workers`` below 1, an
``--until`` that is not a finite time ≥ 0, an ``--out`` or ``--save-probes`` that cannot be
written, a scene efsi refuses."""

import argparse
import os
import sys


def _value(text):
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _checked(kind, noun, ok, rule):
    """An argparse type: `text` read as `kind` (else "is not `noun`"), then refused unless
    `ok(value)` ("must be `rule`, got TEXT")."""

    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"`{text}` is not {noun}") from None
        if not ok(value):
            raise argparse.ArgumentTypeError(f"must be {rule}, got {text}")
        return value

    return parse


_positive_int = _checked(int, "a whole number", lambda n: n >= 1, "at least 1")
_time = _checked(float, "a number", lambda t: t >= 0 and t != float("inf"), "a finite time ≥ 0")


def _read_runs(path):
    """The runs of a ``--runs`` file: a JSON list of objects. Raises ``ValueError``."""
    import json

    try:
        with open(path) as f:
            runs = json.load(f)
    except OSError as e:
        raise ValueError(f"--runs {path}: {e.strerror}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"--runs {path}: not JSON: {e}") from None
    if not isinstance(runs, list):
        raise ValueError(f"--runs {path}: expected a JSON list of objects [{{PATH: VALUE, …}}, …], got {type(runs).__name__}")
    if not runs:
        raise ValueError(f"--runs {path}: the list has no runs")
    return runs


def _grid_option(text):
    path, sep, values = text.partition("=")
    if not sep or not path.strip() or not values.strip():
        raise argparse.ArgumentTypeError(
            f"`{text}`: expected PATH=V1,V2,… (e.g. solid.law.parameters.G=1e5,1e6 or refine=0.5,1)"
        )
    return path.strip(), [_value(v.strip()) for v in values.split(",")]


def main(argv=None):
    parser = argparse.ArgumentParser(prog="efsi sweep", description="Run a scene over a grid of settings on Dask.")
    parser.add_argument("scene", help="the scene file (RON)")
    parser.add_argument(
        "--grid",
        action="append",
        type=_grid_option,
        metavar="PATH=V1,V2",
        help="a setting's values (the paths of efsi run --set; `refine` for --refine); repeat for a product",
    )
    parser.add_argument(
        "--runs",
        metavar="FILE",
        help="the runs as a JSON list of objects {PATH: VALUE, …} instead of --grid",
    )
    parser.add_argument(
        "--save-probes",
        metavar="DIR",
        help="write each run's probe rows to DIR/<run>/probes.csv (column probes_dir)",
    )
    parser.add_argument("--scheduler", metavar="ADDRESS", help="a Dask scheduler's address (default: a LocalCluster)")
    parser.add_argument(
        "--workers", type=_positive_int, help="LocalCluster worker processes, ≥ 1 (default: one per core)"
    )
    parser.add_argument("--serial", action="store_true", help="run in this process, one after the other (no Dask)")
    parser.add_argument(
        "--until", type=_time, help="stop each run at this time, finite and ≥ 0 (default: the scene's end)"
    )
    parser.add_argument("--out", default="sweep.csv", help="the table: .csv, .parquet or .json (default sweep.csv)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if bool(args.grid) == bool(args.runs):
        parser.error("give either --grid PATH=V1,V2 … or --runs FILE")

    from . import SceneError, Scene
    from .sweeps import SaveProbes, check, final_probes, runs, sweep

    def refuse(message):
        print(f"error: {message}", file=sys.stderr)
        return 2

    try:
        grid = _read_runs(args.runs) if args.runs else dict(args.grid)
        runs(grid)
        check(until=args.until, workers=args.workers, out=args.out)
        if args.save_probes:
            os.makedirs(args.save_probes, exist_ok=True)
            if not os.access(args.save_probes, os.W_OK | os.X_OK):
                raise ValueError(f"--save-probes {args.save_probes}: the folder is not writable")
    except (ValueError, TypeError) as e:
        return refuse(e)
    except OSError as e:
        return refuse(f"--save-probes {args.save_probes}: {e.strerror}")
    try:
        scene = Scene.load(args.scene)
    except SceneError as e:
        return refuse(e)
    client = None
    if args.serial:
        client = False
    elif args.scheduler:
        from distributed import Client

        client = Client(args.scheduler)
    try:
        table = sweep(
            scene,
            grid,
            client=client,
            summary=SaveProbes(args.save_probes) if args.save_probes else final_probes,
            until=args.until,
            out=args.out,
            progress=not args.quiet,
            workers=args.workers,
        )
    finally:
        if client:
            client.close()
    if not args.quiet:
        import pandas

        with pandas.option_context("display.max_columns", None, "display.width", 200):
            print(table.to_string(index=False))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "sweep":
        sys.exit(main(sys.argv[2:]))
    print("usage: python -m efsi sweep SCENE --grid PATH=V1,V2 … (see python -m efsi sweep --help)", file=sys.stderr)
    sys.exit(2)

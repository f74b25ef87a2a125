"""The sphere impact's restitution coefficient against the shear modulus G and the cells per
radius, and the speed/accuracy trade: each resolution's error (against the finest) against its
wall time.

    python python/examples/restitution.py [--quick] [--scheduler ADDRESS] [--out DIR]

A sweep of cases/sphere_impact.ron (35 cells per radius) refined by 1/7, 1/4, 1/2 (5, 8.75 and
17.5 cells per radius; --quick: 1/7 and 1/4 and a shorter G list) over G, on a LocalCluster (or
the Dask cluster at ADDRESS). The restitution coefficient is e = v_rebound / |v_impact|: the
largest upward centroid velocity after the contact over the largest downward one before it. The
table goes to DIR/restitution.csv and, with matplotlib installed, the plots to DIR/restitution.png.
"""

import argparse
from pathlib import Path

import numpy as np

import efsi

SCENE = Path(__file__).resolve().parents[2] / "cases/sphere_impact.ron"
CELLS_PER_RADIUS = 35


def restitution(sim):
    """e = v_rebound / |v_impact| from the centroid velocity, and the contact's duration."""
    rows = sim.probes(frame=False)
    t, v, force = rows["t"], rows["solid_v"], rows["contact_force"]
    touching = np.flatnonzero(force > 0)
    if len(touching) == 0:
        return {"e": np.nan, "contact_time": 0.0, "v_impact": float(v.min())}
    first = touching[0]
    v_impact = float(v[: first + 1].min())
    v_rebound = float(v[first:].max())
    return {
        "e": v_rebound / abs(v_impact),
        "contact_time": float(t[touching[-1]] - t[first]),
        "v_impact": v_impact,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="two resolutions, two moduli")
    parser.add_argument("--scheduler", help="a Dask scheduler's address (default: a LocalCluster)")
    parser.add_argument("--out", default="out/restitution", help="output folder")
    args = parser.parse_args()

    refine = [1 / 7, 1 / 4] if args.quick else [1 / 7, 1 / 4, 1 / 2]
    moduli = [1e5, 1e6] if args.quick else [1e5, 1.8e5, 1e6, 1e7]
    client = None
    if args.scheduler:
        from distributed import Client

        client = Client(args.scheduler)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table = efsi.sweep(
        SCENE,
        {"solid.law.parameters.G": moduli, "refine": refine},
        client=client,
        summary=restitution,
        out=out / "restitution.csv",
    )
    table["cells_per_radius"] = table["refine"] * CELLS_PER_RADIUS
    finest = table[table["refine"] == max(refine)].set_index("solid.law.parameters.G")["e"]
    table["error"] = (table["e"] - table["solid.law.parameters.G"].map(finest)).abs()
    print(table[["solid.law.parameters.G", "cells_per_radius", "e", "contact_time", "error", "wall_time", "steps", "outcome"]].to_string(index=False))
    table.to_csv(out / "restitution.csv", index=False)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"wrote {out / 'restitution.csv'} (install matplotlib for the plots)")
        return
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    for cells, part in table.groupby("cells_per_radius"):
        left.semilogx(part["solid.law.parameters.G"], part["e"], "o-", label=f"{cells:.3g} cells/radius")
    left.set_xlabel("G (Pa)")
    left.set_ylabel("restitution coefficient e")
    left.legend()
    coarse = table[table["refine"] < max(refine)]
    for g, part in coarse.groupby("solid.law.parameters.G"):
        right.loglog(part["wall_time"], part["error"], "o-", label=f"G = {g:.3g} Pa")
    right.set_xlabel("wall time per run (s)")
    right.set_ylabel(f"|e − e at {max(refine) * CELLS_PER_RADIUS:.3g} cells/radius|")
    right.legend()
    fig.tight_layout()
    fig.savefig(out / "restitution.png", dpi=120)
    print(f"wrote {out / 'restitution.csv'} and {out / 'restitution.png'}")


if __name__ == "__main__":
    main()

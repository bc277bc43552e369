"""``curvenet info FILE``: describe a point file or a curvenet network."""

from __future__ import annotations

import numpy as np

from .options import add_common


def register(sub) -> None:
    p = sub.add_parser(
        "info",
        help="describe a point file or a network (.json)",
        description="Describe a point file (count, dimension, bounding box, nearest-neighbour spacing, "
                    "duplicated points) or a curvenet network (nodes, free ends, junctions, curves, "
                    "loops, total length, Betti numbers, the parameters used).",
    )
    p.add_argument("file", help="a point file or a curvenet .json network")
    p.add_argument("--columns", type=_columns, default=None, help="coordinate columns, e.g. 0,1,2 or x,y,z")
    add_common(p)
    p.set_defaults(func=run)


def _columns(text: str):
    return [c.strip() for c in text.split(",") if c.strip()]


def run(args) -> int:
    from ..io import extension, read_network, read_points

    if extension(args.file) == ".json":
        net = read_network(args.file)
        v = net.valence
        print(f"{args.file}: curve network, dimension {net.dimension}")
        print(f"  nodes {net.n_nodes} (free ends {int((v == 1).sum())}, junctions {int((v >= 3).sum())})")
        print(f"  curves {net.n_curves} (closed loops without node {sum(c.start is None for c in net.curves)})")
        print(f"  total length {net.lengths.sum():.6g}; Betti numbers b0={net.betti[0]} b1={net.betti[1]}")
        if net.parameters:
            from .progress import _fmt

            print("  parameters " + ", ".join(f"{k}={_fmt(v)}" for k, v in net.parameters.items()))
        return 0
    pts = read_points(args.file, columns=args.columns)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    print(f"{args.file}: {len(pts)} points, dimension {pts.shape[1]}")
    print(f"  bounding box min {np.array2string(lo, precision=6)} max {np.array2string(hi, precision=6)}")
    if len(pts) > 1:
        from ..neighbors import knn

        d, _ = knn(pts, 1)
        print(f"  nearest-neighbour spacing: median {np.median(d):.6g}, 90th percentile {np.percentile(d, 90):.6g}")
        print(f"  duplicated points: {len(pts) - len(np.unique(pts, axis=0))}")
    return 0

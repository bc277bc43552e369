"""``curvenet reconstruct INPUT -o OUTPUT``: the main job."""

from __future__ import annotations

import sys
from pathlib import Path

from . import add_common

#: CLI option -> method parameter name; only options the user gave are passed on.
_PARAMS = {
    "k": "k",
    "epsilon": "epsilon",
    "tau_s": "tau_s",
    "theta": "theta",
    "spacing": "spacing",
}


def register(sub) -> None:
    p = sub.add_parser(
        "reconstruct",
        help="reconstruct a curve network from a point file",
        description="Reconstruct a curve network from a point file and write it (format by extension).",
    )
    p.add_argument("input", help="point file (.xyz .txt .pts .csv .npy .ply .obj .las .laz)")
    p.add_argument("-o", "--output", action="append", default=[], metavar="OUTPUT",
                   help="output network file; format by extension (.json .obj .ply ...); repeatable")
    p.add_argument("--method", default="auto",
                   help="auto (default), paper (the founding paper's Algorithms 1 and 2), or another "
                        "registered method")
    g = p.add_argument_group("parameters of the paper's method")
    g.add_argument("--k", type=int, default=None, help="number of nearest neighbours for the PCA (eq. 1)")
    g.add_argument("--epsilon", type=float, default=None, help="point-variation threshold for candidate nodes (eq. 2)")
    g.add_argument("--tau-s", dest="tau_s", type=float, default=None, help="grouping distance of candidate nodes, in input units")
    g.add_argument("--theta", type=float, default=None, help="minimum angle at a curve point in degrees (100 to 150)")
    g2 = p.add_argument_group("parameters of the default method (estimated when not given)")
    g2.add_argument("--spacing", type=float, default=None, help="sampling spacing h in input units")
    g2.add_argument("--smooth", action="store_true", help="fit smoothing splines that end at the nodes")
    p.add_argument("--columns", type=lambda s: [c.strip() for c in s.split(",") if c.strip()], default=None,
                   help="coordinate columns of a text/array input, e.g. 0,1,2 or x,y,z")
    p.add_argument("--drop-nonfinite", action="store_true", help="drop points with NaN or infinite coordinates")
    add_common(p)
    p.set_defaults(func=run)


def collect_params(args) -> dict:
    params = {name: getattr(args, opt) for opt, name in _PARAMS.items() if getattr(args, opt, None) is not None}
    if getattr(args, "smooth", False):
        params["smooth"] = True
    return params


def run(args) -> int:
    from ..io import check_output_path, read_points, write_network
    from ..reconstruct import reconstruct

    outputs = list(args.output)
    for out in outputs:  # fail on a bad output before any work
        check_output_path(out, inputs=[args.input])
        from ..io import WRITERS, extension
        from ..errors import FormatError

        if extension(out) not in WRITERS:
            raise FormatError(f"{out}: unknown output extension {extension(out)!r}; writable: {', '.join(sorted(WRITERS))}")
    points = read_points(args.input, columns=args.columns, drop_nonfinite=args.drop_nonfinite)
    net = reconstruct(points, method=args.method, **collect_params(args))
    for out in outputs:
        write_network(net, out, inputs=[args.input])
    if not args.quiet:
        print_summary(net, Path(args.input).stem, outputs)
    return 0


def print_summary(net, name: str, outputs=(), file=None) -> None:
    """Print the result in the form of the paper's Table 1."""
    file = file or sys.stdout
    p = net.parameters
    t = net.stats.get("time", {}).get("total", float("nan"))

    def fmt(v):
        return "-" if v is None else (f"{v:.3g}" if isinstance(v, float) else str(v))

    head = ["Model", "N_n", "N_c", "N_d", "eps", "tau_S", "theta", "Time(s)"]
    row = [name, str(net.n_nodes), str(net.n_curves), str(net.stats.get("N_d", "-")),
           fmt(p.get("epsilon")), fmt(p.get("tau_s")), fmt(p.get("theta")), f"{t:.3f}"]
    w = [max(len(a), len(b)) for a, b in zip(head, row)]
    print("  ".join(a.ljust(n) for a, n in zip(head, w)), file=file)
    print("  ".join(b.ljust(n) for b, n in zip(row, w)), file=file)
    other = {k: v for k, v in p.items() if k not in ("epsilon", "tau_s", "theta")}
    if other:
        print("parameters: " + ", ".join(f"{k}={fmt(v)}" for k, v in other.items()), file=file)
    for out in outputs:
        print(f"wrote {out}", file=file)

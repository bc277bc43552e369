"""``curvenet reconstruct INPUT -o OUTPUT``: the main job."""

from __future__ import annotations

import sys
from pathlib import Path

from .options import add_common
from .cmd_render import add_picture_options
from .tiles import add_tile_options, dispatch

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
    p.add_argument("-p", "--param", action="append", default=[], metavar="NAME=VALUE", type=_param,
                   help="any parameter of the method, e.g. --param shell_outer=6 (repeatable); "
                        "see the README for each method's parameters")
    p.add_argument("--columns", type=lambda s: [c.strip() for c in s.split(",") if c.strip()], default=None,
                   help="coordinate columns of a text/array input, e.g. 0,1,2 or x,y,z")
    p.add_argument("--drop-nonfinite", action="store_true", help="drop points with NaN or infinite coordinates")
    p.add_argument("--png", metavar="FILE.png", default=None,
                   help="also draw the result (input points faint, curves coloured) as a PNG picture")
    p.add_argument("--html", metavar="FILE.html", default=None,
                   help="also write the interactive viewer (one offline HTML file)")
    p.add_argument("--surface", metavar="MESH", action="append", default=[],
                   help="also surface the network into a triangle mesh (.obj or .ply; extra surface); repeatable")
    add_picture_options(p, points=False)
    add_tile_options(p)
    add_common(p)
    p.set_defaults(func=run)


def _param(text: str):
    """Parse ``NAME=VALUE``; the value becomes a bool, int or float where it reads as one."""
    import argparse

    name, sep, value = text.partition("=")
    name = name.strip().replace("-", "_")
    if not sep or not name.isidentifier():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    v = value.strip()
    low = v.lower()
    if low in ("true", "yes", "on"):
        return name, True
    if low in ("false", "no", "off"):
        return name, False
    if low in ("none", "auto", ""):
        return name, None
    for conv in (int, float):
        try:
            return name, conv(v)
        except ValueError:
            pass
    return name, v


def collect_params(args) -> dict:
    params = {name: getattr(args, opt) for opt, name in _PARAMS.items() if getattr(args, opt, None) is not None}
    for name, value in getattr(args, "param", []):
        if value is not None:
            params[name] = value
    if getattr(args, "smooth", False):
        params["smooth"] = True
    return params


def run(args) -> int:
    from ..errors import FormatError
    from ..io import WRITERS, check_output_path, extension, read_points, write_network
    from ..reconstruct import reconstruct
    from .cmd_render import check_extension, picture_options
    from .progress import Stages, _fmt, print_summary

    if (tiled := dispatch(args)) is not None:
        return tiled
    outputs = list(args.output)
    inputs = [args.input]
    for out in outputs:  # fail on a bad output before any work
        check_output_path(out, inputs=inputs)
        if extension(out) not in WRITERS:
            raise FormatError(f"{out}: unknown output extension {extension(out)!r}; writable: {', '.join(sorted(WRITERS))}"
                              + " (pictures: --png FILE.png, --html FILE.html)")
    if args.png:
        check_extension(args.png, ".png", "the --png picture")
        check_output_path(args.png, inputs=inputs)
    if args.html:
        check_extension(args.html, ".html", "the --html viewer")
        check_output_path(args.html, inputs=inputs)
    if args.surface:
        from .cmd_surface import check_outputs

        check_outputs(args.surface, inputs=inputs)
    st = Stages(quiet=args.quiet, verbose=args.verbose)
    params = collect_params(args)
    st.info(f"input: {args.input}; method: {args.method}; given parameters: "
            + (", ".join(f"{k}={v}" for k, v in params.items()) or "none"))
    with st.stage(f"reading {Path(args.input).name}"):
        points = read_points(args.input, columns=args.columns, drop_nonfinite=args.drop_nonfinite)
    st.info(f"  {len(points)} points, dimension {points.shape[1]}")
    with st.stage(f"reconstructing ({args.method})"):
        net = reconstruct(points, method=args.method, **params)
    if st.verbose:
        st.info("  parameters used: " + ", ".join(f"{k}={_fmt(v)}" for k, v in net.parameters.items()))
        times = {k: v for k, v in net.stats.get("time", {}).items() if k != "total"}
        if times:
            st.info("  method stages: " + ", ".join(f"{k} {v:.3f} s" for k, v in times.items()))
    written = []
    n_files = len(outputs) + bool(args.png) + bool(args.html)
    with st.stage("writing", total=n_files) as bar:
        for out in outputs:
            write_network(net, out, inputs=inputs)
            written.append(out)
            bar.advance()
        if args.png:
            from ..plots.network_png import save_png

            save_png(net, args.png, inputs=inputs, points=points, **picture_options(args))
            written.append(args.png)
            bar.advance()
        if args.html:
            from ..viewer import save_html

            save_html(net, args.html, inputs=inputs, points=points)
            written.append(args.html)
            bar.advance()
    if args.surface:
        from .cmd_surface import summary, write_surface

        with st.stage("surfacing"):
            mesh, seconds = write_surface(net, args.surface, inputs=inputs)
        written.extend(args.surface)
    if not args.quiet:
        print_summary(net, Path(args.input).stem, written)
        if args.surface:
            print("surface: " + summary(mesh, seconds))
        if not written:
            print("curvenet: note: no output file given (-o, --png, --html), nothing written", file=sys.stderr)
    return 0

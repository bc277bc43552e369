"""``curvenet reconstruct INPUT -o OUTPUT``: the main job."""

from __future__ import annotations

import argparse
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
    "shell_inner": "shell_inner",
    "shell_outer": "shell_outer",
    "link": "link",
    "link_width": "link_width",
    "min_spur": "min_spur",
    "smoothing": "smoothing",
}

def register(sub) -> None:
    from ..reconstruct import DEFAULT_METHOD, METHODS

    p = sub.add_parser(
        "reconstruct",
        help="reconstruct a curve network from a point file",
        description="Reconstruct a curve network from a point file and write it (format by extension).",
    )
    p.add_argument("input", help="point file (.xyz .txt .pts .csv .tsv .npy .ply .pcd .obj .las .laz), "
                                 "or - for standard input (with --format)")
    p.add_argument("-o", "--output", action="append", default=[], metavar="OUTPUT",
                   help="output network file; format by extension (.json .obj .ply .vtu .svg .dxf .geojson "
                        ".swc ...; see curvenet formats); - for standard output (with --output-format); "
                        "repeatable")
    p.add_argument("--format", dest="input_format", default=None, metavar="EXT",
                   help="format of the input when it is - (standard input), e.g. xyz, csv, npy, ply")
    p.add_argument("--output-format", default="json", metavar="EXT",
                   help="format of the output - (standard output); default json")
    others = sorted(m for m in METHODS if m not in (DEFAULT_METHOD, "paper"))
    p.add_argument("--method", default=DEFAULT_METHOD, metavar="METHOD",
                   help=f"{DEFAULT_METHOD} (the default: parameters estimated from the points), paper (the founding "
                        f"paper's Algorithms 1 and 2), or {', '.join(others)} (a baseline); auto is {DEFAULT_METHOD}")
    g0 = p.add_argument_group("parameter of both methods")
    g0.add_argument("--k", type=int, default=None,
                    help="nearest neighbours: of the linked graph (robust, default 16), of the PCA of "
                         "equation (1) (paper, default 6)")
    g2 = p.add_argument_group(f"parameters of the default method, {DEFAULT_METHOD} (estimated when not given)")
    g2.add_argument("--spacing", type=float, default=None, help="sampling spacing h in input units (default: "
                    "estimated per point)")
    g2.add_argument("--shell-inner", type=float, default=None, metavar="SPACINGS",
                    help="inner radius of the junction-test shell, in spacings (default 2.5, widened with noise)")
    g2.add_argument("--shell-outer", type=float, default=None, metavar="SPACINGS",
                    help="outer radius of the junction-test shell, in spacings (default 5.5, widened with noise)")
    g2.add_argument("--link", type=float, default=None, metavar="SPACINGS",
                    help="longest link between two points, in spacings (default 2.5)")
    g2.add_argument("--link-width", type=float, default=None, metavar="SPACINGS",
                    help="a link stays within this many spacings of a tangent line at one of its ends "
                         "(default 1.0, widened with noise)")
    g2.add_argument("--min-spur", type=float, default=None, metavar="SPACINGS",
                    help="drop spurs and isolated pieces shorter than this many spacings (default 3)")
    g2.add_argument("--fit", action=argparse.BooleanOptionalAction, default=None,
                    help="fit each curve by a smoothing spline ending at its nodes (each sample moved onto it; "
                         "DXF output as splines); default: on where the points are noisy, off on noise-free points")
    g2.add_argument("--smoothing", type=float, default=None, metavar="SPACINGS",
                    help="width of the fit's smoothing kernel, in spacings (default: chosen per sample from the "
                         "noise, 1.5 to 4)")
    g = p.add_argument_group("parameters of the paper's method (--method paper)")
    g.add_argument("--epsilon", type=float, default=None,
                   help="point-variation threshold for candidate nodes, eq. 2 (default 1e-3 in 3D, 2e-2 in 2D)")
    g.add_argument("--tau-s", dest="tau_s", type=float, default=None,
                   help="grouping distance of candidate nodes, in input units (default 1.5 k spacings: 9)")
    g.add_argument("--theta", type=float, default=None,
                   help="minimum angle at a curve point in degrees, 100 to 150 (default 120)")
    p.add_argument("-p", "--param", action="append", default=[], metavar="NAME=VALUE", type=_param,
                   help="any other parameter of the method by name, e.g. --param use_numba=false (repeatable)")
    p.add_argument("--columns", type=lambda s: [c.strip() for c in s.split(",") if c.strip()], default=None,
                   help="coordinate columns of a text/array input, e.g. 0,1,2 or x,y,z (other columns, "
                        "text ones included, are skipped)")
    p.add_argument("--drop-nonfinite", action="store_true", help="drop points with NaN or infinite coordinates")
    w = p.add_argument_group("output options")
    w.add_argument("--view", choices=("top", "front", "side", "iso"), default=None,
                   help="view of a 3D network in an .svg output (default top)")
    w.add_argument("--units", default=None, metavar="UNIT",
                   help="unit of the coordinates in a .dxf output: mm, cm, m, in, ft... (default: unitless)")
    w.add_argument("--labels", metavar="FILE.csv|.npy", default=None,
                   help="also write, for each input point, its curve id or node id (-1: noise)")
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


def _output_roles(args) -> list:
    """Every output of the run with what it holds, for :func:`curvenet.io.check_outputs`."""
    from ..io import extension

    from ..io.stdio import STDIO

    roles = [(o, f"the network as {extension(o) or 'a file'}") for o in args.output if o != STDIO]
    roles += [(m, "the --surface mesh") for m in args.surface]
    roles += [(p, what) for p, what in ((args.png, "the --png picture"), (args.html, "the --html viewer"),
                                        (args.labels, "the --labels point labels")) if p]
    return roles


def collect_params(args) -> dict:
    params = {name: getattr(args, opt) for opt, name in _PARAMS.items() if getattr(args, opt, None) is not None}
    for name, value in getattr(args, "param", []):
        if value is not None:
            params[name] = value
    if getattr(args, "fit", None) is not None:
        params["fit"] = bool(args.fit)
    return params


def writer_options(args, ext: str) -> dict:
    """Options of the writer of ``ext`` given on the command line (``--view``, ``--units``)."""
    if ext == ".svg" and getattr(args, "view", None):
        return {"projection": args.view}
    if ext == ".dxf" and getattr(args, "units", None):
        return {"units": args.units}
    return {}


def run(args) -> int:
    from ..errors import FormatError
    from ..io import WRITERS, check_output_path, check_outputs, extension, read_points, write_network
    from ..io.stdio import STDIO, read_points_stdin, stdout_extension, write_stdout
    from ..reconstruct import DEFAULT_METHOD, compile_pending, reconstruct
    from ..validate import reconstructable
    from .cmd_render import check_extension, picture_options
    from .hints import empty_network_hint
    from .progress import Stages, _fmt, print_summary

    if (tiled := dispatch(args)) is not None:
        return tiled
    outputs = list(args.output)
    from_stdin = args.input == STDIO
    inputs = [] if from_stdin else [args.input]
    if outputs.count(STDIO) > 1:
        raise FormatError("standard output (-o -) can be given once")
    for out in outputs:  # fail on a bad output before any work
        ext = stdout_extension(args.output_format) if out == STDIO else extension(out)
        if out != STDIO:
            check_output_path(out, inputs=inputs)
        if ext not in WRITERS:
            raise FormatError(f"{out}: unknown output extension {ext!r}; writable: {', '.join(sorted(WRITERS))}"
                              + " (pictures: --png FILE.png, --html FILE.html)")
    if args.png:
        from .cmd_render import check_picture_options

        check_picture_options(args)
    for flag, path, ext, what in (("png", args.png, ".png", "the --png picture"),
                                  ("html", args.html, ".html", "the --html viewer")):
        if path:
            check_extension(path, ext, what)
            check_output_path(path, inputs=inputs)
    if args.labels:
        if extension(args.labels) not in (".csv", ".npy"):
            raise FormatError(f"{args.labels}: the --labels file must end in .csv or .npy")
        check_output_path(args.labels, inputs=inputs)
    if args.surface:
        from .cmd_surface import check_outputs as check_meshes

        check_meshes(args.surface, inputs=inputs)
    check_outputs(_output_roles(args), inputs=inputs)  # no file given twice for two contents
    to_stdout = STDIO in outputs
    n_files = len(outputs) + bool(args.png) + bool(args.html) + bool(args.labels)
    st = Stages(quiet=args.quiet, verbose=args.verbose, stages=3 + bool(args.surface))
    params = collect_params(args)
    method = DEFAULT_METHOD if args.method == "auto" else args.method
    name = "<stdin>" if from_stdin else Path(args.input).name
    st.info(f"input: {name}; method: {method}; given parameters: "
            + (", ".join(f"{k}={v}" for k, v in params.items()) or "none"))
    with st.stage(f"reading {name}"):
        if from_stdin:
            points = read_points_stdin(args.input_format, columns=args.columns, drop_nonfinite=args.drop_nonfinite)
        else:
            points = read_points(args.input, columns=args.columns, drop_nonfinite=args.drop_nonfinite)
    st.info(f"  {len(points)} points, dimension {points.shape[1]}")
    reconstructable(points, name="<stdin>" if from_stdin else args.input)  # too few or identical points: the file named
    with st.stage(f"reconstructing ({method})", detail=f"{len(points):,} points",
                  compiling=compile_pending(len(points), method=method)) as bar:
        net = reconstruct(points, method=method, on_stage=bar.method_stage, **params)
    hint = empty_network_hint(net)
    if hint and not args.quiet:
        print(f"curvenet: warning: {hint}", file=sys.stderr)
    if st.verbose:
        st.info("  parameters used: " + ", ".join(f"{k}={_fmt(v)}" for k, v in net.parameters.items()))
        times = {k: v for k, v in net.stats.get("time", {}).items() if k != "total"}
        if times:
            st.info("  method stages: " + ", ".join(f"{k} {v:.3f} s" for k, v in times.items()))
    written = []
    stdout_data = None  # written last, once every other output is (no network on standard output after a failure)
    with st.stage("writing", total=n_files, detail=f"{n_files} file(s)") as bar:
        for out in outputs:
            if out == STDIO:
                ext = stdout_extension(args.output_format)
                stdout_data = WRITERS[ext][0](net, **writer_options(args, ext))
            else:
                write_network(net, out, inputs=inputs, **writer_options(args, extension(out)))
                written.append(out)
            bar.advance()
        if args.labels:
            from ..io import atomic_write
            from ..io.labels import labels_to_csv, labels_to_npy, point_labels

            lab = point_labels(net, points)
            data = labels_to_csv(lab) if extension(args.labels) == ".csv" else labels_to_npy(lab)
            atomic_write(args.labels, data, inputs=inputs)
            written.append(args.labels)
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
    if stdout_data is not None:
        write_stdout(stdout_data)
    if not args.quiet:
        report = sys.stderr if to_stdout else sys.stdout  # standard output carries the network
        print_summary(net, "stdin" if from_stdin else Path(args.input).stem, written, file=report)
        if args.surface:
            print("surface: " + summary(mesh, seconds), file=report)
        if not written and not to_stdout:
            print("curvenet: note: no output file given (-o, --png, --html), nothing written", file=sys.stderr)
    return 0

"""``curvenet render NETWORK.json -o OUT.png``: a PNG picture of a network."""

from __future__ import annotations

from .options import add_common


def register(sub) -> None:
    p = sub.add_parser(
        "render",
        help="draw a network (.json) as a PNG picture",
        description="Draw a curve network as a PNG picture: input points faint, each curve in its own "
                    "colour, junctions and free ends marked (3D networks from a fixed view).",
    )
    p.add_argument("network", help="a curvenet .json network (from curvenet reconstruct)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.png", help="the PNG file to write")
    add_picture_options(p)
    add_common(p)
    p.set_defaults(func=run)


def add_picture_options(p, *, points: bool = True) -> None:
    """Options shared by ``render`` and ``reconstruct --png``."""
    g = p.add_argument_group("picture")
    if points:
        g.add_argument("--points", metavar="INPUT", default=None,
                       help="point file to draw faint under the network (usually the input)")
        g.add_argument("--columns", type=lambda s: [c.strip() for c in s.split(",") if c.strip()], default=None,
                       help="coordinate columns of the --points file, e.g. 0,1,2 or x,y,z")
    g.add_argument("--elev", type=float, default=None, help="3D view elevation in degrees (default 25)")
    g.add_argument("--azim", type=float, default=None, help="3D view azimuth in degrees (default -60)")
    g.add_argument("--dpi", type=int, default=120, help="pixels per inch (default 120; the picture is 8 in wide)")
    g.add_argument("--title", default=None, help="picture title (default: the counts of nodes and curves)")


def check_picture_options(args) -> None:
    """Check ``--dpi``, ``--elev`` and ``--azim`` before any work (at the default 8 inch width;
    the height, which follows a 2D network's shape, is checked again when drawing)."""
    from ..plots.network_png import check_picture

    opts = picture_options(args)
    check_picture(width=8.0, height=1.0, dpi=opts["dpi"], elev=opts["elev"], azim=opts["azim"])


def picture_options(args) -> dict:
    from ..plots.network_png import DEFAULT_AZIM, DEFAULT_ELEV

    opts = {
        "elev": DEFAULT_ELEV if args.elev is None else args.elev,
        "azim": DEFAULT_AZIM if args.azim is None else args.azim,
        "dpi": args.dpi,
    }
    if getattr(args, "title", None) is not None:
        opts["title"] = args.title
    return opts


def check_extension(path, ext: str, what: str) -> None:
    from ..errors import FormatError
    from ..io import extension

    if extension(path) != ext:
        raise FormatError(f"{path}: {what} must have the extension {ext}")


def open_network(args):
    """Shared by ``render`` and ``view``: check the output, read the network and the optional points.

    Returns ``(stages, network, points or None, input paths)``.
    """
    from ..io import check_output_path, read_network, read_points
    from .progress import Stages

    inputs = [args.network] + ([args.points] if args.points else [])
    check_output_path(args.output, inputs=inputs)
    st = Stages(quiet=args.quiet, verbose=args.verbose)
    with st.stage("reading"):
        net = read_network(args.network)
        pts = read_points(args.points, columns=args.columns) if args.points else None
    st.info(f"network: {net!r}" + ("" if pts is None else f"; {len(pts)} points"))
    return st, net, pts, inputs


def run(args) -> int:
    from ..plots.network_png import save_png

    check_extension(args.output, ".png", "the picture")
    check_picture_options(args)
    st, net, pts, inputs = open_network(args)
    with st.stage("drawing"):
        save_png(net, args.output, inputs=inputs, points=pts, **picture_options(args))
    if not args.quiet:
        print(f"wrote {args.output}")
    return 0

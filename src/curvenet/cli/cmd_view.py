"""``curvenet view NETWORK.json -o OUT.html``: an interactive viewer in one offline HTML file."""

from __future__ import annotations

import sys

from .options import add_common


def register(sub) -> None:
    p = sub.add_parser(
        "view",
        help="write an interactive viewer (one self-contained offline .html file)",
        description="Write an interactive 3D/2D viewer of a network as one HTML file with its JavaScript "
                    "embedded (works offline): rotate and zoom, toggle nodes and points, hover for ids.",
    )
    p.add_argument("network", help="a curvenet .json network (from curvenet reconstruct)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.html", help="the HTML file to write")
    p.add_argument("--points", metavar="INPUT", default=None, help="point file to show (usually the input)")
    p.add_argument("--columns", type=lambda s: [c.strip() for c in s.split(",") if c.strip()], default=None,
                   help="coordinate columns of the --points file, e.g. 0,1,2 or x,y,z")
    p.add_argument("--max-points", type=int, default=None,
                   help="show at most this many input points (default 200000; thinned independently of order)")
    p.add_argument("--max-mb", type=float, default=None,
                   help="keep the page under this many megabytes by thinning points, then curve samples "
                        "(default 20; curve ends always kept; 0: no limit)")
    p.add_argument("--title", default=None, help="page title")
    add_common(p)
    p.set_defaults(func=run)


def viewer_options(args) -> dict:
    from ..viewer import MAX_VIEWER_POINTS

    from ..viewer import MAX_VIEWER_BYTES

    opts = {"max_points": MAX_VIEWER_POINTS if args.max_points is None else args.max_points}
    mb = getattr(args, "max_mb", None)
    opts["max_bytes"] = MAX_VIEWER_BYTES if mb is None else (None if mb == 0 else int(mb * 1e6))
    if getattr(args, "title", None) is not None:
        opts["title"] = args.title
    return opts


def run(args) -> int:
    from ..errors import InputError
    from ..viewer import save_html
    from .cmd_render import check_extension, open_network

    check_extension(args.output, ".html", "the viewer")
    if args.max_points is not None and args.max_points < 0:
        raise InputError(f"--max-points must be >= 0, got {args.max_points}")
    from ..viewer import MIN_VIEWER_BYTES

    if args.max_mb is not None and not (args.max_mb == 0 or args.max_mb * 1e6 >= MIN_VIEWER_BYTES):
        raise InputError(f"--max-mb must be at least {MIN_VIEWER_BYTES / 1e6:g} (plotly's JavaScript alone "
                         f"takes 4.8 MB) or 0 (no limit), got {args.max_mb:g}")
    st, net, pts, inputs = open_network(args)
    opts = viewer_options(args)
    with st.stage("writing viewer"):
        save_html(net, args.output, inputs=inputs, points=pts, **opts)
    if not args.quiet:
        from ..viewer import plan_display

        note = plan_display(net, pts, max_points=opts["max_points"], max_bytes=opts["max_bytes"]).message()
        if note:
            print(f"curvenet: note: {note}", file=sys.stderr)
        print(f"wrote {args.output}")
    return 0

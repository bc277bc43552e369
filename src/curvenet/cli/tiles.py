"""``curvenet reconstruct ... --tiles SIZE|auto``: the tiled run on Dask (extra ``dask``).

The options are added to ``curvenet reconstruct`` by :func:`add_tile_options`; its ``run``
hands over to :func:`dispatch` first, which runs the tiled reconstruction when ``--tiles`` is
given and returns None otherwise (then nothing changes).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["add_tile_options", "dispatch"]


def _side(text: str):
    if text.strip().lower() == "auto":
        return "auto"
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a tile side in input units or 'auto', got {text!r}") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"the tile side must be a positive number, got {text!r}")
    return v


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def add_tile_options(p: argparse.ArgumentParser) -> None:
    """The further inputs and the options of the tiled run."""
    p.add_argument("more_inputs", nargs="*", metavar="INPUT",
                   help="more point files, globs or folders of tiles (with --tiles: one cloud)")
    g = p.add_argument_group("tiled run on Dask (extra dask; see docs/distributed.md)")
    g.add_argument("--tiles", type=_side, default=None, metavar="SIZE|auto",
                   help="reconstruct tile by tile: the tile side in input units, or auto")
    g.add_argument("--halo", type=_positive, default=None, metavar="H",
                   help="halo around each tile in input units (default: from the method's reach)")
    g.add_argument("--scheduler", default="processes", metavar="processes|threads|ADDRESS",
                   help="a local cluster of processes (default) or threads, or a running scheduler's address")
    g.add_argument("--workers", type=int, default=None, metavar="N", help="local workers (default: the CPU count)")
    g.add_argument("--scratch", default=None, metavar="DIR",
                   help="folder for the temporary tile store (default: the system's temporary folder)")


def dispatch(args) -> int | None:
    """Run the tiled reconstruction when ``--tiles`` was given (exit code), else None.

    Raises
    ------
    InputError
        Several inputs or tile options without ``--tiles``; options the tiled run cannot honour.
    """
    from ..errors import InputError

    if args.tiles is None:
        given = [o for o, v in (("--halo", args.halo), ("--workers", args.workers), ("--scratch", args.scratch))
                 if v is not None]
        if args.more_inputs or given or args.scheduler != "processes":
            what = "several inputs" if args.more_inputs else ", ".join(given) or "--scheduler"
            raise InputError(f"{what} need --tiles SIZE|auto (the tiled run)")
        return None
    if args.method not in ("auto", "robust"):
        raise InputError(f"--tiles runs the default method only, got --method {args.method}")
    if _method_parameters(args):
        raise InputError("--tiles runs the default method with its estimated parameters; "
                         "method parameters (--spacing, --param, --fit ...) are not taken")
    for opt in ("png", "html"):
        if getattr(args, opt):
            raise InputError(f"--{opt} draws the input points, which a tiled run never holds; "
                             "draw the network with curvenet render")
    return _run(args)


#: The method-parameter options of ``curvenet reconstruct`` (attribute names).
_METHOD_OPTIONS = ("k", "epsilon", "tau_s", "theta", "spacing")


def _method_parameters(args) -> bool:
    """Whether any method parameter was given (options, ``--param``, ``--fit``)."""
    return (any(getattr(args, o, None) is not None for o in _METHOD_OPTIONS)
            or any(v is not None for _, v in getattr(args, "param", [])) or getattr(args, "fit", None) is not None)


def _run(args) -> int:
    from ..distributed import make_client, tiled_network
    from ..distributed.inputs import expand_inputs
    from ..errors import FormatError
    from ..io import WRITERS, check_output_path, extension, write_network
    from ..io.streamed import STREAMED, write_network_streamed
    from .progress import COMPILE_NOTE, print_summary

    inputs = [str(f) for f in expand_inputs([args.input, *args.more_inputs])]
    for out in args.output:  # fail on a bad output before any work
        check_output_path(out, inputs=inputs)
        if extension(out) not in WRITERS:
            raise FormatError(f"{out}: unknown output extension {extension(out)!r}; writable: {', '.join(sorted(WRITERS))}")
    if args.surface:
        from .cmd_surface import check_outputs

        check_outputs(args.surface, inputs=inputs)
    show = not args.quiet and sys.stderr.isatty()
    client = make_client(args.scheduler, args.workers, dashboard=not args.quiet)
    try:
        if not args.quiet and client.dashboard_link:
            print(f"curvenet: Dask dashboard: {client.dashboard_link}", file=sys.stderr)
        note = None if args.quiet else (lambda: print(f"curvenet: {COMPILE_NOTE}", file=sys.stderr))
        with tiled_network(inputs, tiles=args.tiles, halo=args.halo, client=client, scratch=args.scratch,
                           columns=args.columns, drop_nonfinite=args.drop_nonfinite, progress=show,
                           on_compile=note) as stored:
            # .json and .ply are written one curve at a time from the scratch store (the client
            # never holds the points); other formats and the surface need the network in memory
            whole = None
            written = []
            for out in args.output:
                if extension(out) in STREAMED:
                    write_network_streamed(stored, out, inputs=inputs)
                else:
                    whole = stored.network() if whole is None else whole
                    write_network(whole, out, inputs=inputs)
                written.append(out)
            if args.surface:
                from .cmd_surface import summary, write_surface

                whole = stored.network() if whole is None else whole
                mesh, seconds = write_surface(whole, args.surface, inputs=inputs)
                written.extend(args.surface)
    finally:
        cluster = getattr(client, "cluster", None) if args.scheduler in ("processes", "threads") else None
        client.close()
        if cluster is not None:
            cluster.close()
    if not args.quiet:
        if args.verbose:
            tm = stored.stats.get("time", {})
            print("tiled run: " + ", ".join(f"{k} {v:.2f} s" for k, v in tm.items()), file=sys.stderr)
        print_summary(stored, Path(inputs[0]).stem, written)
        if args.surface:
            print("surface: " + summary(mesh, seconds))
        if not written:
            print("curvenet: note: no output file given (-o), nothing written", file=sys.stderr)
    return 0

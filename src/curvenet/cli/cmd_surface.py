"""``curvenet surface NETWORK.json -o MESH.obj|ply``: surface a curve network into a mesh."""

from __future__ import annotations

import time

from .options import add_common


def register(sub) -> None:
    p = sub.add_parser(
        "surface",
        help="surface a curve network (.json) into a triangle mesh (.obj or .ply)",
        description="Find the patches bounded by the network's curves, fill each with a faired "
        "triangle mesh, and write the mesh (format by extension).",
    )
    p.add_argument("network", help="a curvenet network (.json)")
    p.add_argument("-o", "--output", action="append", default=[], metavar="MESH",
                   help="output mesh (.obj or .ply); repeatable")
    p.add_argument("--target-edge", type=float, default=None,
                   help="edge length inside the patches (default: from the curve point spacing)")
    p.add_argument("--no-fair", action="store_true",
                   help="flat harmonic membranes instead of patches shaped by the curvature of their curves")
    p.add_argument("--open", metavar="IDS", type=curve_ids, default=(),
                   help="curves that bound one patch at most: the rims of openings left open (a vase's "
                        "mouth), e.g. 24,25 or 24-27; ids as the viewer shows them (from 0). Without it "
                        "every ring of curves that can be capped is capped")
    p.add_argument("--png", metavar="FILE.png", default=None, help="also draw the surface as a PNG picture")
    add_common(p)
    p.set_defaults(func=run)


def curve_ids(text: str) -> tuple[int, ...]:
    """The curve ids of ``--open``: comma-separated ids and ranges (``24,25`` or ``24-27``)."""
    import argparse

    out = []
    for part in text.split(","):
        part = part.strip()
        a, sep, b = part.partition("-")
        try:
            lo = int(a)
            hi = int(b) if sep else lo
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a list of curve ids: {text!r} (e.g. 24,25 or 24-27)") from None
        if lo < 0 or hi < lo:
            raise argparse.ArgumentTypeError(f"not a list of curve ids: {text!r} (e.g. 24,25 or 24-27)")
        out.extend(range(lo, hi + 1))
    return tuple(out)


def check_outputs(outputs, *, png=None, inputs=()) -> None:
    """Fail early on mesh outputs that cannot be written (bad extension, missing folder...)."""
    from ..errors import FormatError
    from ..io import check_output_path, extension
    from ..io import check_outputs as check_all
    from ..io.mesh import MESH_WRITERS

    for out in outputs:
        check_output_path(out, inputs=inputs)
        if extension(out) not in MESH_WRITERS:
            raise FormatError(f"{out}: unknown mesh extension {extension(out)!r}; writable: "
                              + ", ".join(sorted(MESH_WRITERS)))
    if png:
        if extension(png) != ".png":
            raise FormatError(f"{png}: the --png picture must end in .png")
        check_output_path(png, inputs=inputs)
    check_all([(o, f"the mesh as {extension(o)}") for o in outputs] + ([(png, "the --png picture")] if png else []),
              inputs=inputs)


def write_surface(net, outputs, *, png=None, inputs=(), target_edge=None, fair=True, open_curves=()):
    """Surface ``net`` and write the mesh files (format by extension) and an optional PNG.

    For ``curvenet surface`` and for ``curvenet reconstruct --surface MESH``: call
    :func:`check_outputs` before the work, then this. Returns ``(mesh, seconds)``. A failed
    check of the mesh is printed as one ``curvenet: warning:`` line on stderr naming the
    patches (the mesh is still written).
    """
    import sys
    import warnings

    from ..io import atomic_write, extension
    from ..io.mesh import MESH_WRITERS
    from ..surfacing import SurfaceCheckWarning, surface

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SurfaceCheckWarning)
        mesh = surface(net, target_edge=target_edge, fair=fair, open_curves=open_curves)
    dt = time.perf_counter() - t0
    for w in caught:
        if issubclass(w.category, SurfaceCheckWarning):
            print(f"curvenet: warning: {w.message}", file=sys.stderr)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    for out in outputs:
        atomic_write(out, MESH_WRITERS[extension(out)][0](mesh), inputs=inputs)
    if png:
        from ..plots.surface_png import render_surface_png

        atomic_write(png, render_surface_png(mesh, network=net), inputs=inputs)
    return mesh, dt


def summary(mesh, seconds: float) -> str:
    """Patches, vertices, triangles, Euler characteristic, closed or not, time; then, on a second
    line, the checks (self-intersecting faces, non-manifold edges, boundary loops, genus,
    overlapping patch pairs) when the mesh was checked."""
    closed = len(mesh.triangles) > 0 and len(mesh.boundary_edges()) == 0
    line = (f"{mesh.n_patches} patches, {len(mesh.vertices)} vertices, {len(mesh.triangles)} triangles, "
            f"Euler characteristic {mesh.euler_characteristic}{', closed' if closed else ''} ({seconds:.2f} s)")
    if mesh.checks is not None:
        line += "\n  checks: " + mesh.checks.summary()
    return line


def run(args) -> int:
    from ..io import read_network

    inputs = [args.network]
    check_outputs(args.output, png=args.png, inputs=inputs)
    net = read_network(args.network)
    mesh, dt = write_surface(net, args.output, png=args.png, inputs=inputs,
                             target_edge=args.target_edge, fair=not args.no_fair, open_curves=args.open)
    if not args.quiet:
        print(f"{args.network}: {summary(mesh, dt)}")
        if args.verbose:
            print("  time: " + ", ".join(f"{k} {v:.3f} s" for k, v in mesh.stats["time"].items())
                  + f"; candidate cycles {mesh.stats['candidates']}; target edge {mesh.stats['target_edge']:.4g}")
        for out in args.output + ([args.png] if args.png else []):
            print(f"  wrote {out}")
    return 0

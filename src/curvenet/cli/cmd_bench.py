"""``curvenet bench``: run the benchmark and write its report (Markdown, JSON, figures)."""

from __future__ import annotations

import sys

from .options import add_common


def register(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="measure the methods on ground-truth networks (docs/benchmarks.md)",
        description=(
            "Run methods x synthetic models x sampling conditions (and the CASSIE sketches when the "
            "dataset is found), score them against the ground truth and write benchmarks.md, "
            "benchmarks.json and figures (img/) into --out. `curvenet bench --out docs` regenerates "
            "docs/benchmarks.md."
        ),
    )
    p.add_argument("--quick", action="store_true", help="two small models, small tuning grid (under a minute)")
    p.add_argument("--methods", nargs="+", metavar="M", help="methods to run (default: all, and paper-tuned)")
    p.add_argument("--models", nargs="+", metavar="NAME", help="synthetic models (default: all)")
    p.add_argument("--conditions", nargs="+", metavar="C",
                   help="sampling conditions: clean, 'noise 0.2h', 'density x3', 'noise 0.3h + density x3' "
                   "(the default four), 'outliers 2%%', 'noise 0.1h'")
    p.add_argument("--tune-each", action="store_true",
                   help="tune paper-tuned on every condition (default: on the clean sampling only)")
    p.add_argument("--no-cassie", action="store_true", help="skip the CASSIE real-data table")
    p.add_argument("--no-surfacing", action="store_true",
                   help="skip the surfacing section (it needs the surface extra; skipped without it)")
    p.add_argument("--spread-seeds", type=int, default=8, metavar="K",
                   help="also score robust on K samplings of every model and condition (default 8; 0: skip)")
    p.add_argument("--no-figures", action="store_true", help="skip the figures (no matplotlib needed)")
    p.add_argument("--out", default=".", help="output folder (default: the current folder)")
    add_common(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from ..bench import run_all, summarize

    if args.spread_seeds < 0:
        from ..errors import InputError

        raise InputError(f"--spread-seeds must be 0 or more, got {args.spread_seeds}")
    quiet = getattr(args, "quiet", False)
    progress = None if quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    cmd = ["curvenet bench"]
    if args.quick:
        cmd.append("--quick")
    for opt in ("methods", "models", "conditions"):
        if getattr(args, opt):
            cmd.append(f"--{opt} " + " ".join(repr(v) if " " in v else v for v in getattr(args, opt)))
    cmd += ["--tune-each"] * args.tune_each + ["--no-cassie"] * args.no_cassie + ["--no-surfacing"] * args.no_surfacing
    cmd += ["--no-figures"] * args.no_figures
    cmd += [f"--spread-seeds {args.spread_seeds}"] * (args.spread_seeds != 8) + [f"--out {args.out}"]
    res = run_all(
        args.out,
        quick=args.quick,
        methods=args.methods,
        models=args.models,
        conditions=args.conditions,
        cassie=not args.no_cassie,
        figures=not args.no_figures,
        tune_on="each" if args.tune_each else "clean",
        progress=progress if getattr(args, "verbose", False) else None,
        command=" ".join(cmd),
        spread_seeds=args.spread_seeds,
        surfacing=not args.no_surfacing,
    )
    if not quiet:
        for s in summarize(res["rows"]):
            print(
                f"{s['dataset']:9s} {s['condition']:24s} {s['method']:12s} node F1 {s['node_f1']:.3f}  "
                f"curve F1 {s['curve_f1']:.3f}  exact {s['exact_topology'] * 100:5.1f}%  "
                f"offset {s['node_offset_h']:.2f}h  ({s['n']} models, {s['errors']} errors, {s['time']:.1f}s)"
            )
        for f in res["files"]:
            print(f"wrote {f}")
    return 0

"""Surface the CASSIE sketches and the synthetic models and check every mesh (issue 24).

Usage::

    python benchmarks/surface_eval.py [--set free,study,synth,surfaces] [--names hat,teapot]
                                      [--network reconstructed|truth] [--cache DIR] [--quick]
                                      [--markdown PATH]

For each sketch or model: the network (by default reconstructed by the default method from the
true curves sampled at 2 mm for CASSIE, as :func:`curvenet.bench.run_cassie` does, and at the
model's reference spacing for the synthetic models; ``--network truth``: the true network), then
:func:`curvenet.surface` and :func:`curvenet.surfacing.check_mesh`. Prints one line per model:
nodes and curves, patches, triangles, self-intersecting faces (MeshLab's test confirmed by
libigl's), non-manifold edges, boundary loops, genus, overlapping patch pairs, seconds (surfacing
and checks); for the models drawn on a known surface (sphere, torus, mug), the mean and largest
distance of the mesh vertices to it in units of the model's spacing h; then the totals, and the
mug cylinder's smallest and largest radius at mid-height off its curves (0.50 true). ``--quick`` runs a few models only (for CI).
``--cache DIR`` keeps the reconstructed networks between runs (pickles keyed by name).

The set ``surfaces`` holds the networks drawn on known surfaces (:mod:`curvenet.synth.surfaces`:
sphere, torus, capped cylinder, saddle, box with a filleted edge, vase), sampled at their
spacing h and reconstructed like the others: for each, the patches and boundary loops found
against those of the true surface, and the distances in units of h both ways: mesh vertices to
the true surface (mean and largest) and points of the true surface to the mesh (libigl's
point-to-mesh distance; the largest of the two largest is the Hausdorff distance). Times are
seconds on a shared machine; ``ref`` is the k=16 cKDTree query of the network's own curve points
measured just before each model, the ratio ``time / ref`` being the figure to compare between
runs. ``--markdown PATH`` writes the table of every model run (docs/surfacing-table.md).

A model of ``surfaces`` with an opening (the vase's mouth, the saddle's border) is surfaced a
second time with its opening given, as a designer would name it (``surface(...,
open_curves=...)``, ``curvenet surface --open``): the reconstructed curves that lie along the true
boundary curves (:attr:`curvenet.synth.surfaces.SurfaceModel.open_curves`, every point within
:data:`curvenet.surfacing.evaluation.OPEN_MATCH` h of them); its row is the model's name with "(opening given)".
"""

from __future__ import annotations

import argparse
import pickle
import sys
from pathlib import Path

import numpy as np

from curvenet import synth
from curvenet.bench import SURFACING_CASSIE_H, run_seed
from curvenet.reconstruct import reconstruct
from curvenet.surfacing.evaluation import open_curve_ids, surface_row
from curvenet.synth import cassie, surfaces

#: CASSIE sampling spacing (metres), as in :func:`curvenet.bench.run_cassie`.
CASSIE_H = SURFACING_CASSIE_H
#: Models of ``--quick``.
QUICK = {"synth": ["cube", "mug"], "free": ["architecture-2"], "study": [], "surfaces": ["saddle"]}
#: Half-height of the band around the mug's mid-height where the radius is measured.
MUG_BAND = 0.05


def networks(kind: str, names, source: str, cache: Path | None):
    """Yield ``(name, network)`` for one set of models."""
    if kind == "synth":
        all_names = synth.model_names()
    elif kind == "surfaces":
        all_names = surfaces.surface_model_names()
    elif kind == "free":
        all_names = list(cassie.FREE_CREATIONS) if cassie.available() else []
    else:
        all_names = cassie.study_sketches()
    for name in all_names:
        if names and name not in names:
            continue
        if kind in ("synth", "surfaces"):
            truth = synth.model(name) if kind == "synth" else surfaces.surface_model(name).network
            h, rng = synth.h_of(truth), run_seed(name, "clean")
        else:
            truth = cassie.load(name)
            h, rng = CASSIE_H, run_seed("cassie", name)
        if source == "truth":
            yield name, truth
            continue
        path = cache / f"{kind}-{name}.pkl" if cache else None
        if path is not None and path.exists():
            yield name, pickle.loads(path.read_bytes())
            continue
        pts, _ = synth.sample(truth, h=h, rng=rng)
        net = reconstruct(pts)
        if path is not None:
            path.write_bytes(pickle.dumps(net))
        yield name, net


def mug_radius(mesh) -> tuple[float, float]:
    """Smallest and largest distance to the axis of the mug's cylinder at mid-height, off its curves.

    Vertices within :data:`MUG_BAND` of mid-height, the handle's plane and the curve points (on
    the cylinder by construction) left out.
    """
    V = mesh.vertices
    on_curve = np.zeros(len(V), dtype=bool)
    for ids in mesh.curve_vertices:
        if ids is not None:
            on_curve[ids] = True
    band = (np.abs(V[:, 2] - 0.5) < MUG_BAND) & ~on_curve
    handle = (np.abs(V[:, 1]) < 1e-9) & (V[:, 0] > 0.5 - 1e-9)
    r = np.hypot(V[band & ~handle, 0], V[band & ~handle, 1])
    return float(r.min()), float(r.max())


def _cylinder_with_caps(p):
    """Distance to the mug's cylinder (radius 0.5, height 1) with its two caps."""
    rho = np.hypot(p[:, 0], p[:, 1])
    side = np.where((p[:, 2] >= 0) & (p[:, 2] <= 1), np.abs(rho - 0.5), np.inf)
    cap = np.where(rho <= 0.5, np.minimum(np.abs(p[:, 2]), np.abs(p[:, 2] - 1)), np.inf)
    return np.minimum(side, cap)


#: Synthetic models drawn on a known surface -> distance of points to that surface (the mug: its
#: handle patch, off the cylinder, is left out).
TRUE_SURFACES = {
    "sphere": lambda p: np.abs(np.linalg.norm(p, axis=1) - 1.0),
    "torus": lambda p: np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - 1.0, p[:, 2]) - 0.4),
    "mug": _cylinder_with_caps,
}


def truth_distance(name, mesh, h):
    """Mean and largest distance (in units of h) of the mesh vertices to the true surface."""
    V = mesh.vertices
    if name == "mug":
        handle = (np.abs(V[:, 1]) < 1e-9) & (V[:, 0] > 0.5 + 1e-9)
        V = V[~handle]
    d = TRUE_SURFACES[name](V) / h
    return float(d.mean()), float(d.max())


#: Heading of the ``--markdown`` table.
HEADER = """# Surfacing table

Generated by `python benchmarks/surface_eval.py --cache DIR --markdown docs/surfacing-table.md`;
do not edit by hand. Networks reconstructed by the default method (CASSIE sketches sampled at
2 mm, synthetic models at their spacing h); distances in units of h (mesh to truth: the mesh
vertices to the true surface; truth to mesh: samples of the true surface to the mesh); times in
seconds on a 2-core machine (idle or shared with other work), and over a k=16 cKDTree query of
the network's curve points measured in the same run (`time / ref`). A model with an opening is
surfaced a second time with it named (`(opening given)`). See docs/surfacing.md.

"""


def _fmt(x, spec):
    return "-" if x is None else format(x, spec)


def markdown(rows) -> str:
    """The surfacing table (one row per model) as markdown."""
    out = ["| set | model | nodes | curves | patches (true) | boundary loops (true) | self-intersecting faces | "
           "non-manifold edges | genus | mesh to truth, mean / max (h) | truth to mesh, mean / max (h) | "
           "time (s) | time / ref |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        tp = f" ({r['true_patches']})" if r.get("true_patches") is not None else ""
        tb = f" ({r['true_boundary_loops']})" if r.get("true_boundary_loops") is not None else ""
        d = r.get("distances")
        m2t = f"{d[0]:.3f} / {d[1]:.2f}" if d else "-"
        t2m = f"{d[2]:.3f} / {d[3]:.2f}" if d and d[2] is not None else "-"
        out.append(f"| {r['set']} | {r['model']} | {r['nodes']} | {r['curves']} | {r['patches']}{tp} | "
                   f"{r['boundary_loops']}{tb} | {_fmt(r['self_x'], 'd')} | {r['non_manifold']} | "
                   f"{_fmt(r['genus'], 'd')} | {m2t} | {t2m} | {r['time']:.1f} | {r['time'] / r['ref']:.0f} |")
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", default="free,study,synth,surfaces", help="comma list of free, study, synth, surfaces")
    ap.add_argument("--names", default="", help="comma list of model names (default: all)")
    ap.add_argument("--network", choices=["reconstructed", "truth"], default="reconstructed")
    ap.add_argument("--cache", default=None, help="folder for reconstructed networks")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--markdown", default=None, help="write the table of every model run to this file")
    args = ap.parse_args(argv)
    cache = Path(args.cache) if args.cache else None
    if cache:
        cache.mkdir(parents=True, exist_ok=True)
    names = {n for n in args.names.split(",") if n}
    head = (f"{'set':8} {'model':16} {'N_n':>4} {'N_c':>4} {'patch':>5} {'tris':>7} {'selfx':>5} {'nm_e':>4} "
            f"{'bnd':>3} {'genus':>5} {'ovl':>3} {'time':>6} {'t/ref':>6}")
    print(head)
    tot = {"models": 0, "self_x": 0, "self_x_models": 0, "nm": 0, "nm_models": 0, "ovl_models": 0, "time": 0.0,
           "faces": 0}
    bad, rows = [], []
    for kind in [k for k in args.set.split(",") if k]:
        sel = set(QUICK[kind]) if args.quick else names
        if args.quick and not sel:
            continue
        runs = []
        for name, net in networks(kind, sel, args.network, cache):
            model = surfaces.surface_model(name) if kind == "surfaces" else None
            runs.append((name, name, net, model, ()))
            ids = open_curve_ids(model, net, synth.h_of(model.network)) if model is not None else []
            if ids:
                runs.append((f"{name} (opening given)", name, net, model, ids))
        for label, name, net, model, open_curves in runs:
            h = synth.h_of(model.network) if model is not None else None
            row, mesh = surface_row(kind, label, net, model, h, open_curves)
            ck = mesh.checks
            sx, dt = row["self_x"], row["time"]
            print(f"{kind:8} {label:16} {net.n_nodes:4d} {net.n_curves:4d} {mesh.n_patches:5d} "
                  f"{len(mesh.triangles):7d} {sx if sx is not None else '-':>5} {ck.non_manifold_edges:4d} "
                  f"{ck.boundary_loops:3d} {ck.genus if ck.genus is not None else '-':>5} "
                  f"{len(ck.overlaps):3d} {dt:6.1f} {dt / row['ref']:6.0f}", flush=True)
            tot["models"] += 1
            tot["self_x"] += sx or 0
            tot["self_x_models"] += bool(sx)
            tot["nm"] += ck.non_manifold_edges
            tot["nm_models"] += bool(ck.non_manifold_edges)
            tot["ovl_models"] += bool(ck.overlaps)
            tot["time"] += dt
            tot["faces"] += len(mesh.triangles)
            if row["warning"]:
                bad.append(f"{label}: {row['warning']}")
            if model is not None:
                d = row["distances"]
                print(f"      patches {mesh.n_patches} (true {model.patches}), boundary loops {ck.boundary_loops} "
                      f"(true {model.boundary_loops}); mesh to the true surface: mean {d[0]:.3f} h, max {d[1]:.3f} h; "
                      f"true surface to mesh: mean {d[2]:.3f} h, max {d[3]:.3f} h")
            if kind == "synth" and name in TRUE_SURFACES:
                dm, dx = truth_distance(name, mesh, synth.h_of(synth.model(name)))
                row.update(distances=(dm, dx, None, None))
                print(f"      distance to the true {name} surface: mean {dm:.3f} h, max {dx:.3f} h")
            if kind == "synth" and name == "mug":
                rmin, rmean = mug_radius(mesh)
                print(f"      mug cylinder at mid-height: radius min {rmin:.3f}, max {rmean:.3f} (true 0.500)")
            rows.append(row)
    print(f"total: {tot['models']} models, {tot['faces']} faces; self-intersecting faces {tot['self_x']} in "
          f"{tot['self_x_models']} models; non-manifold edges {tot['nm']} in {tot['nm_models']} models; "
          f"overlapping patches in {tot['ovl_models']} models; surfacing time {tot['time']:.0f} s")
    for line in bad:
        print("  " + line)
    if args.markdown:
        Path(args.markdown).write_text(HEADER + markdown(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Issue 21: the network and surface files open in Blender's own importers (``bpy``).

Blender as a module (``pip install bpy``, Python 3.11 for bpy 4.x) is a 350 MB wheel that unpacks
to about 860 MB, too large for the ``test`` extra: these tests run where bpy is installed and are
skipped elsewhere. Blender runs in a subprocess (its factory settings reset for each file, and
nothing of it is left in the test process).
"""

import importlib.util
import json
import subprocess
import sys

import numpy as np
import pytest

from curvenet import synth

pytestmark = pytest.mark.skipif(importlib.util.find_spec("bpy") is None,
                                reason="Blender as a Python module (pip install bpy) is not installed")

#: Imports each file given in a fresh empty scene and prints, per file, the importer's result and
#: the counts of the mesh objects it made.
BLENDER_SCRIPT = """
import json, sys
import bpy
out = {}
for f in sys.argv[1:]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    op = bpy.ops.wm.obj_import if f.endswith(".obj") else bpy.ops.wm.ply_import
    result = op(filepath=f)
    meshes = [o.data for o in bpy.context.scene.objects if o.type == "MESH"]
    out[f] = {"result": sorted(result), "objects": len(meshes),
              "vertices": sum(len(m.vertices) for m in meshes), "edges": sum(len(m.edges) for m in meshes),
              "faces": sum(len(m.polygons) for m in meshes),
              "triangles": sum(1 for m in meshes for p in m.polygons if len(p.vertices) == 3)}
print("COUNTS " + json.dumps(out))
"""


def blender_counts(*paths):
    r = subprocess.run([sys.executable, "-c", BLENDER_SCRIPT, *map(str, paths)], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    line = [ln for ln in r.stdout.splitlines() if ln.startswith("COUNTS ")][-1]
    return {k: v for k, v in json.loads(line[len("COUNTS "):]).items()}


def test_network_obj_and_ply_import_in_blender_as_one_mesh_of_edges(tmp_path):
    net = synth.model("speaker")  # junctions, free ends and two closed loops without node
    v, polylines = net.polyline_vertices()
    n_edges = sum(len(ids) - 1 for ids in polylines)  # a loop repeats its first vertex: its closing edge counts
    obj, ply = net.save(tmp_path / "net.obj"), net.save(tmp_path / "net.ply")
    got = blender_counts(obj, ply)
    for path in (obj, ply):
        c = got[str(path)]
        assert c["result"] == ["FINISHED"], (path, c)
        # one object whose curves share their node vertices (the junctions stay joined)
        assert (c["objects"], c["vertices"], c["edges"], c["faces"]) == (1, len(v), n_edges, 0), (path, c)


def test_surface_obj_and_ply_import_in_blender_with_every_triangle(tmp_path):
    pytest.importorskip("triangle")
    from curvenet import surface
    from curvenet.io.mesh import MESH_WRITERS

    mesh = surface(synth.model("cube"))
    tri = np.sort(mesh.triangles, axis=1)
    n_edges = len(np.unique(np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]]]), axis=0))
    paths = []
    for ext in (".obj", ".ply"):
        path = tmp_path / f"mesh{ext}"
        path.write_bytes(MESH_WRITERS[ext][0](mesh))
        paths.append(path)
    got = blender_counts(*paths)
    for path in paths:
        c = got[str(path)]
        assert c["result"] == ["FINISHED"], (path, c)
        assert (c["objects"], c["vertices"], c["edges"]) == (1, len(mesh.vertices), n_edges), (path, c)
        assert c["faces"] == c["triangles"] == len(mesh.triangles), (path, c)

"""Mesh writers: pure functions from a :class:`SurfaceMesh` to the bytes of a file.

``MESH_WRITERS`` maps an extension to ``(writer, description)``; the caller writes the bytes
(atomically, with :func:`curvenet.io.atomic_write`). They live with the other writers: their numbers
go through the same bulk formatting (:mod:`curvenet.io.numbers`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["mesh_to_obj", "mesh_to_ply", "MESH_WRITERS"]


def mesh_to_obj(mesh, *, precision: int = 9) -> bytes:
    """Wavefront OBJ text: ``v`` lines, then one group ``g patch_K`` of ``f`` lines per patch.

    The numbers are written in bulk (:mod:`curvenet.io.numbers`): the coordinates as
    ``"%.{precision}g"`` writes them, the faces' vertex numbers by orjson when installed.

    Parameters
    ----------
    mesh : SurfaceMesh
    precision : int
        Significant digits of the coordinates.

    Returns
    -------
    bytes
    """
    from .numbers import g_table_bytes

    V = np.asarray(mesh.vertices, dtype=float).reshape(-1, 3)
    out = [b"# curvenet surface mesh\n",
           f"# vertices {len(V)} triangles {len(mesh.triangles)} patches {mesh.n_patches}\n".encode(),
           g_table_bytes(V, precision, [" ", " ", "\n"], "v ")]
    T = np.asarray(mesh.triangles, dtype=np.int64).reshape(-1, 3) + 1
    return b"".join(out + _face_groups(T, np.asarray(mesh.patch)))


def _face_groups(T: np.ndarray, patch: np.ndarray) -> list[bytes]:
    """The ``g patch_K`` line and ``f`` lines of each patch, in the order of the patch ids, the
    faces of a patch in their order (one stable sort and one bulk call for all).

    Parameters
    ----------
    T : (t, 3) int ndarray
        Faces, vertex numbers from 1.
    patch : (t,) ndarray of int
        The patch of each face.

    Returns
    -------
    list of bytes
    """
    from .numbers import table_groups

    if not len(T):
        return []
    order = np.argsort(patch, kind="stable")
    ids, starts = np.unique(patch[order], return_index=True)
    groups = table_groups(T[order], [" ", " ", "\nf "], groups=np.append(starts, len(T)))
    return [b"g patch_%d\nf %s\n" % (int(k), g) for k, g in zip(ids.tolist(), groups)]


def mesh_to_ply(mesh, *, binary: bool = True, patch: bool = False) -> bytes:
    """PLY with float64 vertices and triangle faces (optionally with an int ``patch`` property).

    Parameters
    ----------
    mesh : SurfaceMesh
    binary : bool
        Binary little-endian (default) or ASCII.
    patch : bool
        Give each face an ``int patch`` property (its patch id). Off by default: meshio's PLY
        reader fails on a binary face element with a property after the vertex list; the OBJ
        keeps the patches as groups.

    Returns
    -------
    bytes
    """
    V = np.asarray(mesh.vertices, dtype="<f8")
    T = np.asarray(mesh.triangles, dtype="<i4")
    P = np.asarray(mesh.patch, dtype="<i4")
    header = (
        "ply\n"
        f"format {'binary_little_endian' if binary else 'ascii'} 1.0\n"
        "comment curvenet surface mesh\n"
        f"element vertex {len(V)}\n"
        "property double x\nproperty double y\nproperty double z\n"
        f"element face {len(T)}\n"
        "property list uchar int vertex_indices\n"
        + ("property int patch\n" if patch else "")
        + "end_header\n"
    ).encode("ascii")
    if binary:
        fields = [("n", "u1"), ("v", "<i4", (3,))] + ([("patch", "<i4")] if patch else [])
        face = np.zeros(len(T), dtype=fields)
        face["n"] = 3
        face["v"] = T
        if patch:
            face["patch"] = P
        return header + V.tobytes() + face.tobytes()
    lines = [" ".join(map(repr, v)) for v in V.tolist()]
    lines += [f"3 {t[0]} {t[1]} {t[2]}" + (f" {p}" if patch else "") for t, p in zip(T, P)]
    return header + ("\n".join(lines) + "\n").encode("ascii")


#: extension -> (writer, description)
MESH_WRITERS = {
    ".obj": (mesh_to_obj, "Wavefront OBJ triangles, one group per patch"),
    ".ply": (mesh_to_ply, "binary PLY triangles (trimesh, Open3D, meshio, MeshLab, Blender)"),
}

"""toothfuse for MeshLab (pymeshlab): fuse an IOS jaw mesh with CBCT tooth meshes.

    import pymeshlab, toothfuse_meshlab
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh("ios.ply")     # FDI labels as a custom scalar attribute "label"
    ms.load_new_mesh("cbct.ply")    # (per vertex or per face; 0 = gingiva)
    fused_id = toothfuse_meshlab.fuse_meshset(ms, ios_id=0, cbct_ids=[1], frame="ios")
    # ms.mesh(fused_id): the fused jaw, custom vertex scalar attributes "label" and "source"
    # (0 IOS crown, 1 band, 2 CBCT root); the vertex quality holds the label too.

CBCT teeth may also be separate meshes, one tooth each: pass a dict {fdi: mesh} to
fuse_meshes, or cbct_ids={fdi: id} to fuse_meshset. Built on the toothfuse Python binding
(bindings/python/toothfuse.py, ctypes); pymeshlab (and so numpy) is needed only to build the
output mesh: everything else works on any object with pymeshlab's Mesh accessors.
"""

import toothfuse

__all__ = ["mesh_labels", "mesh_part", "fuse_meshes", "fuse_meshset"]

_VERTEX_GETTERS = [("vertex_custom_scalar_attribute_array", False),
                   ("face_custom_scalar_attribute_array", True)]
_QUALITY_GETTERS = [("vertex_scalar_array", False), ("face_scalar_array", True)]


def _ints(values, what):
    out = []
    for n, v in enumerate(toothfuse._flat(values)):
        iv = int(round(float(v)))
        if iv != v:
            raise ValueError(f"{what}: value {v} at {n} is not an integer tooth label")
        out.append(iv)
    return out


def mesh_labels(mesh, attribute="label"):
    """(labels, per_face) of a pymeshlab mesh: the custom scalar attribute `attribute` per
    vertex, else per face; with attribute "quality", the vertex (else face) quality. Raises
    ValueError when the mesh has none."""
    getters = _QUALITY_GETTERS if attribute == "quality" else _VERTEX_GETTERS
    for getter, per_face in getters:
        fn = getattr(mesh, getter, None)
        if fn is None:
            continue
        try:
            values = fn() if attribute == "quality" else fn(attribute)
        except Exception:  # pymeshlab raises when the attribute does not exist
            continue
        return _ints(values, f'attribute "{attribute}"'), per_face
    raise ValueError(f'the mesh has no per-vertex or per-face scalar attribute "{attribute}"')


def mesh_part(mesh, attribute="label", fdi=None):
    """(vertices, triangles, labels, per_face) of a mesh; with `fdi`, the whole mesh is that
    tooth and needs no labels."""
    v, f = mesh.vertex_matrix(), mesh.face_matrix()
    if fdi is not None:
        if not toothfuse.is_fdi(fdi):
            raise ValueError(f"{fdi} is not an FDI tooth number")
        return v, f, int(fdi), False
    labels, per_face = mesh_labels(mesh, attribute)
    return v, f, labels, per_face


def fuse_meshes(ios, cbct, *, attribute="label", preset="default", frame="cbct",
                ios_repair=False, as_mesh=True):
    """Fuses an IOS jaw mesh (labeled) with CBCT teeth: one labeled mesh, a list of labeled
    meshes, or {fdi: mesh} with one tooth per mesh. Returns (mesh, jaw): a new pymeshlab.Mesh
    (None with as_mesh=False) and the toothfuse.FusedJaw (teeth, skipped, quality, report)."""
    iv, it, il, ipf = mesh_part(ios, attribute)
    if isinstance(cbct, dict):
        parts = [mesh_part(m, attribute, fdi) for fdi, m in sorted(cbct.items())]
    elif isinstance(cbct, (list, tuple)):
        parts = [mesh_part(m, attribute) for m in cbct]
    else:
        parts = [mesh_part(cbct, attribute)]
    cv, ct, cl = toothfuse.merge_meshes(parts)
    jaw = toothfuse.fuse(iv, it, il, cv, ct, cl, ios_per_face=ipf, cbct_per_face=True,
                         preset=preset, frame=frame, ios_repair=ios_repair,
                         as_numpy=as_mesh)
    return (_to_mesh(jaw) if as_mesh else None), jaw


def _to_mesh(jaw):
    import numpy as np
    import pymeshlab

    labels = jaw.labels.astype(np.float64)
    m = pymeshlab.Mesh(vertex_matrix=jaw.positions, face_matrix=jaw.triangles.astype(np.int32),
                       v_scalar_array=labels)
    m.add_vertex_custom_scalar_attribute(labels, "label")
    m.add_vertex_custom_scalar_attribute(jaw.sources.astype(np.float64), "source")
    return m


def fuse_meshset(ms, ios_id, cbct_ids, *, name="toothfuse_fused", **options):
    """fuse_meshes on meshes of a pymeshlab.MeshSet (cbct_ids: a list of ids, or {fdi: id});
    adds the fused jaw to the set and returns its id. Options as fuse_meshes'."""
    if isinstance(cbct_ids, dict):
        cbct = {fdi: ms.mesh(i) for fdi, i in cbct_ids.items()}
    else:
        cbct = [ms.mesh(i) for i in cbct_ids]
    mesh, jaw = fuse_meshes(ms.mesh(ios_id), cbct, **options)
    ms.add_mesh(mesh, name)
    for fdi, reason in jaw.skipped:
        print(f"toothfuse: tooth {fdi} not fused: {reason}")
    return ms.current_mesh_id()

"""toothfuse for MeshLab (pymeshlab): fuse an IOS jaw mesh with CBCT tooth meshes.

    import pymeshlab, toothfuse_meshlab
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh("ios.ply")
    ms.load_new_mesh("cbct.ply")
    fused_id = toothfuse_meshlab.fuse_meshset(
        ms, ios_id=0, cbct_ids=1, frame="ios",
        ios_labels=toothfuse_meshlab.ply_labels("ios.ply"),     # FDI per vertex or face,
        cbct_labels=toothfuse_meshlab.ply_labels("cbct.ply"))   # 0 = gingiva
    # ms.mesh(fused_id): the fused jaw, custom vertex scalar attributes "label" and "source"
    # (0 IOS crown, 1 band, 2 CBCT root); the vertex quality holds the label too.

pymeshlab's PLY reader (measured with 2025.7) drops every custom vertex/face property except
`quality`, so labels read from a PLY file are passed explicitly (ply_labels reads them). Without
explicit labels, a mesh's custom scalar attribute (default "label", per vertex then per face)
is used, or its quality with attribute="quality".

CBCT teeth may also be separate meshes, one tooth each: pass a dict {fdi: mesh} to
fuse_meshes, or cbct_ids={fdi: id} to fuse_meshset. Built on the toothfuse Python package
(`pip install ./bindings/python` into the Python that runs pymeshlab; it ships the library);
pymeshlab (and so numpy) is needed only to build the
output mesh: everything else works on any object with pymeshlab's Mesh accessors.
"""

import toothfuse

import struct

__all__ = ["ply_labels", "mesh_labels", "mesh_part", "fuse_meshes", "fuse_meshset"]

_VERTEX_GETTERS = [("vertex_custom_scalar_attribute_array", False),
                   ("face_custom_scalar_attribute_array", True)]
_QUALITY_GETTERS = [("vertex_scalar_array", False), ("face_scalar_array", True)]


def _ints(values, what):
    out = []
    for n, v in enumerate(toothfuse._core._flat(values)):
        iv = int(round(float(v)))
        if iv != v:
            raise ValueError(f"{what}: value {v} at {n} is not an integer tooth label")
        out.append(iv)
    return out


_PLY = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
        "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
        "float": "f", "float32": "f", "double": "d", "float64": "d"}


def ply_labels(path, name="label"):
    """(labels, per_face) of PLY file `path` (ASCII or binary): the vertex property `name`,
    else the face property `name`. For meshes pymeshlab loaded without their labels."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    fmt, elements = None, []
    for line in data[:end].decode("ascii", "replace").splitlines():
        w = line.split()
        if w and w[0] == "format":
            fmt = w[1]
        elif w and w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w and w[0] == "property":
            elements[-1][2].append(w[1:])
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise ValueError(f"{path}: unknown PLY format {fmt}")
    order = "<" if fmt == "binary_little_endian" else ">"
    tokens = data[end:].split() if fmt == "ascii" else None
    pos = 0 if fmt == "ascii" else end
    for el, count, props in elements:
        col = [p[-1] for p in props].index(name) if any(p[-1] == name for p in props) else -1
        wanted = el in ("vertex", "face") and col >= 0
        values = []
        for _ in range(count):
            for k, p in enumerate(props):
                if p[0] == "list":  # list <count type> <item type> name
                    if tokens is not None:
                        n = int(tokens[pos])
                        pos += 1 + n
                        continue
                    cf = order + _PLY[p[1]]
                    (n,) = struct.unpack_from(cf, data, pos)
                    pos += struct.calcsize(cf) + n * struct.calcsize(order + _PLY[p[2]])
                    continue
                if tokens is not None:
                    v = float(tokens[pos])
                    pos += 1
                else:
                    f = order + _PLY[p[0]]
                    (v,) = struct.unpack_from(f, data, pos)
                    pos += struct.calcsize(f)
                if wanted and k == col:
                    values.append(v)
        if wanted:
            return _ints(values, f'{path}: {el} property "{name}"'), el == "face"
    raise ValueError(f'{path}: no vertex or face property "{name}"')


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


def mesh_part(mesh, attribute="label", fdi=None, labels=None):
    """(vertices, triangles, labels, per_face) of a mesh; with `fdi`, the whole mesh is that
    tooth and needs no labels; `labels` = (values, per_face) given explicitly."""
    v, f = mesh.vertex_matrix(), mesh.face_matrix()
    if labels is not None:
        values, per_face = labels
        return v, f, _ints(values, "labels"), per_face
    if fdi is not None:
        if not toothfuse.is_fdi(fdi):
            raise ValueError(f"{fdi} is not an FDI tooth number")
        return v, f, int(fdi), False
    labels, per_face = mesh_labels(mesh, attribute)
    return v, f, labels, per_face


def fuse_meshes(ios, cbct, *, attribute="label", ios_labels=None, cbct_labels=None,
                preset="default", frame="cbct", ios_repair=False, as_mesh=True):
    """Fuses an IOS jaw mesh (labeled) with CBCT teeth: one labeled mesh, a list of labeled
    meshes, or {fdi: mesh} with one tooth per mesh. Labels come from the meshes' `attribute`
    unless given: ios_labels = (values, per_face), cbct_labels = the same for one CBCT mesh or
    a list of them for a list. Returns (mesh, jaw): a new pymeshlab.Mesh (None with
    as_mesh=False) and the toothfuse.FusedJaw (teeth, skipped, quality, report)."""
    iv, it, il, ipf = mesh_part(ios, attribute, labels=ios_labels)
    if isinstance(cbct, dict):
        parts = [mesh_part(m, attribute, fdi) for fdi, m in sorted(cbct.items())]
    elif isinstance(cbct, (list, tuple)):
        given = cbct_labels if cbct_labels is not None else [None] * len(cbct)
        if isinstance(given, tuple) and len(given) == 2 and isinstance(given[1], bool):
            given = [given]  # one (values, per_face) pair
        if len(given) != len(cbct):
            raise ValueError(f"{len(given)} CBCT label sets for {len(cbct)} CBCT meshes")
        parts = [mesh_part(m, attribute, labels=lab) for m, lab in zip(cbct, given)]
    else:
        parts = [mesh_part(cbct, attribute, labels=cbct_labels)]
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
    """fuse_meshes on meshes of a pymeshlab.MeshSet (cbct_ids: one id, a list of ids, or
    {fdi: id}); adds the fused jaw to the set and returns its id. Options as fuse_meshes'."""
    if isinstance(cbct_ids, dict):
        cbct = {fdi: ms.mesh(i) for fdi, i in cbct_ids.items()}
    elif isinstance(cbct_ids, int):
        cbct = ms.mesh(cbct_ids)
    else:
        cbct = [ms.mesh(i) for i in cbct_ids]
    mesh, jaw = fuse_meshes(ms.mesh(ios_id), cbct, **options)
    ms.add_mesh(mesh, name)
    for fdi, reason in jaw.skipped:
        print(f"toothfuse: tooth {fdi} not fused: {reason}")
    return ms.current_mesh_id()

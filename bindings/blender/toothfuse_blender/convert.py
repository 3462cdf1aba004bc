"""The Blender add-on's logic without Blender (testable with plain python3): world
coordinates of an object's triangles, its FDI labels (an integer attribute on points or
faces, else the object's "fdi" custom property or its name, e.g. "tooth_36"), the one-call
fuse through the toothfuse Python binding, and the fused jaw as mesh data for Blender."""

import re

try:
    import toothfuse  # the package, pip-installed into Blender's Python
except ImportError:
    from . import toothfuse  # or the package folder copied into the add-on


class Part:
    """One Blender object as toothfuse input: world vertices in mm (flat), triangles (flat),
    labels (per vertex, per face, or None when the object is one tooth `fdi`)."""

    def __init__(self, name, xyz, tris, labels, per_face, fdi=None):
        self.name, self.xyz, self.tris = name, xyz, tris
        self.labels, self.per_face, self.fdi = labels, per_face, fdi


def fdi_from_name(name):
    """The first two-digit FDI number standing alone in an object name ("tooth_36",
    "CBCT 11.001", "36"), else None."""
    for m in re.finditer(r"(?<!\d)(\d{2})(?!\d)", name):
        n = int(m.group(1))
        if toothfuse.is_fdi(n):
            return n
    return None


def to_world(co, matrix, scale=1.0):
    """Flat local coordinates -> flat world coordinates in mm: `matrix` is the object's
    matrix_world as 4 rows, `scale` the millimetres per Blender unit."""
    (a, b, c, d), (e, f, g, h), (i, j, k, l) = matrix[0], matrix[1], matrix[2]
    out = []
    for n in range(0, len(co), 3):
        x, y, z = co[n], co[n + 1], co[n + 2]
        out.append((a * x + b * y + c * z + d) * scale)
        out.append((e * x + f * y + g * z + h) * scale)
        out.append((i * x + j * y + k * z + l) * scale)
    return out


def _int_labels(values, name, what):
    out = []
    for n, v in enumerate(values):
        iv = int(round(v))
        if iv != v:
            raise ValueError(f'{name}: attribute "{what}" value {v} at {n} is not an integer')
        out.append(iv)
    return out


def object_part(name, co, tri_vertices, tri_polygons, matrix, *, attribute=None,
                domain=None, values=None, fdi=None, scale=1.0):
    """A Part from what the add-on reads off an evaluated Blender mesh: `co` (flat vertex
    coordinates), `tri_vertices` / `tri_polygons` (loop_triangles' vertices and
    polygon_index), the label attribute's `domain` ("POINT" or "FACE") and `values` (None when
    the object has no such attribute), the object's "fdi" property, `matrix` (matrix_world)."""
    xyz = to_world(co, matrix, scale)
    tris = list(tri_vertices)
    if values is not None:
        labels = _int_labels(values, name, attribute)
        if domain == "POINT":
            return Part(name, xyz, tris, labels, False)
        if domain == "FACE":  # Blender polygons -> their loop triangles
            return Part(name, xyz, tris, [labels[p] for p in tri_polygons], True)
        raise ValueError(f'{name}: attribute "{attribute}" is on {domain}, expected POINT or FACE')
    tooth = fdi if fdi is not None else fdi_from_name(name)
    if tooth is None or not toothfuse.is_fdi(tooth):
        raise ValueError(f'{name}: no "{attribute}" attribute and no FDI number in its '
                         f'"fdi" property or its name')
    return Part(name, xyz, tris, None, False, fdi=int(tooth))


def fuse_parts(ios, cbct, *, preset="default", frame="cbct", ios_repair=False):
    """Fuses an IOS Part (a labeled jaw) with CBCT Parts (labeled meshes or one tooth each)."""
    if ios.labels is None:
        raise ValueError(f"{ios.name}: the IOS object needs a per-point or per-face label "
                         f"attribute (FDI, 0 = gingiva)")
    if not cbct:
        raise ValueError("select the CBCT tooth objects as well as the IOS object")
    cx, ct, cl = toothfuse.merge_meshes(
        [(p.xyz, p.tris, p.fdi if p.labels is None else p.labels, p.per_face) for p in cbct])
    return toothfuse.fuse(ios.xyz, ios.tris, ios.labels, cx, ct, cl,
                          ios_per_face=ios.per_face, cbct_per_face=True, preset=preset,
                          frame=frame, ios_repair=ios_repair, as_numpy=False)


def mesh_data(jaw, scale=1.0):
    """The fused jaw as Blender mesh data: vertices [(x, y, z)] in Blender units, faces
    [(a, b, c)], and the per-vertex "label" and "source" attribute values."""
    p, t = jaw.positions, jaw.triangles
    verts = [(p[i] / scale, p[i + 1] / scale, p[i + 2] / scale) for i in range(0, len(p), 3)]
    faces = [(t[i], t[i + 1], t[i + 2]) for i in range(0, len(t), 3)]
    return verts, faces, list(jaw.labels), list(jaw.sources)

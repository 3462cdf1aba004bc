"""Helpers of the Python tests (no third-party packages): the demo jaws of the ctest
`demo_jaws` fixture, a reader for the binary PLY files toothfuse writes, and independent
pure-Python mesh checks (edge use counts, components, signed volume)."""

import os
import struct
import unittest


def jaw_dir(k):
    """TOOTHFUSE_JAWS_DIR/jaw_<k> (the demo_jaws fixture); skips the test when unset."""
    root = os.environ.get("TOOTHFUSE_JAWS_DIR")
    if not root:
        raise unittest.SkipTest("TOOTHFUSE_JAWS_DIR is not set (ctest's demo_jaws fixture)")
    return os.path.join(root, f"jaw_{k}")


_TYPES = {"double": "d", "float": "f", "int": "i", "uint": "I", "uchar": "B", "char": "b",
          "short": "h", "ushort": "H", "float64": "d", "float32": "f", "int32": "i",
          "uint32": "I", "uint8": "B", "int8": "b"}


def read_ply(path):
    """A binary little-endian PLY with per-vertex scalar properties and triangle faces (what
    `toothfuse demo` writes) -> (xyz flat list, triangles flat list, {property: list})."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in header:
        raise ValueError(f"{path}: not binary little-endian PLY")
    elements, current = [], None
    for line in header:
        w = line.split()
        if w[0] == "element":
            current = (w[1], int(w[2]), [])
            elements.append(current)
        elif w[0] == "property":
            current[2].append(w[1:])
    pos, xyz, tris, props = end, [], [], {}
    for name, count, plist in elements:
        if name == "vertex":
            fmt = "<" + "".join(_TYPES[p[0]] for p in plist)
            size = struct.calcsize(fmt)
            rows = list(struct.iter_unpack(fmt, data[pos:pos + size * count]))
            pos += size * count
            names = [p[1] for p in plist]
            cols = list(zip(*rows)) if rows else [[] for _ in names]
            col = dict(zip(names, cols))
            for x, y, z in zip(col["x"], col["y"], col["z"]):
                xyz.extend((x, y, z))
            props = {n: list(c) for n, c in col.items() if n not in ("x", "y", "z")}
        elif name == "face":
            (p,) = plist  # property list <count type> <index type> vertex_indices
            cfmt, ifmt = _TYPES[p[1]], _TYPES[p[2]]
            fmt = "<" + cfmt + 3 * ifmt
            size = struct.calcsize(fmt)
            for row in struct.iter_unpack(fmt, data[pos:pos + size * count]):
                if row[0] != 3:
                    raise ValueError(f"{path}: a face with {row[0]} vertices")
                tris.extend(row[1:])
            pos += size * count
        else:
            raise ValueError(f"{path}: unexpected element {name}")
    return xyz, tris, props


def edge_report(tris):
    """Pure-Python edge counts of a triangle list (flat): boundary edges (used once),
    non-manifold edges (used more than twice) and misoriented edges (a directed edge used
    twice, i.e. neighbouring faces disagree)."""
    directed = {}
    for t in range(0, len(tris), 3):
        a, b, c = tris[t], tris[t + 1], tris[t + 2]
        for e in ((a, b), (b, c), (c, a)):
            directed[e] = directed.get(e, 0) + 1
    undirected = {}
    for (a, b), n in directed.items():
        key = (a, b) if a < b else (b, a)
        undirected[key] = undirected.get(key, 0) + n
    return {
        "edges": len(undirected),
        "boundary": sum(1 for n in undirected.values() if n == 1),
        "non_manifold": sum(1 for n in undirected.values() if n > 2),
        "misoriented": sum(1 for n in directed.values() if n > 1),
    }


def components(tris):
    """Connected components (by shared vertices) of a flat triangle list."""
    parent = {}

    def find(v):
        while parent.setdefault(v, v) != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    for t in range(0, len(tris), 3):
        a = find(tris[t])
        for v in (tris[t + 1], tris[t + 2]):
            b = find(v)
            if a != b:
                parent[b] = a
    return len({find(v) for v in parent})


def signed_volume(xyz, tris):
    """Signed enclosed volume of a closed triangle mesh (positive when outward oriented)."""
    vol = 0.0
    for t in range(0, len(tris), 3):
        a, b, c = (3 * tris[t + k] for k in range(3))
        ax, ay, az = xyz[a:a + 3]
        bx, by, bz = xyz[b:b + 3]
        cx, cy, cz = xyz[c:c + 3]
        vol += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    return vol / 6.0


def split_by_label(tris, labels):
    """{label: flat triangle list} of a jaw whose triangles each carry one vertex label;
    raises ValueError on a triangle spanning two labels."""
    out = {}
    for t in range(0, len(tris), 3):
        a, b, c = tris[t], tris[t + 1], tris[t + 2]
        la = labels[a]
        if labels[b] != la or labels[c] != la:
            raise ValueError(f"triangle {t // 3} spans labels {la}, {labels[b]}, {labels[c]}")
        out.setdefault(la, []).extend((a, b, c))
    return out


def crown_points(xyz, tris, labels):
    """{label: set of (x, y, z)} of the IOS crowns as toothfuse splits them: the vertices of
    triangles whose three vertices carry the same non-zero label."""
    out = {}
    for t in range(0, len(tris), 3):
        a, b, c = tris[t], tris[t + 1], tris[t + 2]
        la = labels[a]
        if la == 0 or labels[b] != la or labels[c] != la:
            continue
        s = out.setdefault(la, set())
        for v in (a, b, c):
            s.add(tuple(xyz[3 * v:3 * v + 3]))
    return out


def apply(m, xyz, i):
    """Row-major 4x4 `m` applied to point i of flat `xyz`."""
    x, y, z = xyz[3 * i:3 * i + 3]
    return [m[4 * r] * x + m[4 * r + 1] * y + m[4 * r + 2] * z + m[4 * r + 3] for r in range(3)]

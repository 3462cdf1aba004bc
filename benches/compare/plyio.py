"""Reads a binary little-endian triangle PLY with per-vertex properties (the foreign jaws' format:
float x, y, z, int label; faces as `list uchar int vertex_indices`)."""

from pathlib import Path

import numpy as np

PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "<i2", "int16": "<i2", "ushort": "<u2", "uint16": "<u2",
    "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
    "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8",
}


def read_ply(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns (vertices (n, 3) float64, vertex labels (n,) int64, triangles (m, 3) int64)."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in header:
        raise ValueError(f"{path}: not a binary little-endian PLY")
    elements: list[tuple[str, int, list[str]]] = []
    for line in header:
        words = line.split()
        if words[:1] == ["element"]:
            elements.append((words[1], int(words[2]), []))
        elif words[:1] == ["property"]:
            elements[-1][2].append(line)
    (vname, nv, vprops), (fname, nf, fprops) = elements
    if vname != "vertex" or fname != "face" or fprops != ["property list uchar int vertex_indices"]:
        raise ValueError(f"{path}: expected vertex then face elements with uchar/int index lists")
    vdtype = np.dtype([(p.split()[2], PLY_TYPES[p.split()[1]]) for p in vprops])
    vert = np.frombuffer(data, dtype=vdtype, count=nv, offset=end)
    fdtype = np.dtype([("n", "u1"), ("v", "<i4", (3,))])
    face = np.frombuffer(data, dtype=fdtype, count=nf, offset=end + nv * vdtype.itemsize)
    if np.any(face["n"] != 3):
        raise ValueError(f"{path}: only triangles are read")
    xyz = np.stack([vert["x"], vert["y"], vert["z"]], axis=1).astype(np.float64)
    return xyz, vert["label"].astype(np.int64), face["v"].astype(np.int64)


def split_by_label(vertices: np.ndarray, labels: np.ndarray, triangles: np.ndarray
                   ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Per non-zero label: the faces whose three vertices carry it, as a compact mesh."""
    out = {}
    face_labels = labels[triangles]
    for label in np.unique(labels[labels > 0]):
        faces = triangles[np.all(face_labels == label, axis=1)]
        used, inverse = np.unique(faces, return_inverse=True)
        out[int(label)] = (vertices[used], inverse.reshape(-1, 3))
    return out

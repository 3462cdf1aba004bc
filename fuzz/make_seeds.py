#!/usr/bin/env python3
"""Writes the fuzz seed corpus: tiny valid files of every format and encoding the readers
accept (a labeled tetrahedron or square pyramid), plus mutation records for ffi_fuse.

    python3 fuzz/make_seeds.py        # rewrites fuzz/seeds/<target>/*

Each seed is a few hundred bytes; libFuzzer grows its working corpus from them
(scripts/check_fuzz.sh copies them to a scratch corpus so the repository stays unchanged)."""
import base64
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = os.path.join(HERE, "seeds")

# A square pyramid: 5 vertices, 4 triangles + 1 quad (closed), labels 11 (apex) and 0.
V = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0), (0.5, 0.5, 1.0)]
F = [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)]
VL = [0, 0, 0, 11, 11]
FL = [0, 11, 11, 11, 11]
TRIS = [(0, 2, 1), (0, 3, 2), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)]


def write(target, name, data):
    d = os.path.join(SEEDS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def ply():
    head = lambda fmt, xyz: (
        f"ply\nformat {fmt} 1.0\ncomment toothfuse seed\nelement vertex {len(V)}\n"
        f"property {xyz} x\nproperty {xyz} y\nproperty {xyz} z\nproperty int label\n"
        f"element face {len(F)}\nproperty list uchar int vertex_indices\n"
        "property ushort label\nend_header\n")
    text = head("ascii", "float") + "".join(
        f"{x} {y} {z} {l}\n" for (x, y, z), l in zip(V, VL)) + "".join(
        f"{len(f)} {' '.join(map(str, f))} {l}\n" for f, l in zip(F, FL))
    write("read_ply", "ascii.ply", text)
    for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        b = head(fmt, "double").encode()
        for (x, y, z), l in zip(V, VL):
            b += struct.pack(e + "dddi", x, y, z, l)
        for f, l in zip(F, FL):
            b += struct.pack(e + "B" + "i" * len(f) + "H", len(f), *f, l)
        write("read_ply", fmt + ".ply", b)


def stl():
    b = bytearray(b"binary seed".ljust(80, b" ")) + struct.pack("<I", len(TRIS))
    for t in TRIS:
        b += struct.pack("<3f", 0, 0, 0)
        for v in t:
            b += struct.pack("<3f", *V[v])
        b += b"\0\0"
    write("read_stl", "binary.stl", bytes(b))
    s = "solid seed\n"
    for t in TRIS:
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join(f"   vertex {V[v][0]} {V[v][1]} {V[v][2]}\n" for v in t)
        s += "  endloop\n endfacet\n"
    write("read_stl", "ascii.stl", s + "endsolid seed\n")


def obj():
    o = "# seed\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in V)
    o += "vn 0 0 1\nvt 0 0\ng jaw\n"
    o += "f 1/1/1 4/1/1 3/1/1 2/1/1\nf 1//1 2//1 5//1\nf 2 3 5\nf -3 -2 -1\nf 4 1 5\n"
    labels = '{"id_patient": "seed", "jaw": "upper", "labels": [%s], "instances": [%s]}' % (
        ", ".join(map(str, VL)), ", ".join("1" if l else "0" for l in VL))
    write("read_obj_labels", "labeled.obj", o + "\0" + labels)
    write("read_obj_labels", "plain.obj", o)


def vtk_legacy():
    pts = " ".join(f"{x} {y} {z}" for x, y, z in V)
    polys = "\n".join(f"{len(f)} {' '.join(map(str, f))}" for f in F)
    size = sum(len(f) + 1 for f in F)
    write("read_vtk_legacy", "ascii.vtk",
          f"# vtk DataFile Version 3.0\nseed\nASCII\nDATASET POLYDATA\nPOINTS {len(V)} float\n{pts}\n"
          f"POLYGONS {len(F)} {size}\n{polys}\nPOINT_DATA {len(V)}\nSCALARS label int 1\n"
          f"LOOKUP_TABLE default\n{' '.join(map(str, VL))}\nCELL_DATA {len(F)}\n"
          f"FIELD FieldData 1\nLabels 1 {len(F)} int\n{' '.join(map(str, FL))}\n")
    offs = [0]
    for f in F:
        offs.append(offs[-1] + len(f))
    conn = [i for f in F for i in f]
    write("read_vtk_legacy", "offsets.vtk",
          f"# vtk DataFile Version 5.1\nseed\nASCII\nDATASET POLYDATA\nPOINTS {len(V)} double\n{pts}\n"
          f"POLYGONS {len(offs)} {len(conn)}\nOFFSETS vtktypeint64\n{' '.join(map(str, offs))}\n"
          f"CONNECTIVITY vtktypeint64\n{' '.join(map(str, conn))}\n"
          f"POINT_DATA {len(V)}\nSCALARS label int 1\nLOOKUP_TABLE default\n{' '.join(map(str, VL))}\n")
    b = (f"# vtk DataFile Version 3.0\nseed\nBINARY\nDATASET POLYDATA\nPOINTS {len(V)} float\n").encode()
    b += b"".join(struct.pack(">3f", *p) for p in V)
    b += f"\nPOLYGONS {len(F)} {size}\n".encode()
    b += b"".join(struct.pack(">%di" % (len(f) + 1), len(f), *f) for f in F)
    b += f"\nCELL_DATA {len(F)}\nSCALARS label int 1\nLOOKUP_TABLE default\n".encode()
    b += struct.pack(">%di" % len(FL), *FL) + b"\n"
    write("read_vtk_legacy", "binary.vtk", b)


def vtp():
    conn = [i for f in F for i in f]
    offs = []
    for f in F:
        offs.append((offs[-1] if offs else 0) + len(f))
    pts = [c for p in V for c in p]
    arrays = [  # (section, type, name, components, struct code, values)
        ("PointData", "Int32", "Label", 1, "i", VL),
        ("CellData", "UInt8", "labels", 1, "B", FL),
        ("Points", "Float32", "Points", 3, "f", pts),
        ("Polys", "Int64", "connectivity", 1, "q", conn),
        ("Polys", "Int64", "offsets", 1, "q", offs),
    ]

    def doc(fmt_attr, body_of, header, appended=b""):
        out = [f'<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" '
               f'byte_order="LittleEndian" header_type="{header}"{fmt_attr}>\n<PolyData>\n'
               f'<Piece NumberOfPoints="{len(V)}" NumberOfPolys="{len(F)}">\n']
        for section in ("PointData", "CellData", "Points", "Polys"):
            out.append(f"<{section}>\n")
            for a in arrays:
                if a[0] == section:
                    out.append(body_of(a))
            out.append(f"</{section}>\n")
        out.append("</Piece>\n</PolyData>\n")
        if appended:
            out.append('<AppendedData encoding="raw">\n_')
            return "".join(out).encode() + appended + b"\n</AppendedData>\n</VTKFile>\n"
        return ("".join(out) + "</VTKFile>\n").encode()

    def tag(a, fmt, extra=""):
        return (f'<DataArray type="{a[1]}" Name="{a[2]}" NumberOfComponents="{a[3]}" '
                f'format="{fmt}"{extra}>')

    ascii_body = lambda a: tag(a, "ascii") + " ".join(map(str, a[5])) + "</DataArray>\n"
    write("read_vtp", "ascii.vtp", doc("", ascii_body, "UInt32"))

    raw = lambda a: struct.pack("<%d%s" % (len(a[5]), a[4]), *a[5])
    binary_body = lambda a: (tag(a, "binary") + base64.b64encode(
        struct.pack("<Q", len(raw(a))) + raw(a)).decode() + "</DataArray>\n")
    write("read_vtp", "binary_uint64.vtp", doc("", binary_body, "UInt64"))

    def compressed(a):
        data = raw(a)
        z = zlib.compress(data)
        return struct.pack("<4I", 1, len(data), len(data), len(z)) + z

    blob, offsets = b"", {}
    for a in arrays:
        offsets[a[2]] = len(blob)
        blob += compressed(a)
    app_body = lambda a: tag(a, "appended", f' offset="{offsets[a[2]]}"') + "</DataArray>\n"
    write("read_vtp", "appended_zlib.vtp",
          doc(' compressor="vtkZLibDataCompressor"', app_body, "UInt32", blob))


def ffi_fuse():
    # 8-byte records: op, target (u16 LE), value (4 bytes), tooth. Empty = the clean jaw.
    rec = lambda op, target, value, tooth=0: struct.pack("<BH4sB", op, target, value, tooth)
    f32 = lambda x: struct.pack("<f", x)
    write("ffi_fuse", "clean", b"")
    write("ffi_fuse", "nudged", rec(0, 17, bytes([5, 0, 0, 0])) + rec(1, 40, bytes([250, 0, 0, 0]), 2))
    write("ffi_fuse", "float_padded_face_labels", rec(14, 0, bytes([1, 1, 1, 0])))
    write("ffi_fuse", "repair_paper_ios_frame", rec(14, 0, bytes([0, 0, 0, 1])) + rec(15, 0, bytes([0, 1, 0, 0])))
    write("ffi_fuse", "nan_vertex", rec(2, 5, f32(float("nan"))))
    write("ffi_fuse", "bad_index", rec(4, 9, struct.pack("<I", 100000)))
    write("ffi_fuse", "metres", rec(10, 0, f32(0.001)))
    write("ffi_fuse", "mirrored", rec(12, 0, bytes(4)))
    write("ffi_fuse", "swapped_labels", rec(13, 0, struct.pack("<i", 21), 1) + rec(13, 0, struct.pack("<i", 11), 2))


if __name__ == "__main__":
    ply()
    stl()
    obj()
    vtk_legacy()
    vtp()
    ffi_fuse()

#!/usr/bin/env python3
"""Stand-in for `toothfuse demo --out DIR` until the CLI lands (used by make_demo.cmake only when
the CLI writes nothing). Writes the same files in the same format:

  DIR/ios.ply   binary little-endian PLY: double x/y/z, int `label` per vertex (FDI, 0 = gingiva);
                per tooth an open crown (top of an ellipsoid) ringed by two gingiva rings.
  DIR/cbct.ply  binary little-endian PLY: double x/y/z, int `label` per vertex; one closed
                ellipsoid per tooth.

Deterministic; coordinates are not representable in float, so float round trips are tested.
"""
import argparse
import math
import os
import struct

UPPER = [17, 16, 15, 14, 13, 12, 11, 21, 22, 23, 24, 25, 26, 27]


def tooth_frame(k, n):
    """Position of tooth k of n along a parabolic arch (mm)."""
    t = (k + 0.5) / n * 2.0 - 1.0  # -1 .. 1
    return (25.0 * t + 0.1234567, 18.0 * t * t + 0.7654321, 1.1111111)


def ring_points(c, rings, seg, a, b, h, z_of, r_of):
    pts = []
    for i in rings:
        for j in range(seg):
            phi = 2.0 * math.pi * j / seg
            r = r_of(i)
            pts.append((c[0] + a * r * math.cos(phi), c[1] + b * r * math.sin(phi), c[2] + z_of(i)))
    return pts


def sphere_mesh(c, a, b, h, rings, seg, open_below=None, gingiva_rings=0):
    """Lat-long ellipsoid. Returns (points, triangles, labels-as-flags: True = tooth)."""
    pts = [(c[0], c[1], c[2] + h)]  # top pole
    last = rings - 1 if open_below is None else open_below
    theta = lambda i: math.pi * i / rings
    tooth = [True]
    for i in range(1, last + 1):
        for p in ring_points(c, [i], seg, a, b, h, lambda i: h * math.cos(theta(i)),
                             lambda i: math.sin(theta(i))):
            pts.append(p)
            tooth.append(True)
    extra = 0
    if open_below is not None:
        # Gingiva rings flaring outward below the crown margin.
        r0 = math.sin(theta(last))
        z0 = h * math.cos(theta(last))
        for g in range(1, gingiva_rings + 1):
            for j in range(seg):
                phi = 2.0 * math.pi * j / seg
                r = r0 + 0.35 * g
                pts.append((c[0] + a * r * math.cos(phi), c[1] + b * r * math.sin(phi),
                            c[2] + z0 - 0.9 * g))
                tooth.append(False)
        extra = gingiva_rings
    else:
        pts.append((c[0], c[1], c[2] - h))  # bottom pole
        tooth.append(True)
    tris = []
    ring = lambda i, j: 1 + (i - 1) * seg + (j % seg)
    for j in range(seg):
        tris.append((0, ring(1, j), ring(1, j + 1)))
    for i in range(1, last + extra):
        for j in range(seg):
            a0, a1, b0, b1 = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            tris.append((a0, b0, b1))
            tris.append((a0, b1, a1))
    if open_below is None:
        bottom = len(pts) - 1
        for j in range(seg):
            tris.append((bottom, ring(last, j + 1), ring(last, j)))
    return pts, tris, tooth


def write_ply(path, pts, labels, tris):
    with open(path, "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\ncomment toothfuse test jaw\n")
        f.write(b"element vertex %d\n" % len(pts))
        f.write(b"property double x\nproperty double y\nproperty double z\nproperty int label\n")
        f.write(b"element face %d\n" % len(tris))
        f.write(b"property list uchar int vertex_indices\nend_header\n")
        for p, l in zip(pts, labels):
            f.write(struct.pack("<dddi", p[0], p[1], p[2], l))
        for t in tris:
            f.write(struct.pack("<Biii", 3, *t))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    ios_p, ios_l, ios_t, cb_p, cb_l, cb_t = [], [], [], [], [], []
    for k, fdi in enumerate(UPPER):
        c = tooth_frame(k, len(UPPER))
        a, b, h = 3.1 + 0.05 * k, 3.6, 10.3
        p, t, flag = sphere_mesh(c, a, b, h, rings=24, seg=32, open_below=8, gingiva_rings=2)
        off = len(ios_p)
        ios_p += p
        ios_l += [fdi if f else 0 for f in flag]
        ios_t += [(x + off, y + off, z + off) for x, y, z in t]
        p, t, _ = sphere_mesh(c, a, b, h, rings=20, seg=24)
        off = len(cb_p)
        cb_p += p
        cb_l += [fdi] * len(p)
        cb_t += [(x + off, y + off, z + off) for x, y, z in t]
    write_ply(os.path.join(args.out, "ios.ply"), ios_p, ios_l, ios_t)
    write_ply(os.path.join(args.out, "cbct.ply"), cb_p, cb_l, cb_t)


if __name__ == "__main__":
    main()

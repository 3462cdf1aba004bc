"""The one-call fuse of a whole labeled jaw (`fuse`, returning a `FusedJaw`) and the helpers
for preparing its input (`merge_meshes`, `is_fdi`), over the Session of _core.py."""

from ._abi import _TRANSFORMS, CBCT, IOS
from ._core import Session, _flat, _is_ndarray, _numpy


def is_fdi(n):
    """True for an FDI tooth number: 11-18 ... 41-48 (permanent), 51-55 ... 81-85 (primary)."""
    q, u = divmod(int(n), 10)
    return (1 <= q <= 4 and 1 <= u <= 8) or (5 <= q <= 8 and 1 <= u <= 5)


def merge_meshes(parts):
    """Merges labeled meshes (e.g. one CBCT tooth per object) into one jaw with per-face labels,
    for `fuse(..., cbct_per_face=True)`. parts: (vertices, triangles, labels, per_face) with
    flat or nested vertices/triangles; labels one per vertex (per_face False; a face takes the
    label of its vertices, which must agree) or one per face, or a single int for the whole
    mesh. Returns (flat vertex list, flat triangle list, per-face labels)."""
    xyz, tris, face_labels = [], [], []
    for k, (v, t, labels, per_face) in enumerate(parts):
        v, t = list(_flat(v)), list(_flat(t))
        if len(v) % 3 or len(t) % 3:
            raise ValueError(f"mesh {k}: coordinate or index count not a multiple of 3")
        base, nf = len(v) // 3, len(t) // 3
        if t and (min(t) < 0 or max(t) >= base):
            raise ValueError(f"mesh {k}: a triangle index is outside 0..{base - 1}")
        if isinstance(labels, int):
            fl = [labels] * nf
        elif per_face:
            fl = list(_flat(labels))
            if len(fl) != nf:
                raise ValueError(f"mesh {k}: {len(fl)} face labels for {nf} faces")
        else:
            vl = list(_flat(labels))
            if len(vl) != base:
                raise ValueError(f"mesh {k}: {len(vl)} vertex labels for {base} vertices")
            fl = []
            for f in range(nf):
                a, b, c = (vl[t[3 * f + i]] for i in range(3))
                if not a == b == c:
                    raise ValueError(f"mesh {k}: face {f} spans labels {a}, {b}, {c}")
                fl.append(a)
        off = len(xyz) // 3
        xyz.extend(v)
        tris.extend(i + off for i in t)
        face_labels.extend(int(x) for x in fl)
    return xyz, tris, face_labels


class FusedJaw:
    """Result of `fuse`: the fused jaw and what happened to each tooth.

    positions: vertex x, y, z (flat array('d'), or an (n, 3) numpy array); triangles: vertex
    indices (flat array('I'), or (m, 3) uint32); labels: per-vertex FDI (array('i') / int32);
    sources: per-vertex SOURCE_IOS, SOURCE_BAND or SOURCE_CBCT (array('B') / uint8); teeth: the
    fused FDI numbers; skipped: [(fdi, reason)]; quality: {fdi: dict}; transforms: {fdi:
    {"cbct_to_output": [16], "ios_to_output": [16], "cbct_to_ios": [16]}}; report: the
    report.json dict; frame: "cbct" or "ios"; questionable: True when the registration gate
    found the data questionable and `accept_questionable` let it through."""

    def __init__(self, **fields):
        self.__dict__.update(fields)

    def __repr__(self):
        return (f"FusedJaw(teeth={self.teeth}, skipped={[f for f, _ in self.skipped]}, "
                f"vertices={len(self.labels)}, frame={self.frame!r})")


def fuse(ios_vertices, ios_triangles, ios_labels, cbct_vertices, cbct_triangles, cbct_labels,
         *, ios_per_face=False, cbct_per_face=False, preset="default", frame="cbct",
         ios_repair=False, max_hole_fraction=0.5, as_numpy=None, accept_questionable=False,
         max_threads=0, progress=None):
    """One call: a labeled IOS jaw (FDI per vertex, or per face with ios_per_face; 0 =
    gingiva) and labeled CBCT teeth (one mesh with FDI labels; every tooth closed) -> FusedJaw.
    ios_repair repairs real-scan crowns on entry. Results are numpy arrays when as_numpy is
    True, or when it is None and numpy is installed and the IOS vertices are a numpy array.
    Raises ToothfuseError with the library's message (naming the tooth at fault): status
    STATUS_UNIT_MISMATCH for wrong units, STATUS_MIRRORED for a mirrored modality,
    STATUS_REGISTRATION_REJECTED for data that do not belong together (another patient, the other
    jaw, shifted labels). accept_questionable=True registers such data anyway; the result's
    `questionable` is then True and report["questionable_findings"] names the findings.
    max_threads caps the threads the call uses (0: no cap; 1: all on the calling thread); the
    results are the same whatever it is. progress: a callback(stage, done, total) as
    Session.set_progress takes it (a truthy return cancels: ToothfuseError, STATUS_CANCELLED)."""
    with Session() as s:
        s.set_max_threads(max_threads)
        s.set_progress(progress)
        if ios_repair:
            s.set_ios_repair(True, max_hole_fraction)
        s.add_jaw(IOS, ios_vertices, ios_triangles, ios_labels, per_face=ios_per_face)
        s.add_jaw(CBCT, cbct_vertices, cbct_triangles, cbct_labels, per_face=cbct_per_face)
        teeth = s.fuse(preset=preset, frame=frame, accept_questionable=accept_questionable)
        pos, idx, src, labels = s.fused_mesh(0)
        jaw = FusedJaw(
            positions=pos, triangles=idx, labels=labels, sources=src, teeth=teeth,
            skipped=s.skipped(), frame=frame, report=s.report(),
            questionable=bool(s.report().get("questionable", False)),
            quality={f: s.fused_quality(f) for f in teeth},
            transforms={f: {w: s.transform(f, w) for w in _TRANSFORMS} for f in teeth})
    if as_numpy is None:
        as_numpy = _is_ndarray(ios_vertices)
    if as_numpy:
        np = _numpy()
        if np is None:
            raise ImportError("as_numpy=True needs numpy")
        jaw.positions = np.frombuffer(pos, dtype=np.float64).reshape(-1, 3)
        jaw.triangles = np.frombuffer(idx, dtype=np.uint32).reshape(-1, 3)
        jaw.labels = np.frombuffer(labels, dtype=np.int32)
        jaw.sources = np.frombuffer(src, dtype=np.uint8)
    return jaw

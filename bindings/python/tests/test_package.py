"""pytest suite of the installed toothfuse package (run by scripts/test.sh in a fresh venv):
the bundled library, read_mesh on label arrays as dental tools write them, numpy in and out,
errors carrying status and message, and a fuse of a demo jaw read from files."""

import os
from pathlib import Path

import numpy as np
import pytest

import toothfuse

# A unit cube split into two open halves: vertices 0-3 bottom, 4-7 top.
CUBE = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0],
                 [0, 0, 2], [2, 0, 2], [2, 2, 2], [0, 2, 2]], dtype=np.float64)
TRIS = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                 [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


def write_ply(path, name, labels):
    """ASCII PLY with one int vertex property `name` (as tools such as MeshLab save it)."""
    lines = ["ply", "format ascii 1.0", f"element vertex {len(CUBE)}", "property double x",
             "property double y", "property double z", f"property int {name}",
             f"element face {len(TRIS)}", "property list uchar int vertex_indices", "end_header"]
    lines += [f"{x} {y} {z} {lab}" for (x, y, z), lab in zip(CUBE, labels)]
    lines += ["3 " + " ".join(map(str, t)) for t in TRIS]
    Path(path).write_text("\n".join(lines) + "\n")


def write_vtk(path, name, labels):
    """Legacy ASCII .vtk with a `RegionId` decoy and the label array `name` as SCALARS."""
    lines = ["# vtk DataFile Version 4.2", "t", "ASCII", "DATASET POLYDATA",
             f"POINTS {len(CUBE)} double"]
    lines += [f"{x} {y} {z}" for x, y, z in CUBE]
    lines += [f"POLYGONS {len(TRIS)} {4 * len(TRIS)}"]
    lines += ["3 " + " ".join(map(str, t)) for t in TRIS]
    lines += [f"POINT_DATA {len(CUBE)}", "FIELD FieldData 1", f"RegionId 1 {len(CUBE)} int"]
    lines += ["0"] * len(CUBE)
    lines += [f"SCALARS {name} int 1", "LOOKUP_TABLE default"] + [str(v) for v in labels]
    Path(path).write_text("\n".join(lines) + "\n")


def test_installed_package_uses_its_own_library():
    pkg = Path(toothfuse.__file__).resolve().parent
    assert (pkg / "py.typed").is_file()
    if "TOOTHFUSE_LIBRARY" not in os.environ:
        assert Path(toothfuse.LIBRARY_PATH).resolve() == (pkg / "libtoothfuse.so").resolve()
    assert toothfuse.abi_version() == toothfuse.ABI_VERSION
    assert toothfuse.version().count(".") == 2


@pytest.mark.parametrize("writer,ext", [(write_ply, "ply"), (write_vtk, "vtk")])
def test_universal_ids_are_detected_and_mapped_to_fdi(tmp_path, writer, ext):
    # Universal 3 (FDI 16) below, 33 (the DCBIA tools' gingiva) above.
    path = tmp_path / f"jaw.{ext}"
    writer(path, "UniversalID", [3] * 4 + [33] * 4)
    m = toothfuse.read_mesh(path)
    assert m.label_array == "UniversalID"
    assert m.numbering == "universal" and "UniversalID" in m.numbering_reason
    assert m.positions.dtype == np.float64 and m.positions.shape == (8, 3)
    assert m.triangles.dtype == np.uint32 and m.triangles.shape == (12, 3)
    np.testing.assert_array_equal(m.positions, CUBE)
    np.testing.assert_array_equal(m.labels, [16] * 4 + [0] * 4)
    assert m.face_labels is None
    assert any(a["name"] == "UniversalID" and a["on_points"] for a in m.arrays)
    by_name = toothfuse.read_mesh(path, label_array="UniversalID")
    np.testing.assert_array_equal(by_name.labels, m.labels)


def test_numbering_override_and_ambiguity(tmp_path):
    path = tmp_path / "jaw.ply"
    write_ply(path, "label", [11] * 4 + [12] * 4)  # valid FDI and Universal, one jaw either way
    with pytest.raises(toothfuse.ToothfuseError) as e:
        toothfuse.read_mesh(path)
    assert e.value.status_name == "invalid argument"
    assert "ambiguous" in str(e.value) and str(path) in str(e.value)
    np.testing.assert_array_equal(toothfuse.read_mesh(path, numbering="fdi").labels,
                                  [11] * 4 + [12] * 4)
    np.testing.assert_array_equal(toothfuse.read_mesh(path, numbering="universal").labels,
                                  [23] * 4 + [24] * 4)
    with pytest.raises(ValueError):
        toothfuse.read_mesh(path, numbering="palmer")


def test_missing_array_and_bad_file_raise_with_status_and_message(tmp_path):
    path = tmp_path / "jaw.vtk"
    write_vtk(path, "PredictedID", [0] * 8)
    with pytest.raises(toothfuse.ToothfuseError) as e:
        toothfuse.read_mesh(path, label_array="UniversalID")
    assert e.value.status != 0
    assert "UniversalID" in str(e.value) and "RegionId" in str(e.value)
    junk = tmp_path / "junk.ply"
    junk.write_text("not a mesh\n")
    with pytest.raises(toothfuse.ToothfuseError) as e:
        toothfuse.read_mesh(junk)
    assert str(junk) in str(e.value)
    with pytest.raises(toothfuse.ToothfuseError):
        toothfuse.read_mesh(tmp_path / "missing.stl")


def jaw_dir(k):
    root = os.environ.get("TOOTHFUSE_JAWS_DIR")
    if not root or not Path(root, f"jaw_{k}").is_dir():
        pytest.skip("TOOTHFUSE_JAWS_DIR is not set (scripts/test.sh points it at ctest's jaws)")
    return Path(root, f"jaw_{k}")


def test_fuse_a_demo_jaw_read_from_files():
    d = jaw_dir(2)
    ios = toothfuse.read_mesh(d / "ios.ply")
    cbct = toothfuse.read_mesh(d / "cbct.ply")
    assert ios.numbering == "fdi" and cbct.numbering == "fdi"
    jaw = toothfuse.fuse(ios.positions, ios.triangles, ios.labels,
                         cbct.positions, cbct.triangles, cbct.labels, frame="ios")
    assert isinstance(jaw.positions, np.ndarray) and jaw.positions.shape[1] == 3
    assert jaw.triangles.dtype == np.uint32
    teeth = sorted(set(np.unique(ios.labels)) - {0})
    assert jaw.teeth == [t for t in teeth if t in set(np.unique(cbct.labels))]
    assert sorted(set(jaw.labels.tolist())) == jaw.teeth
    assert all(q["watertight"] for q in jaw.quality.values()), jaw.quality


def test_fuse_on_one_thread_is_the_same():
    """max_threads=1 runs the whole call on the calling thread: the same jaw bit for bit; a
    negative cap is refused before reaching the library."""
    d = jaw_dir(2)
    ios = toothfuse.read_mesh(d / "ios.ply")
    cbct = toothfuse.read_mesh(d / "cbct.ply")
    args = (ios.positions, ios.triangles, ios.labels, cbct.positions, cbct.triangles, cbct.labels)
    one = toothfuse.fuse(*args, max_threads=1)
    free = toothfuse.fuse(*args)
    assert one.teeth == free.teeth and len(one.teeth) >= 3
    assert one.positions.tobytes() == free.positions.tobytes()
    assert np.array_equal(one.triangles, free.triangles)
    assert np.array_equal(one.labels, free.labels)
    with toothfuse.Session() as s:
        with pytest.raises(ValueError):
            s.set_max_threads(-1)
        s.set_max_threads(2)


def test_per_jaw_volume_is_split_with_the_ios_added_first():
    """A DentalSegmentator-style volume (3 upper teeth, 4 lower teeth) is split into teeth with
    the IOS crowns the session holds: without them it is refused, naming what to do, and the
    session keeps no CBCT tooth."""
    labels = np.zeros((12, 12, 12), dtype=np.uint8)
    labels[3:9, 3:9, 3:9] = 4
    with toothfuse.Session() as s:
        with pytest.raises(toothfuse.ToothfuseError) as e:
            s.add_label_volume(labels, spacing=(0.5, 0.5, 0.5), origin=(0, 0, 0),
                               scheme="dentalsegmentator")
        assert e.value.status_name == "missing data"
        assert "add the IOS teeth first" in str(e.value)
        # With an IOS crown too small to register as an arch: refused, nothing added.
        s.add_tooth(toothfuse.IOS, 36, CUBE, TRIS[2:])
        with pytest.raises(toothfuse.ToothfuseError) as e:
            s.add_label_volume(labels, spacing=(0.5, 0.5, 0.5), origin=(0, 0, 0),
                               scheme="dentalsegmentator")
        assert "too few to register the arch" in str(e.value)
        assert s.teeth(toothfuse.CBCT) == []


def test_label_volume_flipped_between_lps_and_ras():
    """flip_lps_ras negates the world x and y of the volume's mapping: the surfaced tooth is the
    unflipped one with x and y negated, whether the mapping is given as spacing + origin or as
    a matrix."""
    ii, jj, kk = np.indices((24, 24, 30))
    labels = np.zeros((24, 24, 30), dtype=np.uint8)
    labels[(ii - 11.5) ** 2 + (jj - 12) ** 2 + 0.5 * (kk - 15) ** 2 < 40] = 11
    spacing, origin = (0.4, 0.4, 0.4), (3.0, -2.0, 7.0)
    matrix = [[0.4, 0, 0, 3.0], [0, 0.4, 0, -2.0], [0, 0, 0.4, 7.0], [0, 0, 0, 1]]
    meshes = []
    for kw in [dict(spacing=spacing, origin=origin),
               dict(spacing=spacing, origin=origin, flip_lps_ras=True),
               dict(voxel_to_world=matrix, flip_lps_ras=True)]:
        with toothfuse.Session() as s:
            assert s.add_label_volume(labels, **kw) == 1
            pos, idx = s.mesh(toothfuse.CBCT, 11)
            meshes.append((np.array(pos).reshape(-1, 3), list(idx)))
    (p0, t0), (p1, t1), (p2, t2) = meshes
    assert len(p0) > 100 and p0[:, 0].min() > 2.9
    assert t1 == t2 and np.array_equal(p1, p2)
    assert len(p1) == len(p0)
    assert np.allclose(p1, p0 * [-1, -1, 1], atol=1e-9)


def _arch_cap(c, r, nu=32, nv=10):
    """Open upper cap (polar angle up to 1.9 rad) of a ball of radius r at c: (vertices, tris)."""
    pts = [np.array(c) + [0.0, 0.0, r]]
    for v in range(1, nv + 1):
        polar = v / nv * 1.9
        for u in range(nu):
            a = u / nu * 2 * np.pi
            pts.append(np.array(c) + r * np.array(
                [np.sin(polar) * np.cos(a), np.sin(polar) * np.sin(a), np.cos(polar)]))
    ring = lambda v, u: 1 + (v - 1) * nu + u % nu
    tris = [[0, ring(1, u), ring(1, u + 1)] for u in range(nu)]
    for v in range(1, nv):
        for u in range(nu):
            tris += [[ring(v, u), ring(v + 1, u), ring(v + 1, u + 1)],
                     [ring(v, u), ring(v + 1, u + 1), ring(v, u + 1)]]
    return np.array(pts), np.array(tris, dtype=np.uint32)


def test_per_jaw_volume_split_by_the_ios_crowns_of_a_synthetic_arch():
    """Six teeth (ball crowns of growing radius on cylinder roots, along a parabola) as one
    lower-teeth class 4; the IOS crowns are the balls' caps: every tooth is split and added, and
    after registration each carries its split confidence among its warnings."""
    fdis = [33, 32, 31, 41, 42, 43]
    centres = [(-20.0 + 8.0 * t, 0.03 * (-20.0 + 8.0 * t) ** 2, 0.0) for t in range(6)]
    radii = [2.4 + 0.25 * t for t in range(6)]
    h, origin = 0.3, np.array([-25.0, -4.0, -10.5])
    ii, jj, kk = np.indices((165, 70, 50))
    x, y, z = (origin[0] + h * ii, origin[1] + h * jj, origin[2] + h * kk)
    labels = np.zeros((165, 70, 50), dtype=np.uint8)
    for (cx, cy, cz), r in zip(centres, radii):
        ball = (x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2 < r * r
        root = ((x - cx) ** 2 + (y - cy) ** 2 < 1.5 ** 2) & (z < cz) & (z > cz - 9)
        labels[ball | root] = 4
    with toothfuse.Session() as s:
        for f, c, r in zip(fdis, centres, radii):
            v, t = _arch_cap(c, r)
            s.add_tooth(toothfuse.IOS, f, v, t)
        added = s.add_label_volume(labels, spacing=(h, h, h), origin=tuple(origin),
                                   scheme="dentalsegmentator")
        assert added == 6
        assert s.teeth(toothfuse.CBCT) == sorted(fdis)
        assert sorted(s.register(accept_questionable=True)) == sorted(fdis)
        for f in fdis:
            ws = s.tooth_report(f)["warnings"]
            assert any("split from the per-jaw teeth mask" in w for w in ws), (f, ws)


def _demo_args():
    d = jaw_dir(2)
    ios = toothfuse.read_mesh(d / "ios.ply")
    cbct = toothfuse.read_mesh(d / "cbct.ply")
    return (ios.positions, ios.triangles, ios.labels, cbct.positions, cbct.triangles, cbct.labels)


def test_progress_is_reported_stage_by_stage_and_changes_nothing():
    args = _demo_args()
    seen = []
    watched = toothfuse.fuse(*args, progress=lambda *r: seen.append(r))
    plain = toothfuse.fuse(*args)
    assert watched.positions.tobytes() == plain.positions.tobytes()
    assert np.array_equal(watched.triangles, plain.triangles)
    stages = [r[0] for r in seen]
    order = ["register", "cut", "stitch"]
    assert sorted(stages, key=order.index) == stages and set(stages) == set(order)
    for stage in order:
        of = [r for r in seen if r[0] == stage]
        assert of[0][1] == 0 and of[-1][1] == of[-1][2], of
        assert all(a[1] <= b[1] and a[2] == b[2] for a, b in zip(of, of[1:])), of
    assert [r[2] for r in seen if r[0] == "stitch"][-1] == len(plain.teeth)


def test_a_cancel_raises_cancelled_and_the_session_keeps_its_results():
    args = _demo_args()
    with toothfuse.Session() as s:
        s.add_jaw(toothfuse.IOS, *args[:3])
        s.add_jaw(toothfuse.CBCT, *args[3:])
        teeth = s.fuse()
        before = s.fused_mesh(0)
        report = s.report_json()
        # A truthy return cancels in the stage it is returned in.
        for stage in ["register", "cut", "stitch"]:
            s.set_progress(lambda st, done, total, stage=stage: st == stage)
            with pytest.raises(toothfuse.ToothfuseError) as e:
                s.fuse()
            assert e.value.status == toothfuse.STATUS_CANCELLED and stage in str(e.value)
        # An exception in the callback cancels and is raised again, the cancel as its cause.
        def boom(stage, done, total):
            if stage == "cut":
                raise ValueError("stop here")
        s.set_progress(boom)
        with pytest.raises(ValueError, match="stop here") as e:
            s.fuse()
        assert isinstance(e.value.__cause__, toothfuse.ToothfuseError)
        assert e.value.__cause__.status == toothfuse.STATUS_CANCELLED
        with pytest.raises(TypeError):
            s.set_progress(3)
        assert s.fused_teeth() == teeth and s.report_json() == report
        assert all(a.tobytes() == b.tobytes() for a, b in zip(before, s.fused_mesh(0)))
        s.set_progress(None)
        assert s.fuse() == teeth


def test_a_fuse_runs_where_sigint_is_ignored_or_a_hosts_own():
    """Without a progress callback and where Ctrl-C is not Python's (ignored, as under nohup or
    a shell's background job, or a host's own handler), the call runs unwatched: the same jaw
    as under Python's handler, the process's handler left in place."""
    import signal
    args = _demo_args()
    plain = toothfuse.fuse(*args)
    before = signal.getsignal(signal.SIGINT)

    def hosts(*_):
        pass

    try:
        for handler in (signal.SIG_IGN, hosts):
            signal.signal(signal.SIGINT, handler)
            r = toothfuse.fuse(*args)
            assert signal.getsignal(signal.SIGINT) is handler
            assert r.teeth == plain.teeth and len(r.teeth) >= 3
            assert r.positions.tobytes() == plain.positions.tobytes()
            with toothfuse.Session() as s:
                s.add_jaw(toothfuse.IOS, *args[:3])
                s.add_jaw(toothfuse.CBCT, *args[3:])
                s.fuse()
                assert s.fused_teeth() == plain.teeth
    finally:
        signal.signal(signal.SIGINT, before)


def test_a_fuse_runs_on_a_worker_thread():
    """A host's worker thread (a GUI keeping its own thread free) runs the call unwatched, as
    Ctrl-C belongs to the main thread: the same jaw as on the main thread."""
    import threading
    args = _demo_args()
    plain = toothfuse.fuse(*args)
    out = {}

    def work():
        try:
            out["r"] = toothfuse.fuse(*args)
        except BaseException as e:  # re-raised on the test's thread below
            out["e"] = e

    t = threading.Thread(target=work)
    t.start()
    t.join()
    if "e" in out:
        raise out["e"]
    assert out["r"].teeth == plain.teeth and len(plain.teeth) >= 3
    assert out["r"].positions.tobytes() == plain.positions.tobytes()


def test_ctrl_c_cancels_a_running_fuse_without_a_callback():
    import _thread
    import signal
    import threading
    import time
    args = _demo_args()
    # Python's own Ctrl-C handler, whatever the test runner was started under (a background
    # job ignores SIGINT, and interrupt_main then does nothing).
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _ctrl_c_cancels(args, _thread, threading, time)
    finally:
        signal.signal(signal.SIGINT, before)


def _ctrl_c_cancels(args, _thread, threading, time):
    with toothfuse.Session() as s:
        s.add_jaw(toothfuse.IOS, *args[:3])
        s.add_jaw(toothfuse.CBCT, *args[3:])
        # Ctrl-C while the library runs: the interrupt waits for the next progress report,
        # where it cancels the call and is raised from it.
        delay = 0.05
        timer = threading.Timer(delay, _thread.interrupt_main)
        start = time.monotonic()
        timer.start()
        try:
            s.fuse()
        except KeyboardInterrupt as e:
            assert isinstance(e.__cause__, toothfuse.ToothfuseError)
            assert e.__cause__.status == toothfuse.STATUS_CANCELLED
            with pytest.raises(toothfuse.ToothfuseError):
                s.fused_teeth()  # nothing fused: the session holds what it held before
            return
        finally:
            timer.cancel()
        # The interrupt can only be missed by a call that ended before it was sent.
        assert time.monotonic() - start < delay + 0.01
        pytest.skip("the fuse ended before the interrupt")


def test_a_label_volume_reports_its_surfacing_and_a_cancel_adds_nothing():
    ii, jj, kk = np.indices((24, 24, 30))
    labels = np.zeros((24, 24, 30), dtype=np.uint8)
    labels[(ii - 11.5) ** 2 + (jj - 12) ** 2 + 0.5 * (kk - 15) ** 2 < 40] = 11
    with toothfuse.Session() as s:
        s.set_progress(lambda stage, done, total: stage == "surface")
        with pytest.raises(toothfuse.ToothfuseError) as e:
            s.add_label_volume(labels, spacing=(0.4, 0.4, 0.4), origin=(0, 0, 0))
        assert e.value.status == toothfuse.STATUS_CANCELLED
        assert s.teeth(toothfuse.CBCT) == []
        seen = []
        s.set_progress(lambda *r: seen.append(r))
        assert s.add_label_volume(labels, spacing=(0.4, 0.4, 0.4), origin=(0, 0, 0)) == 1
        assert seen[0] == ("surface", 0, 1) and seen[-1] == ("surface", 1, 1)

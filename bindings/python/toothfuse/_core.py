"""The Python API of the toothfuse package over the library's C ABI (declared in _abi.py).

    import toothfuse
    with toothfuse.Session() as s:
        s.add_tooth(toothfuse.CBCT, 46, vertices, triangles)   # vertices: flat x,y,z (mm)
        s.teeth(toothfuse.CBCT)                                # [46]
        positions, indices = s.mesh(toothfuse.CBCT, 46)

    # One call: labeled IOS jaw + labeled CBCT teeth -> fused jaw (register, cut, stitch).
    jaw = toothfuse.fuse(ios_vertices, ios_triangles, ios_labels,
                         cbct_vertices, cbct_triangles, cbct_labels, frame="ios")
    jaw.positions, jaw.triangles, jaw.labels, jaw.sources, jaw.teeth, jaw.skipped, jaw.report

Vertices are any flat sequence of floats (list, tuple, array.array('d'/'f')); triangles any flat
sequence of ints, 3 per triangle. array.array('f') input is passed as float32 without copying
through Python floats; everything else as float64. numpy arrays (any shape, e.g. (n, 3)) are
accepted when numpy is installed: float32/float64 pass without a copy, and `fuse` then returns
numpy arrays ((n, 3) positions, (m, 3) triangles); otherwise results are array.array values.
The library and its C functions are declared in _abi.py. Errors raise ToothfuseError carrying
the status and the session's detailed message.
"""

import array
import ctypes
import json
import signal
import threading

from ._abi import (  # noqa: F401 (some only re-exported: __init__, _files, the tests)
    ABI_VERSION,
    CBCT,
    IOS,
    LIBRARY_PATH,
    SOURCE_BAND,
    SOURCE_CBCT,
    SOURCE_IOS,
    STATUS_CANCELLED,
    STATUS_MIRRORED,
    STATUS_REGISTRATION_REJECTED,
    STATUS_UNIT_MISMATCH,
    ToothfuseError,
    _FACE,
    _FLOAT32,
    _FLOAT64,
    _FRAMES,
    _FusedQuality,
    _MeshInfo,
    _NO_PROGRESS,
    _OK,
    _Options,
    _PRESETS,
    _PROGRESS_FN,
    _S,
    _STAGES,
    _TRANSFORMS,
    _ToothReport,
    _VERTEX,
    _add_jaw,
    _add_tooth,
    _add_volume,
    _copy_ci,
    _copy_cl,
    _copy_cv,
    _copy_fi,
    _copy_fl,
    _copy_fs,
    _copy_fv,
    _copy_i,
    _copy_s,
    _copy_v,
    _count,
    _crossings,
    _cut,
    _cut_size,
    _cut_teeth,
    _d_p,
    _dropped,
    _fn,
    _free,
    _fuse,
    _fuse_registered,
    _fused_size,
    _fused_teeth,
    _i32_p,
    _info,
    _last_error,
    _list,
    _new,
    _opts_default,
    _quality,
    _register,
    _registered,
    _remove,
    _report,
    _report_json,
    _set_progress,
    _set_repair,
    _set_threads,
    _size,
    _size_p,
    _skipped,
    _skipped_count,
    _st,
    _stitch,
    _transform,
    _trim,
    _u32_p,
    _warning,
    abi_version,
    version,
)

__all__ = ["Session", "ToothfuseError", "IOS", "CBCT", "version", "abi_version", "SOURCE_IOS", "SOURCE_BAND", "SOURCE_CBCT", "STATUS_UNIT_MISMATCH",
           "STATUS_MIRRORED", "STATUS_REGISTRATION_REJECTED", "STATUS_CANCELLED"]


def _numpy():
    """The numpy module when installed, else None (numpy is optional)."""
    try:
        import numpy
    except ImportError:
        return None
    return numpy


def _is_ndarray(x):
    return hasattr(x, "__array_interface__") and _numpy() is not None


def _vertex_buffer(vertices):
    if _is_ndarray(vertices):  # float32 stays float32 (no copy when contiguous)
        np = _numpy()
        dt = np.float32 if vertices.dtype == np.float32 else np.float64
        arr = np.ascontiguousarray(vertices, dtype=dt).reshape(-1)
        if arr.size % 3:
            raise ValueError(f"{arr.size} vertex coordinates is not a multiple of 3")
        ptr = arr.ctypes.data if arr.size else None
        scalar = _FLOAT32 if dt == np.float32 else _FLOAT64
        return arr, ptr, arr.size // 3, 3 * arr.itemsize, scalar
    if isinstance(vertices, array.array) and vertices.typecode == "f":
        arr, scalar = vertices, _FLOAT32
    elif isinstance(vertices, array.array) and vertices.typecode == "d":
        arr, scalar = vertices, _FLOAT64
    else:
        arr, scalar = array.array("d", _flat(vertices)), _FLOAT64
    if len(arr) % 3:
        raise ValueError(f"{len(arr)} vertex coordinates is not a multiple of 3")
    ptr = arr.buffer_info()[0] if len(arr) else None
    return arr, ptr, len(arr) // 3, 3 * arr.itemsize, scalar


def _flat(values):
    """A flat list/array of numbers from a flat or nested sequence or a numpy array."""
    if _is_ndarray(values):
        return values.reshape(-1).tolist()
    if len(values) and isinstance(values[0], (list, tuple)):
        return [v for row in values for v in row]
    return values


def _u32_buffer(values):
    arr = array.array("I", _flat(values))
    assert arr.itemsize == 4
    return arr, ctypes.cast(arr.buffer_info()[0], _u32_p) if len(arr) else None


class Session:
    """A toothfuse session: tooth meshes per modality (IOS, CBCT), keyed by FDI number.
    Not thread-safe; use one per thread or lock around it."""

    def __init__(self):
        self._h = ctypes.c_void_p()
        st = _new(ctypes.byref(self._h))
        if st != _OK:
            raise ToothfuseError(st, "")
        # The progress callback (None: none), the exception it raised during the last call, and
        # whether Ctrl-C was pressed during it.
        self._progress = [None, None, False]
        self._trampoline = _PROGRESS_FN(_trampoline_of(self._progress))

    def close(self):
        """Frees the session (also done by `with` and on garbage collection)."""
        if self._h:
            _free(self._h)
            self._h = ctypes.c_void_p()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def _check(self, st):
        if st != _OK:
            raise ToothfuseError(st, _last_error(self._h).decode())

    def _long_call(self, fn, *args):
        """Runs register/fuse/cut/stitch/add_label_volume `fn` on this session with `args`,
        with the progress callback, and with Ctrl-C
        cancelling it: on the main thread, while Python's own SIGINT handler is in place, the
        call runs under a handler that only notes the interrupt (raised at the next progress
        report, a KeyboardInterrupt would be lost in the C callback); the callback then cancels
        the call and the KeyboardInterrupt is raised from it. Other handlers (a host's) are left
        alone."""
        progress = self._progress
        progress[1:] = [None, False]
        previous = None
        if (threading.current_thread() is threading.main_thread()
                and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
            previous = signal.signal(signal.SIGINT, lambda *_: progress.__setitem__(2, True))
        try:
            watched = progress[0] is not None or previous is not None
            # No callback: a null function pointer (ctypes refuses None for a CFUNCTYPE).
            self._check(_set_progress(self._h, self._trampoline if watched else _NO_PROGRESS, None))
            st = fn(self._h, *args)
        finally:
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
        raised = progress[1] if progress[1] is not None else (
            KeyboardInterrupt() if progress[2] else None)
        progress[1:] = [None, False]
        if st != _OK:
            error = ToothfuseError(st, _last_error(self._h).decode())
            if raised is not None:
                raise raised from error
            raise error
        if raised is not None:  # after the call's last report: the work was done
            raise raised

    def add_tooth(self, modality, fdi, vertices, triangles):
        """Adds or replaces one tooth (IOS crown: manifold, open; CBCT: closed, manifold)."""
        v, vp, n, stride, scalar = _vertex_buffer(vertices)
        t, tp = _u32_buffer(triangles)
        self._check(_add_tooth(self._h, modality, fdi, vp, n, stride, scalar, tp, len(t)))

    def add_jaw(self, modality, vertices, triangles, labels, per_face=False):
        """Splits a labeled jaw (FDI per vertex, or per face; 0 = gingiva, dropped) into teeth,
        all or nothing. Returns the FDI numbers now held."""
        v, vp, n, stride, scalar = _vertex_buffer(vertices)
        t, tp = _u32_buffer(triangles)
        lab = array.array("i", _flat(labels))
        assert lab.itemsize == 4
        lp = ctypes.cast(lab.buffer_info()[0], _i32_p) if len(lab) else None
        self._check(_add_jaw(self._h, modality, vp, n, stride, scalar, tp, len(t), lp, len(lab),
                             _FACE if per_face else _VERTEX))
        return self.teeth(modality)

    def add_label_volume(self, labels, dims=None, voxel_to_world=None, spacing=None,
                         origin=None, scheme="fdi", flip_lps_ras=False):
        """Adds the CBCT teeth of a label volume (one label per tooth), each surfaced to a closed
        mesh in the world frame of voxel_to_world (16 floats, row-major 4x4, voxel index ->
        mm; e.g. nibabel's img.affine for RAS, or an LPS matrix) or of spacing + origin (axis-
        aligned). labels: a 3-D numpy array indexed [i, j, k] (nibabel's order), or a flat
        array('B'/'H'/'h'/'i') / list with i fastest plus dims. scheme: "fdi", "universal",
        "toothfairy2" or "dentalsegmentator" (one teeth label per jaw, 3 upper and 4 lower: split
        into teeth with the IOS teeth already added, so add the IOS first; each tooth's split,
        its contested share or why it was refused, is in the warnings / skipped notes after
        register or fuse). flip_lps_ras negates the world x and y of the mapping (an LPS
        matrix becomes RAS and back: e.g. nibabel's RAS affine for meshes in LPS, as 3D Slicer
        and ITK write them). All or nothing. Returns the number of teeth added."""
        schemes = {"fdi": 0, "universal": 1, "toothfairy2": 2, "dentalsegmentator": 3}
        if scheme not in schemes:
            raise ValueError(f"scheme {scheme!r} is not one of {sorted(schemes)}")
        if _is_ndarray(labels):
            np = _numpy()
            if labels.ndim != 3:
                raise ValueError(f"labels must be a 3-D array, got shape {labels.shape}")
            dims = labels.shape
            codes = {np.dtype(np.uint8): (0, "B"), np.dtype(np.uint16): (1, "H"),
                     np.dtype(np.int16): (2, "h"), np.dtype(np.int32): (3, "i")}
            if labels.dtype not in codes:
                if labels.size and (labels.min() < 0 or labels.max() > 65535):
                    raise ValueError("labels must be 0-65535")
                labels = labels.astype(np.int32)
            ltype, _ = codes[labels.dtype]
            flat = np.ascontiguousarray(labels.ravel(order="F"))
            ptr, count = flat.ctypes.data_as(ctypes.c_void_p), flat.size
            keep = flat
        else:
            if dims is None:
                raise ValueError("dims (nx, ny, nz) is needed with flat labels")
            tc = labels.typecode if isinstance(labels, array.array) else None
            types = {"B": 0, "H": 1, "h": 2, "i": 3}
            arr = labels if tc in types else array.array("i", _flat(labels))
            ltype = types[arr.typecode]
            count = len(arr)
            ptr = ctypes.c_void_p(arr.buffer_info()[0]) if count else None
            keep = arr
        d = (ctypes.c_size_t * 3)(*[int(x) for x in dims])
        m = sp = org = None
        if voxel_to_world is None and (spacing is None or origin is None):
            raise ValueError("give voxel_to_world, or spacing and origin")
        if voxel_to_world is not None or flip_lps_ras:
            if voxel_to_world is not None:
                rows = [float(x) for x in _flat(voxel_to_world)]
                if len(rows) != 16:
                    raise ValueError(f"voxel_to_world needs 16 values, got {len(rows)}")
            else:
                (sx, sy, sz), (ox, oy, oz) = spacing, origin
                rows = [sx, 0, 0, ox, 0, sy, 0, oy, 0, 0, sz, oz, 0, 0, 0, 1]
            if flip_lps_ras:
                rows = [-float(x) for x in rows[:8]] + [float(x) for x in rows[8:]]
            m = (ctypes.c_double * 16)(*rows)
        else:
            sp = (ctypes.c_double * 3)(*[float(x) for x in spacing])
            org = (ctypes.c_double * 3)(*[float(x) for x in origin])
        added = ctypes.c_size_t()
        cast = lambda a: ctypes.cast(a, _d_p) if a is not None else None
        self._long_call(_add_volume, ctypes.cast(d, _size_p), cast(m), cast(sp), cast(org), ptr,
                        count, ltype, schemes[scheme], ctypes.byref(added))
        del keep
        return added.value

    def set_ios_repair(self, enabled, max_hole_fraction=0.5):
        """Repair IOS crowns on entry (real scans need it); off by default."""
        self._check(_set_repair(self._h, enabled, max_hole_fraction))

    def set_max_threads(self, n):
        """Caps the threads this session's calls use at n in all (0, the default: no cap; 1: every
        call on the calling thread). The results are the same bit for bit whatever the cap."""
        if not 0 <= int(n) < 2**32:
            raise ValueError(f"max_threads {n} is not in [0, 2**32)")
        self._check(_set_threads(self._h, int(n)))

    def set_progress(self, callback):
        """Calls callback(stage, done, total) during this session's register, fuse,
        fuse_registered, cut, stitch and add_label_volume: `done` of `total` units of `stage`
        ("register", "cut", "stitch" or "surface") are finished. It runs on the calling thread. A truthy return value cancels
        the call, which raises ToothfuseError with status STATUS_CANCELLED; an exception raised
        by the callback cancels it too and is raised again from the call. The session keeps its
        earlier results either way. None removes the callback. Without one, Ctrl-C
        (KeyboardInterrupt) still cancels a running call the same way. The results are the same
        bit for bit with or without a callback."""
        if callback is not None and not callable(callback):
            raise TypeError(f"progress callback {callback!r} is not callable")
        self._progress[0] = callback

    def remove_tooth(self, modality, fdi):
        """Removes a held tooth."""
        self._check(_remove(self._h, modality, fdi))

    def teeth(self, modality):
        """FDI numbers held for `modality`, ascending."""
        n = ctypes.c_size_t()
        self._check(_count(self._h, modality, ctypes.byref(n)))
        out = (ctypes.c_int32 * max(n.value, 1))()
        written = ctypes.c_size_t()
        self._check(_list(self._h, modality, out, n.value, ctypes.byref(written)))
        return list(out[: written.value])

    def mesh(self, modality, fdi, scalar="d"):
        """(positions, indices) of a held tooth as array.array('d' or 'f') and array('I')."""
        nv, ni = ctypes.c_size_t(), ctypes.c_size_t()
        self._check(_size(self._h, modality, fdi, ctypes.byref(nv), ctypes.byref(ni)))
        pos = array.array(scalar, bytes(3 * nv.value * array.array(scalar).itemsize))
        kind = _FLOAT32 if scalar == "f" else _FLOAT64
        if nv.value:
            self._check(_copy_v(self._h, modality, fdi, pos.buffer_info()[0], nv.value,
                                3 * pos.itemsize, kind))
        idx = array.array("I", bytes(4 * ni.value))
        if ni.value:
            self._check(_copy_i(self._h, modality, fdi,
                                ctypes.cast(idx.buffer_info()[0], _u32_p), ni.value))
        return pos, idx

    def source_vertices(self, modality, fdi):
        """For each vertex of the tooth, its index in the buffer it was added from."""
        nv, ni = ctypes.c_size_t(), ctypes.c_size_t()
        self._check(_size(self._h, modality, fdi, ctypes.byref(nv), ctypes.byref(ni)))
        out = array.array("I", bytes(4 * nv.value))
        if nv.value:
            self._check(_copy_s(self._h, modality, fdi,
                                ctypes.cast(out.buffer_info()[0], _u32_p), nv.value))
        return out

    def info(self, modality, fdi):
        """Topology facts as a dict (boundary_loops, closed, manifold, signed_volume, ...)."""
        i = _MeshInfo()
        self._check(_info(self._h, modality, fdi, ctypes.byref(i)))
        return {name: getattr(i, name) for name, _ in _MeshInfo._fields_}

    # --- registration and fusion ---------------------------------------------------------------

    def register(self, preset="default", frame="cbct", accept_questionable=False):
        """Registers the held CBCT teeth to the held IOS crowns; returns the registered FDI
        numbers. preset: "default" or "paper"; frame: "cbct" or "ios" (the output frame)."""
        self._long_call(_register, ctypes.byref(_options(preset, frame, accept_questionable)))
        return self._fdi_list(_registered)

    def fuse(self, preset="default", frame="cbct", accept_questionable=False):
        """Register + cut + stitch in one call (registers anew); returns the fused FDI numbers.
        Teeth whose fusion failed are listed by `skipped()`."""
        self._long_call(_fuse, ctypes.byref(_options(preset, frame, accept_questionable)))
        return self._fdi_list(_fused_teeth)

    def fuse_registered(self, preset="default"):
        """Cut + stitch with the last registration (no new registration; the output frame is
        the registration's; only the fusion settings of `preset` are used); returns the fused
        FDI numbers."""
        self._long_call(_fuse_registered, ctypes.byref(_options(preset, "cbct")))
        return self._fdi_list(_fused_teeth)

    def cut(self, preset="default"):
        """Crown removal with the last registration (the first fusion stage); returns the cut
        FDI numbers. The cut is kept for `stitch` until the teeth change or a new register or
        fuse; read it with `cut_root`."""
        self._long_call(_cut, ctypes.byref(_options(preset, "cbct")))
        return self._fdi_list(_cut_teeth)

    def stitch(self, preset="default"):
        """Stitching of the held cut (the second fusion stage); returns the fused FDI numbers,
        read with `fused_mesh`. Same meshes as `fuse_registered`, bit for bit."""
        self._long_call(_stitch, ctypes.byref(_options(preset, "cbct")))
        return self._fdi_list(_fused_teeth)

    def cut_teeth(self):
        """FDI numbers of the cut teeth (after cut)."""
        return self._fdi_list(_cut_teeth)

    def cut_root(self, fdi, scalar="d"):
        """The cut CBCT root of a tooth (output frame) as (positions array('d' or 'f'), indices
        array('I'), cut loop array('I'): the root's one boundary loop, root vertex indices)."""
        nv, ni, nl = ctypes.c_size_t(), ctypes.c_size_t(), ctypes.c_size_t()
        self._check(_cut_size(self._h, fdi, ctypes.byref(nv), ctypes.byref(ni), ctypes.byref(nl)))
        pos = array.array(scalar, bytes(3 * nv.value * array.array(scalar).itemsize))
        kind = _FLOAT32 if scalar == "f" else _FLOAT64
        idx = array.array("I", bytes(4 * ni.value))
        loop = array.array("I", bytes(4 * nl.value))
        self._check(_copy_cv(self._h, fdi, pos.buffer_info()[0], nv.value, 3 * pos.itemsize,
                             kind))
        self._check(_copy_ci(self._h, fdi, ctypes.cast(idx.buffer_info()[0], _u32_p), ni.value))
        self._check(_copy_cl(self._h, fdi, ctypes.cast(loop.buffer_info()[0], _u32_p), nl.value))
        return pos, idx, loop

    def _fdi_list(self, fn):
        out = (ctypes.c_int32 * 52)()
        n = ctypes.c_size_t()
        self._check(fn(self._h, out, 52, ctypes.byref(n)))
        return list(out[: n.value])

    def registered_teeth(self):
        """FDI numbers of the registered teeth (after register or fuse)."""
        return self._fdi_list(_registered)

    def fused_teeth(self):
        """FDI numbers of the fused teeth (after fuse)."""
        return self._fdi_list(_fused_teeth)

    def transform(self, fdi, which="cbct_to_output"):
        """A registered tooth's 4x4 rigid transform as 16 floats, row-major; which:
        "cbct_to_output", "ios_to_output" or "cbct_to_ios"."""
        if which not in _TRANSFORMS:
            raise ValueError(f"unknown transform {which!r}; one of {sorted(_TRANSFORMS)}")
        out = (ctypes.c_double * 16)()
        self._check(_transform(self._h, fdi, _TRANSFORMS[which], out))
        return list(out)

    def tooth_report(self, fdi):
        """Registration report of a tooth as a dict (sd_mm, rmse_mm, inlier_fraction,
        fine_correction_mm, iterations, converged, warnings: [str])."""
        r = _ToothReport()
        self._check(_report(self._h, fdi, ctypes.byref(r)))
        d = {name: getattr(r, name) for name, _ in _ToothReport._fields_}
        warnings = []
        for i in range(r.warning_count):
            w = ctypes.c_char_p()
            self._check(_warning(self._h, fdi, i, ctypes.byref(w)))
            warnings.append(w.value.decode())
        del d["warning_count"]
        d["warnings"] = warnings
        return d

    def skipped(self):
        """Teeth of the last result that were not registered/fused: [(fdi, reason)]."""
        n = ctypes.c_size_t()
        self._check(_skipped_count(self._h, ctypes.byref(n)))
        out = []
        for i in range(n.value):
            f, reason = ctypes.c_int32(), ctypes.c_char_p()
            self._check(_skipped(self._h, i, ctypes.byref(f), ctypes.byref(reason)))
            out.append((f.value, reason.value.decode()))
        return out

    def report_json(self):
        """The report of the last result as JSON text (the CLI's report.json)."""
        n = ctypes.c_size_t()
        self._check(_report_json(self._h, None, 0, ctypes.byref(n)))
        buf = ctypes.create_string_buffer(n.value + 1)
        self._check(_report_json(self._h, buf, n.value + 1, ctypes.byref(n)))
        return buf.value.decode()

    def report(self):
        """The report of the last result, parsed (dict)."""
        return json.loads(self.report_json())

    def fused_mesh(self, fdi=0):
        """A fused mesh (fdi 0 = the whole jaw) as (positions array('d'), indices array('I'),
        sources array('B'), labels array('i') for the jaw or None for one tooth)."""
        nv, ni = ctypes.c_size_t(), ctypes.c_size_t()
        self._check(_fused_size(self._h, fdi, ctypes.byref(nv), ctypes.byref(ni)))
        pos = array.array("d", bytes(24 * nv.value))
        idx = array.array("I", bytes(4 * ni.value))
        src = array.array("B", bytes(nv.value))
        if nv.value:
            self._check(_copy_fv(self._h, fdi, pos.buffer_info()[0], nv.value, 24, _FLOAT64))
            self._check(_copy_fs(self._h, fdi,
                                 ctypes.cast(src.buffer_info()[0], ctypes.POINTER(ctypes.c_uint8)),
                                 nv.value))
        if ni.value:
            self._check(_copy_fi(self._h, fdi, ctypes.cast(idx.buffer_info()[0], _u32_p),
                                 ni.value))
        labels = None
        if fdi == 0:
            labels = array.array("i", bytes(4 * nv.value))
            assert labels.itemsize == 4
            if nv.value:
                self._check(_copy_fl(self._h, ctypes.cast(labels.buffer_info()[0], _i32_p),
                                     nv.value))
        return pos, idx, src, labels

    def fused_quality(self, fdi):
        """Quality of a fused tooth as a dict (closed, manifold, watertight, components,
        boundary_edges, volume, self_intersections (None when not checked), ...,
        ios_vertices_trimmed and ios_trim_reach_mm: IOS crown vertices dropped from the folded
        margin fringe and their largest distance from the margin in mm; ios_vertices_dropped:
        IOS crown vertices the crown repair dropped (stray tooth-labelled islands given back to
        the gingiva, vertices in no face); band_crossings_left:
        intersecting face pairs the fusion added and left (with a band face, or with a face
        added to the crown: a hole's cap, a slit's strip), 0 when it added none;
        ios_self_intersections: the input crown's own intersecting face pairs, kept)."""
        q = _FusedQuality()
        self._check(_quality(self._h, fdi, ctypes.byref(q)))
        d = {name: getattr(q, name) for name, _ in _FusedQuality._fields_}
        if d["self_intersections"] == ctypes.c_size_t(-1).value:
            d["self_intersections"] = None
        trimmed, reach = ctypes.c_size_t(), ctypes.c_double()
        self._check(_trim(self._h, fdi, ctypes.byref(trimmed), ctypes.byref(reach)))
        d["ios_vertices_trimmed"] = trimmed.value
        d["ios_trim_reach_mm"] = reach.value
        dropped = ctypes.c_size_t()
        self._check(_dropped(self._h, fdi, ctypes.byref(dropped)))
        d["ios_vertices_dropped"] = dropped.value
        band, own = ctypes.c_size_t(), ctypes.c_size_t()
        self._check(_crossings(self._h, fdi, ctypes.byref(band), ctypes.byref(own)))
        d["band_crossings_left"] = band.value
        d["ios_self_intersections"] = own.value
        return d


def _trampoline_of(progress):
    """The C callback of a session: cancels once Ctrl-C was noted (progress[2]), else calls
    progress[0] (if set) and, when it raises, keeps the exception in progress[1] and cancels the
    call (`Session._long_call` raises it again)."""

    def trampoline(_user_data, stage, done, total):
        if progress[2]:
            return 1
        try:
            callback = progress[0]
            return 1 if callback is not None and callback(_STAGES.get(stage, str(stage)),
                                                           done, total) else 0
        except BaseException as e:  # noqa: BLE001 - raised again from the call
            progress[1] = e
            return 1

    return trampoline


def _options(preset, frame, accept_questionable=False):
    o = _Options()
    st = _opts_default(ctypes.byref(o))
    if st != _OK:
        raise ToothfuseError(st, "")
    if preset not in _PRESETS:
        raise ValueError(f"unknown preset {preset!r}; one of {sorted(_PRESETS)}")
    if frame not in _FRAMES:
        raise ValueError(f"unknown frame {frame!r}; one of {sorted(_FRAMES)}")
    o.preset, o.frame = _PRESETS[preset], _FRAMES[frame]
    o.accept_questionable = 1 if accept_questionable else 0
    return o

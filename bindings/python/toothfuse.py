"""Python bindings for toothfuse over its C ABI (ctypes; no third-party packages).

    import toothfuse
    with toothfuse.Session() as s:
        s.add_tooth(toothfuse.CBCT, 46, vertices, triangles)   # vertices: flat x,y,z (mm)
        s.teeth(toothfuse.CBCT)                                # [46]
        positions, indices = s.mesh(toothfuse.CBCT, 46)

Vertices are any flat sequence of floats (list, tuple, array.array('d'/'f')); triangles any flat
sequence of ints, 3 per triangle. array.array('f') input is passed as float32 without copying
through Python floats; everything else as float64. The library is found from the environment
variable TOOTHFUSE_LIBRARY, else as libtoothfuse.so.<major> / libtoothfuse.so on the loader path.
Errors raise ToothfuseError carrying the status and the session's detailed message.
"""

import array
import ctypes
import os

__all__ = ["Session", "ToothfuseError", "IOS", "CBCT", "version", "abi_version"]

IOS = 0
CBCT = 1
_FLOAT32 = 0
_FLOAT64 = 1
_VERTEX = 0
_FACE = 1
_OK = 0
ABI_VERSION = 1


def _load():
    names = [os.environ.get("TOOTHFUSE_LIBRARY"), "libtoothfuse.so.0", "libtoothfuse.so"]
    last = None
    for name in names:
        if not name:
            continue
        try:
            return ctypes.CDLL(name)
        except OSError as e:  # try the next name
            last = e
    raise OSError(f"cannot load the toothfuse library (set TOOTHFUSE_LIBRARY): {last}")


_lib = _load()
_size_p = ctypes.POINTER(ctypes.c_size_t)
_u32_p = ctypes.POINTER(ctypes.c_uint32)
_i32_p = ctypes.POINTER(ctypes.c_int32)


class _MeshInfo(ctypes.Structure):
    _fields_ = [
        ("vertex_count", ctypes.c_size_t),
        ("triangle_count", ctypes.c_size_t),
        ("boundary_edges", ctypes.c_size_t),
        ("boundary_loops", ctypes.c_size_t),
        ("longest_loop_vertices", ctypes.c_size_t),
        ("components", ctypes.c_size_t),
        ("closed", ctypes.c_bool),
        ("manifold", ctypes.c_bool),
        ("signed_volume", ctypes.c_double),
        ("area", ctypes.c_double),
    ]


def _fn(name, restype, *argtypes):
    f = getattr(_lib, name)
    f.restype = restype
    f.argtypes = list(argtypes)
    return f


_S = ctypes.c_void_p
_st = ctypes.c_uint32
_version = _fn("toothfuse_version", ctypes.c_char_p)
_abi_version = _fn("toothfuse_abi_version", ctypes.c_uint32)
_status_string = _fn("toothfuse_status_string", ctypes.c_char_p, ctypes.c_uint32)
_new = _fn("toothfuse_session_new", _st, ctypes.POINTER(ctypes.c_void_p))
_free = _fn("toothfuse_session_free", None, _S)
_last_error = _fn("toothfuse_session_last_error", ctypes.c_char_p, _S)
_buf = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t, ctypes.c_uint32, _u32_p, ctypes.c_size_t]
_add_tooth = _fn("toothfuse_session_add_tooth", _st, _S, ctypes.c_uint32, ctypes.c_int32, *_buf)
_add_jaw = _fn("toothfuse_session_add_jaw", _st, _S, ctypes.c_uint32, *_buf, _i32_p,
               ctypes.c_size_t, ctypes.c_uint32)
_set_repair = _fn("toothfuse_session_set_ios_repair", _st, _S, ctypes.c_bool, ctypes.c_double)
_remove = _fn("toothfuse_session_remove_tooth", _st, _S, ctypes.c_uint32, ctypes.c_int32)
_count = _fn("toothfuse_session_tooth_count", _st, _S, ctypes.c_uint32, _size_p)
_list = _fn("toothfuse_session_list_teeth", _st, _S, ctypes.c_uint32, _i32_p, ctypes.c_size_t,
            _size_p)
_size = _fn("toothfuse_session_mesh_size", _st, _S, ctypes.c_uint32, ctypes.c_int32, _size_p,
            _size_p)
_copy_v = _fn("toothfuse_session_copy_vertices", _st, _S, ctypes.c_uint32, ctypes.c_int32,
              ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t, ctypes.c_uint32)
_copy_i = _fn("toothfuse_session_copy_indices", _st, _S, ctypes.c_uint32, ctypes.c_int32, _u32_p,
              ctypes.c_size_t)
_copy_s = _fn("toothfuse_session_copy_source_vertices", _st, _S, ctypes.c_uint32, ctypes.c_int32,
              _u32_p, ctypes.c_size_t)
_info = _fn("toothfuse_session_mesh_info", _st, _S, ctypes.c_uint32, ctypes.c_int32,
            ctypes.POINTER(_MeshInfo))


def version():
    """The library version, "MAJOR.MINOR.PATCH"."""
    return _version().decode()


def abi_version():
    """The C ABI version the library implements."""
    return _abi_version()


if abi_version() != ABI_VERSION:
    raise ImportError(f"toothfuse ABI {abi_version()} but these bindings expect {ABI_VERSION}")


class ToothfuseError(Exception):
    """A failed call: `status` (int), `status_name` (static text) and the detailed message."""

    def __init__(self, status, message):
        self.status = status
        self.status_name = _status_string(status).decode()
        super().__init__(f"{self.status_name}: {message}" if message else self.status_name)


def _vertex_buffer(vertices):
    if isinstance(vertices, array.array) and vertices.typecode == "f":
        arr, scalar = vertices, _FLOAT32
    elif isinstance(vertices, array.array) and vertices.typecode == "d":
        arr, scalar = vertices, _FLOAT64
    else:
        arr, scalar = array.array("d", vertices), _FLOAT64
    if len(arr) % 3:
        raise ValueError(f"{len(arr)} vertex coordinates is not a multiple of 3")
    ptr = arr.buffer_info()[0] if len(arr) else None
    return arr, ptr, len(arr) // 3, 3 * arr.itemsize, scalar


def _u32_buffer(values):
    arr = array.array("I", values)
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
        lab = array.array("i", labels)
        assert lab.itemsize == 4
        lp = ctypes.cast(lab.buffer_info()[0], _i32_p) if len(lab) else None
        self._check(_add_jaw(self._h, modality, vp, n, stride, scalar, tp, len(t), lp, len(lab),
                             _FACE if per_face else _VERTEX))
        return self.teeth(modality)

    def set_ios_repair(self, enabled, max_hole_fraction=0.5):
        """Repair IOS crowns on entry (real scans need it); off by default."""
        self._check(_set_repair(self._h, enabled, max_hole_fraction))

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

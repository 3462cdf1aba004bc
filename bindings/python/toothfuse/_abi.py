"""The toothfuse library loaded over ctypes: its C ABI's constants, structures and functions
declared once (argument and result types), the version check, and the error type every failed
call raises. The Python API over them is in _core.py.

The library is found from the environment variable TOOTHFUSE_LIBRARY, else the libtoothfuse.so
shipped inside the installed package, else as libtoothfuse.so.<major> / libtoothfuse.so on the
loader path.
"""

import ctypes
import os

IOS = 0
CBCT = 1
SOURCE_IOS = 0
SOURCE_BAND = 1
SOURCE_CBCT = 2
STATUS_UNIT_MISMATCH = 6
STATUS_MIRRORED = 14
STATUS_REGISTRATION_REJECTED = 15
STATUS_CANCELLED = 16
_STAGES = {1: "register", 2: "cut", 3: "stitch", 4: "surface"}
_PRESETS = {"paper": 0, "default": 1}
_FRAMES = {"cbct": 0, "ios": 1}
_TRANSFORMS = {"cbct_to_output": 0, "ios_to_output": 1, "cbct_to_ios": 2}
_FLOAT32 = 0
_FLOAT64 = 1
_VERTEX = 0
_FACE = 1
_OK = 0
ABI_VERSION = 2


_BUNDLED = os.path.join(os.path.dirname(os.path.abspath(__file__)), "libtoothfuse.so")


def _load():
    bundled = _BUNDLED if os.path.exists(_BUNDLED) else None
    names = [os.environ.get("TOOTHFUSE_LIBRARY"), bundled, "libtoothfuse.so.0", "libtoothfuse.so"]
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
LIBRARY_PATH = _lib._name
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


class _Options(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("preset", ctypes.c_uint32),
                ("frame", ctypes.c_uint32), ("accept_questionable", ctypes.c_uint32)]


class _ToothReport(ctypes.Structure):
    _fields_ = [
        ("sd_mm", ctypes.c_double),
        ("rmse_mm", ctypes.c_double),
        ("inlier_fraction", ctypes.c_double),
        ("fine_correction_mm", ctypes.c_double),
        ("iterations", ctypes.c_size_t),
        ("warning_count", ctypes.c_size_t),
        ("converged", ctypes.c_bool),
    ]


class _FusedQuality(ctypes.Structure):
    _fields_ = [
        ("volume", ctypes.c_double),
        ("band_min_angle_deg", ctypes.c_double),
        ("band_edge_mean", ctypes.c_double),
        ("components", ctypes.c_size_t),
        ("boundary_edges", ctypes.c_size_t),
        ("non_manifold_edges", ctypes.c_size_t),
        ("non_manifold_vertices", ctypes.c_size_t),
        ("self_intersections", ctypes.c_size_t),
        ("degenerate_faces", ctypes.c_size_t),
        ("band_faces", ctypes.c_size_t),
        ("crown_vertices", ctypes.c_size_t),
        ("closed", ctypes.c_bool),
        ("manifold", ctypes.c_bool),
        ("watertight", ctypes.c_bool),
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
_d_p = ctypes.POINTER(ctypes.c_double)
_add_volume = _fn("toothfuse_session_add_label_volume", _st, _S, _size_p, _d_p, _d_p, _d_p,
                  ctypes.c_void_p, ctypes.c_size_t, ctypes.c_uint32, ctypes.c_uint32, _size_p)
_set_repair = _fn("toothfuse_session_set_ios_repair", _st, _S, ctypes.c_bool, ctypes.c_double)
_set_threads = _fn("toothfuse_session_set_max_threads", _st, _S, ctypes.c_uint32)
_PROGRESS_FN = ctypes.CFUNCTYPE(ctypes.c_int32, ctypes.c_void_p, ctypes.c_uint32, ctypes.c_size_t,
                                ctypes.c_size_t)
_set_progress = _fn("toothfuse_session_set_progress", _st, _S, _PROGRESS_FN, ctypes.c_void_p)
_NO_PROGRESS = _PROGRESS_FN()
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
_opts_default = _fn("toothfuse_options_default", _st, ctypes.POINTER(_Options))
_register = _fn("toothfuse_session_register", _st, _S, ctypes.POINTER(_Options))
_fuse = _fn("toothfuse_session_fuse", _st, _S, ctypes.POINTER(_Options))
_fuse_registered = _fn("toothfuse_session_fuse_registered", _st, _S, ctypes.POINTER(_Options))
_cut = _fn("toothfuse_session_cut", _st, _S, ctypes.POINTER(_Options))
_stitch = _fn("toothfuse_session_stitch", _st, _S, ctypes.POINTER(_Options))
_cut_teeth = _fn("toothfuse_session_cut_teeth", _st, _S, _i32_p, ctypes.c_size_t, _size_p)
_cut_size = _fn("toothfuse_session_cut_size", _st, _S, ctypes.c_int32, _size_p, _size_p, _size_p)
_copy_cv = _fn("toothfuse_session_copy_cut_vertices", _st, _S, ctypes.c_int32, ctypes.c_void_p,
               ctypes.c_size_t, ctypes.c_size_t, ctypes.c_uint32)
_copy_ci = _fn("toothfuse_session_copy_cut_indices", _st, _S, ctypes.c_int32, _u32_p,
               ctypes.c_size_t)
_copy_cl = _fn("toothfuse_session_copy_cut_loop", _st, _S, ctypes.c_int32, _u32_p,
               ctypes.c_size_t)
_registered = _fn("toothfuse_session_registered_teeth", _st, _S, _i32_p, ctypes.c_size_t, _size_p)
_fused_teeth = _fn("toothfuse_session_fused_teeth", _st, _S, _i32_p, ctypes.c_size_t, _size_p)
_transform = _fn("toothfuse_session_transform", _st, _S, ctypes.c_int32, ctypes.c_uint32,
                 ctypes.POINTER(ctypes.c_double))
_report = _fn("toothfuse_session_tooth_report", _st, _S, ctypes.c_int32,
              ctypes.POINTER(_ToothReport))
_warning = _fn("toothfuse_session_tooth_warning", _st, _S, ctypes.c_int32, ctypes.c_size_t,
               ctypes.POINTER(ctypes.c_char_p))
_skipped_count = _fn("toothfuse_session_skipped_count", _st, _S, _size_p)
_skipped = _fn("toothfuse_session_skipped", _st, _S, ctypes.c_size_t, _i32_p,
               ctypes.POINTER(ctypes.c_char_p))
_report_json = _fn("toothfuse_session_report_json", _st, _S, ctypes.c_char_p, ctypes.c_size_t,
                   _size_p)
_fused_size = _fn("toothfuse_session_fused_size", _st, _S, ctypes.c_int32, _size_p, _size_p)
_copy_fv = _fn("toothfuse_session_copy_fused_vertices", _st, _S, ctypes.c_int32, ctypes.c_void_p,
               ctypes.c_size_t, ctypes.c_size_t, ctypes.c_uint32)
_copy_fi = _fn("toothfuse_session_copy_fused_indices", _st, _S, ctypes.c_int32, _u32_p,
               ctypes.c_size_t)
_copy_fs = _fn("toothfuse_session_copy_fused_sources", _st, _S, ctypes.c_int32,
               ctypes.POINTER(ctypes.c_uint8), ctypes.c_size_t)
_copy_fl = _fn("toothfuse_session_copy_fused_labels", _st, _S, _i32_p, ctypes.c_size_t)
_quality = _fn("toothfuse_session_fused_quality", _st, _S, ctypes.c_int32,
               ctypes.POINTER(_FusedQuality))
_trim = _fn("toothfuse_session_fused_trim", _st, _S, ctypes.c_int32,
            ctypes.POINTER(ctypes.c_size_t), ctypes.POINTER(ctypes.c_double))
_dropped = _fn("toothfuse_session_fused_dropped", _st, _S, ctypes.c_int32,
               ctypes.POINTER(ctypes.c_size_t))
_crossings = _fn("toothfuse_session_fused_crossings", _st, _S, ctypes.c_int32,
                 ctypes.POINTER(ctypes.c_size_t), ctypes.POINTER(ctypes.c_size_t))


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

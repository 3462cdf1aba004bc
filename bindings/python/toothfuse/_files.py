"""Reading mesh files through the library (toothfuse_session_read_file): PLY, STL, OBJ with a
Teeth3DS JSON, VTK XML PolyData (.vtp) and legacy VTK (.vtk), labels converted to FDI."""

from __future__ import annotations

import ctypes
import json
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Optional, Union

from ._core import _OK, _S, Session, ToothfuseError, _fn, _st

if TYPE_CHECKING:  # numpy is imported when a file is read (the ctypes layer works without it)
    import numpy as np
    import numpy.typing as npt

_NUMBERING = {"auto": 0, "fdi": 1, "universal": 2, "meshlabeler": 3}
_F = ctypes.c_void_p


class _MeshView(ctypes.Structure):
    _fields_ = [
        ("positions", ctypes.POINTER(ctypes.c_double)),
        ("vertex_count", ctypes.c_size_t),
        ("indices", ctypes.POINTER(ctypes.c_uint32)),
        ("index_count", ctypes.c_size_t),
    ]


_read = _fn("toothfuse_session_read_file", _st, _S, ctypes.c_char_p, ctypes.c_char_p,
            ctypes.c_uint32, ctypes.POINTER(ctypes.c_void_p))
_file_free = _fn("toothfuse_mesh_file_free", None, _F)
_file_view = _fn("toothfuse_mesh_file_view", _st, _F, ctypes.POINTER(_MeshView))
_file_labels = _fn("toothfuse_mesh_file_labels", _st, _F, ctypes.c_uint32,
                   ctypes.POINTER(ctypes.POINTER(ctypes.c_int32)),
                   ctypes.POINTER(ctypes.c_size_t))
_file_desc = _fn("toothfuse_mesh_file_description", ctypes.c_char_p, _F)


@dataclass
class MeshFile:
    """A mesh read from a file. `positions` (n, 3) float64 in mm, `triangles` (m, 3) uint32,
    `labels` the per-vertex FDI labels (0 = gingiva) or None, `face_labels` the per-triangle
    ones or None; `label_array` the array they came from, `numbering` how its numbers were read
    ("fdi", "universal", "meshlabeler") and `numbering_reason` why; `arrays` every
    one-component array of the file ({"name", "on_points", "type"})."""

    positions: npt.NDArray[np.float64]
    triangles: npt.NDArray[np.uint32]
    labels: Optional[npt.NDArray[np.int32]] = None
    face_labels: Optional[npt.NDArray[np.int32]] = None
    label_array: Optional[str] = None
    numbering: Optional[str] = None
    numbering_reason: Optional[str] = None
    arrays: list[dict[str, Any]] = field(default_factory=list)


def _copy_labels(handle: ctypes.c_void_p, domain: int) -> Optional[npt.NDArray[np.int32]]:
    import numpy as np

    p = ctypes.POINTER(ctypes.c_int32)()
    n = ctypes.c_size_t()
    st = _file_labels(handle, domain, ctypes.byref(p), ctypes.byref(n))
    if st != _OK:
        raise ToothfuseError(st, "reading the labels of a mesh file")
    if not p:
        return None
    return np.ctypeslib.as_array(p, shape=(n.value,)).copy()


def read_mesh(path: Union[str, os.PathLike[str]], label_array: Optional[str] = None,
              numbering: str = "auto") -> MeshFile:
    """Reads a mesh file by extension (.ply, .stl, .obj (+ Teeth3DS .json beside it), .vtp,
    .vtk). `label_array` names the label array (point or cell data; PLY vertex or face
    property); None picks the first known name (label, labels, UniversalID, PredictedID, FDI,
    ...). `numbering` is "auto" (from the array name or the values; ambiguous values are
    refused), "fdi", "universal" or "meshlabeler". Raises ToothfuseError (status and message
    naming the file) on failure, ValueError on an unknown `numbering`."""
    import numpy as np

    if numbering not in _NUMBERING:
        raise ValueError(f"numbering {numbering!r} is not one of {sorted(_NUMBERING)}")
    name = os.fspath(path).encode()
    arr = label_array.encode() if label_array is not None else None
    with Session() as s:
        h = ctypes.c_void_p()
        s._check(_read(s._h, name, arr, _NUMBERING[numbering], ctypes.byref(h)))
    try:
        v = _MeshView()
        st = _file_view(h, ctypes.byref(v))
        if st != _OK:
            raise ToothfuseError(st, "reading a mesh file's geometry")
        pos = (np.ctypeslib.as_array(v.positions, shape=(v.vertex_count * 3,)).copy()
               if v.vertex_count else np.zeros(0, np.float64))
        idx = (np.ctypeslib.as_array(v.indices, shape=(v.index_count,)).copy()
               if v.index_count else np.zeros(0, np.uint32))
        desc = json.loads(_file_desc(h).decode())
        return MeshFile(
            positions=pos.reshape(-1, 3),
            triangles=idx.astype(np.uint32).reshape(-1, 3),
            labels=_copy_labels(h, 0),
            face_labels=_copy_labels(h, 1),
            label_array=desc["label_array"],
            numbering=desc["numbering"],
            numbering_reason=desc["numbering_reason"],
            arrays=desc["arrays"],
        )
    finally:
        _file_free(h)

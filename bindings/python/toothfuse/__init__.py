"""toothfuse for Python: fuse intraoral-scan crowns with CBCT roots, over the library's C ABI.

    import toothfuse
    ios = toothfuse.read_mesh("ios.vtp")                  # labels from Label/UniversalID/...,
    cbct = toothfuse.read_mesh("cbct.ply")                # converted to FDI (0 = gingiva)
    jaw = toothfuse.fuse(ios.positions, ios.triangles, ios.labels,
                         cbct.positions, cbct.triangles, cbct.labels, frame="ios")
    jaw.positions, jaw.triangles, jaw.labels, jaw.sources, jaw.report

    with toothfuse.Session() as s:                         # tooth by tooth
        s.add_tooth(toothfuse.CBCT, 46, vertices, triangles)

numpy arrays go in and come out (`read_mesh` and `fuse` with numpy input return numpy arrays);
failures raise ToothfuseError carrying `status`, `status_name` and the library's message. The
installed package ships its own libtoothfuse.so (TOOTHFUSE_LIBRARY overrides it).
"""

from ._core import (
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
    Session,
    ToothfuseError,
    abi_version,
    version,
)
from ._jaw import FusedJaw, fuse, is_fdi, merge_meshes
from ._files import MeshFile, read_mesh

__all__ = [
    "ABI_VERSION", "CBCT", "IOS", "LIBRARY_PATH", "SOURCE_BAND", "SOURCE_CBCT", "SOURCE_IOS",
    "STATUS_CANCELLED", "STATUS_MIRRORED", "STATUS_REGISTRATION_REJECTED", "STATUS_UNIT_MISMATCH",
    "FusedJaw", "MeshFile", "Session", "ToothfuseError", "abi_version", "fuse", "is_fdi",
    "merge_meshes", "read_mesh", "version",
]

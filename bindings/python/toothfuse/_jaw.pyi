# Type hints of the one-call fuse (the implementation is toothfuse/_jaw.py).
from typing import Any, Callable, Optional, Sequence

Buffer = Any  # a flat or (n, 3) sequence, array.array or numpy array

def is_fdi(n: int) -> bool: ...
def merge_meshes(parts: Sequence[tuple[Buffer, Buffer]]) -> tuple[Any, Any, Any]: ...

class FusedJaw:
    positions: Any
    triangles: Any
    labels: Any
    sources: Any
    teeth: list[int]
    skipped: list[tuple[int, str]]
    quality: dict[int, dict[str, Any]]
    transforms: dict[int, dict[str, list[float]]]
    report: dict[str, Any]
    frame: str
    def __init__(self, **fields: Any) -> None: ...

def fuse(ios_vertices: Buffer, ios_triangles: Buffer, ios_labels: Buffer, cbct_vertices: Buffer,
         cbct_triangles: Buffer, cbct_labels: Buffer, *, ios_per_face: bool = ...,
         cbct_per_face: bool = ..., preset: str = ..., frame: str = ..., ios_repair: bool = ...,
         max_hole_fraction: float = ..., as_numpy: Optional[bool] = ...,
         accept_questionable: bool = ..., max_threads: int = ...,
         progress: Optional[Callable[[str, int, int], Any]] = ...) -> FusedJaw: ...

"""Open3D's point-to-plane ICP on the point sets `icp_compare export` wrote (see
examples/icp_compare.rs): per tooth, IOS crown points as the source, CBCT tooth vertices with
toothfuse's normals as the target, the shared initial pose, the manifest's correspondence
distance and iteration count with the convergence tests disabled.

    python icp_open3d.py MANIFEST_DIR RESULT_JSON

Writes the same fields as `icp_compare run`: the IOS -> CBCT estimate per tooth, `call_ms` (one
registration_icp call: Open3D builds the target's k-d tree, pairs the points once, then runs the
iterations) and `loop_ms` (that call less a call with no iteration: the iterations alone).
OMP_NUM_THREADS, set by the caller, chooses Open3D's thread count.
"""

import json
import sys
import time
from pathlib import Path

import numpy as np
import open3d as o3d

reg = o3d.pipelines.registration


def points(path: Path) -> o3d.utility.Vector3dVector:
    return o3d.utility.Vector3dVector(np.fromfile(path, dtype="<f8").reshape(-1, 3))


def timed_icp(source, target, max_dist: float, init: np.ndarray, iterations: int):
    # Thresholds of 0 are never undercut: every one of the iterations runs.
    criteria = reg.ICPConvergenceCriteria(relative_fitness=0.0, relative_rmse=0.0,
                                          max_iteration=iterations)
    t0 = time.perf_counter()
    result = reg.registration_icp(source, target, max_dist, init,
                                  reg.TransformationEstimationPointToPlane(), criteria)
    return result, (time.perf_counter() - t0) * 1e3


def main() -> None:
    root, out = Path(sys.argv[1]), Path(sys.argv[2])
    manifest = json.loads((root / "manifest.json").read_text())
    iterations, max_dist = manifest["iterations"], manifest["max_correspondence_mm"]
    cases = []
    for case in manifest["cases"]:
        rows = []
        for tooth in case["teeth"]:
            d = root / tooth["dir"]
            source = o3d.geometry.PointCloud(points(d / "source.f64"))
            target = o3d.geometry.PointCloud(points(d / "cbct_vertices.f64"))
            target.normals = points(d / "target_normals.f64")
            init = np.fromfile(d / "initial.f64", dtype="<f8").reshape(4, 4)
            result, call_ms = timed_icp(source, target, max_dist, init, iterations)
            _, setup_ms = timed_icp(source, target, max_dist, init, 0)
            rows.append({
                "fdi": tooth["fdi"],
                "ios_to_cbct": np.asarray(result.transformation).ravel().tolist(),
                "iterations": iterations,
                "loop_ms": call_ms - setup_ms,
                "call_ms": call_ms,
            })
        cases.append({"name": case["name"], "teeth": rows})
    out.write_text(json.dumps({"cases": cases}, indent=1))


if __name__ == "__main__":
    main()

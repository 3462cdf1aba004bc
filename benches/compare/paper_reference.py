"""The paper's section 2 as written, built from Open3D, SciPy and VTK: the reference that
`benches/compare/run.sh` times and scores `toothfuse fuse` against.

    python paper_reference.py --ios ios.ply --cbct cbct.ply --out DIR

Inputs: a labelled IOS jaw and labelled CBCT teeth (binary PLY, per-vertex FDI label, 0 = gingiva).
Outputs, in the CBCT frame like `toothfuse fuse`: DIR/tooth_<fdi>.ply per tooth and
DIR/transforms.json (the estimated IOS -> CBCT map per tooth, 4x4 row-major).

1. Centroid alignment, eq. (1): the rigid fit of the CBCT tooth vertex centroids to the IOS ones.
2. Coarse registration, eq. (2): one Open3D point-to-plane ICP for the whole jaw.
3. Fine registration, eq. (3): groups of three neighbouring teeth in arch order, registered in
   sequence, each group's result applied to its teeth before the next group.
4. Crown removal: the IOS margin mapped onto the CBCT tooth, the CBCT vertices nearest to it
   joined by SciPy Dijkstra shortest paths, the tooth split along that cut, the crown side dropped.
5. Stitching, Algorithm 1: points interpolated recursively between the IOS margin and the CBCT
   cut, voxel downsampling at 0.05 mm, vtkDelaunay3D + vtkDataSetSurfaceFilter, the result
   appended to the crown and the root.

Where Open3D cannot follow the text, or the paper leaves a value open, the comment at the
constant or function says what was chosen.
"""

import argparse
import json
from pathlib import Path

import numpy as np
import open3d as o3d
import vtk
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree
from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray

from plyio import read_ply, split_by_label

# The paper gates no pair; Open3D needs a distance. 10 mm keeps every pair after centroid
# alignment (which leaves the teeth a few millimetres off).
MAX_CORRESPONDENCE_MM = 10.0
# The paper gives no iteration cap or threshold: Open3D's default thresholds, 50 iterations.
ICP_CRITERIA = o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=50)
# Algorithm 1's parameters, not given in the paper: neighbours N, points per segment K, depth m.
NEIGHBOURS, POINTS_PER_SEGMENT, DEPTH = 3, 3, 2
# Radius of the Dijkstra searches between consecutive cut anchors (mm).
CUT_SEARCH_MM = 5.0
# Algorithm 1, line 6: voxel downsampling at 0.05 mm.
VOXEL_MM = 0.05


def arch_order(fdis: list[int]) -> list[int]:
    """Teeth from one end of the arch to the other: quadrant 1 or 4 from the molars to the
    central incisor, then quadrant 2 or 3 from the central incisor to the molars."""
    return sorted(fdis, key=lambda f: -(f % 10) if f // 10 in (1, 4) else f % 10)


def rigid_fit(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Eq. (1): the rigid 4x4 transform minimising sum |dst - R(src)|^2 (Kabsch)."""
    cs, cd = src.mean(axis=0), dst.mean(axis=0)
    u, _, vt = np.linalg.svd((src - cs).T @ (dst - cd))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = rot, cd - rot @ cs
    return t


def apply(t: np.ndarray, pts: np.ndarray) -> np.ndarray:
    return pts @ t[:3, :3].T + t[:3, 3]


def point_to_plane_icp(source: np.ndarray, target: np.ndarray, target_normals: np.ndarray,
                       init: np.ndarray) -> np.ndarray:
    """Open3D's point-to-plane ICP; returns the source -> target transform."""
    src = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(source))
    tgt = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(target))
    tgt.normals = o3d.utility.Vector3dVector(target_normals)
    return o3d.pipelines.registration.registration_icp(
        src, tgt, MAX_CORRESPONDENCE_MM, init,
        o3d.pipelines.registration.TransformationEstimationPointToPlane(), ICP_CRITERIA,
    ).transformation


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(vertices),
                                     o3d.utility.Vector3iVector(triangles))
    mesh.compute_vertex_normals()
    return np.asarray(mesh.vertex_normals)


def register(ios: dict, cbct: dict, order: list[int]) -> dict[int, np.ndarray]:
    """Eqs. (1)-(3); returns the IOS -> CBCT transform of each tooth in `order`.

    Open3D's point-to-plane ICP pairs each source point with its nearest target point and
    measures the residual along the target's normal. Eq. (2) pairs each IOS point with the
    nearest CBCT vertex of the same tooth, along the CBCT normal: here IOS is the source and CBCT
    the target (the residual is the same whichever side moves), but the nearest CBCT vertex is
    searched over the whole jaw, since Open3D takes one point cloud. Eq. (3) measures the
    residual along the IOS normal; Open3D uses the CBCT normal.
    """
    normals = {f: vertex_normals(*cbct[f]) for f in order}
    cent = rigid_fit(np.array([cbct[f][0].mean(axis=0) for f in order]),
                     np.array([ios[f][0].mean(axis=0) for f in order]))
    coarse = point_to_plane_icp(np.concatenate([ios[f][0] for f in order]),
                                np.concatenate([cbct[f][0] for f in order]),
                                np.concatenate([normals[f] for f in order]),
                                np.linalg.inv(cent))
    ios_to_cbct = {f: coarse.copy() for f in order}
    groups = [order] if len(order) <= 3 else [order[i:i + 3] for i in range(len(order) - 2)]
    for group in groups:
        step = point_to_plane_icp(
            np.concatenate([apply(ios_to_cbct[f], ios[f][0]) for f in group]),
            np.concatenate([cbct[f][0] for f in group]),
            np.concatenate([normals[f] for f in group]),
            np.eye(4))
        for f in group:
            ios_to_cbct[f] = step @ ios_to_cbct[f]
    return ios_to_cbct


def mesh_edges(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each edge once, as (lower, higher) vertex index, and the number of faces it borders."""
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    n = int(triangles.max()) + 1
    keys, count = np.unique(edges[:, 0] * n + edges[:, 1], return_counts=True)
    return np.stack(np.divmod(keys, n), axis=1), count


def boundary_loop(triangles: np.ndarray) -> np.ndarray:
    """The longest loop of boundary edges (edges of one face): the IOS margin, or the CBCT cut."""
    edges, count = mesh_edges(triangles)
    neighbours: dict[int, list[int]] = {}
    for a, b in edges[count == 1]:
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    loops = []
    for start in list(neighbours):
        while neighbours[start]:
            loop, v = [start], start
            while True:
                w = neighbours[v].pop()
                neighbours[w].remove(v)
                if w == start:
                    break
                loop.append(w)
                v = w
                if not neighbours[v]:
                    break
            loops.append(loop)
    return np.array(max(loops, key=len))


def edge_graph(vertices: np.ndarray, triangles: np.ndarray, keep: np.ndarray):
    """Sparse symmetric graph of the mesh edges between kept vertices, weighted by length."""
    e, _ = mesh_edges(triangles)
    e = e[keep[e[:, 0]] & keep[e[:, 1]]]
    w = np.linalg.norm(vertices[e[:, 0]] - vertices[e[:, 1]], axis=1)
    n = len(vertices)
    return coo_matrix((np.r_[w, w], (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                      shape=(n, n)).tocsr()


def remove_crown(vertices: np.ndarray, triangles: np.ndarray, margin: np.ndarray,
                 crown_centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The CBCT root: the cut joins the CBCT vertices nearest to the margin points by Dijkstra
    shortest paths; of the parts the cut leaves, the one holding the vertex farthest from the
    crown is kept (the supplementary details of the paper are not published)."""
    _, nearest = cKDTree(vertices).query(margin)
    anchors = nearest[np.r_[True, nearest[1:] != nearest[:-1]]]
    if anchors[0] == anchors[-1] and len(anchors) > 1:
        anchors = anchors[:-1]
    sources, row = np.unique(anchors, return_inverse=True)
    graph = edge_graph(vertices, triangles, np.ones(len(vertices), bool))
    # Consecutive anchors lie a fraction of a millimetre apart: searching 5 mm around each
    # finds the same shortest paths as an unbounded search, at a fraction of the cost.
    _, pred = dijkstra(graph, indices=sources, return_predecessors=True, limit=CUT_SEARCH_MM)
    on_cut = np.zeros(len(vertices), bool)
    for i in range(len(anchors)):
        a, b = anchors[i], anchors[(i + 1) % len(anchors)]
        v = b
        while v != a and v >= 0:
            on_cut[v] = True
            v = pred[row[i], v]
        on_cut[a] = True
    _, part = connected_components(edge_graph(vertices, triangles, ~on_cut), directed=False)
    root = part[np.argmax(np.linalg.norm(vertices - crown_centre, axis=1))]
    faces = triangles[np.all(part[triangles] == root, axis=1)]
    used, inverse = np.unique(faces, return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3)


def interpolate_points(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Algorithm 1, INTERPOLATEPOINTS: K points on the segment from each point of `a` to each of
    its N nearest points of `b`."""
    n = min(NEIGHBOURS, len(b))
    _, idx = cKDTree(b).query(a, k=n)
    nb = b[idx.reshape(len(a), n)]
    t = np.arange(1, POINTS_PER_SEGMENT + 1) / (POINTS_PER_SEGMENT + 1)
    pts = a[:, None, None, :] + (nb - a[:, None, :])[:, :, None, :] * t[None, None, :, None]
    return pts.reshape(-1, 3)


def gen_inter_points(a: np.ndarray, b: np.ndarray, depth: int) -> np.ndarray:
    """Algorithm 1, GENINTERPOINTS."""
    if depth == 0:
        return np.empty((0, 3))
    mid = interpolate_points(a, b)
    return np.concatenate([gen_inter_points(a, mid, depth - 1), mid,
                           gen_inter_points(mid, b, depth - 1)])


def polydata(vertices: np.ndarray, triangles: np.ndarray) -> vtk.vtkPolyData:
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(vertices), deep=True))
    cells = vtk.vtkCellArray()
    conn = numpy_to_vtkIdTypeArray(np.ascontiguousarray(triangles.ravel()), deep=True)
    cells.SetData(3, conn)
    pd = vtk.vtkPolyData()
    pd.SetPoints(pts)
    pd.SetPolys(cells)
    return pd


def band(points: np.ndarray) -> vtk.vtkPolyData:
    """Algorithm 1, lines 6-7: voxel downsampling, then vtkDelaunay3D (the paper gives no alpha:
    VTK's default 0, the convex hull) and its outer surface."""
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    down = np.asarray(cloud.voxel_down_sample(VOXEL_MM).points)
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(down), deep=True))
    cloud_pd = vtk.vtkPolyData()
    cloud_pd.SetPoints(pts)
    delaunay = vtk.vtkDelaunay3D()
    delaunay.SetInputData(cloud_pd)
    surface = vtk.vtkDataSetSurfaceFilter()
    surface.SetInputConnection(delaunay.GetOutputPort())
    surface.Update()
    return surface.GetOutput()


def fuse_tooth(crown: tuple, tooth: tuple, ios_to_cbct: np.ndarray) -> vtk.vtkPolyData:
    """Crown removal and stitching of one tooth, in the CBCT frame."""
    crown_v = apply(ios_to_cbct, crown[0])
    margin = crown_v[boundary_loop(crown[1])]
    root_v, root_f = remove_crown(*tooth, margin, crown_v.mean(axis=0))
    cut = root_v[boundary_loop(root_f)]
    append = vtk.vtkAppendPolyData()
    append.AddInputData(polydata(crown_v, crown[1]))
    append.AddInputData(band(gen_inter_points(margin, cut, DEPTH)))
    append.AddInputData(polydata(root_v, root_f))
    clean = vtk.vtkCleanPolyData()
    clean.SetInputConnection(append.GetOutputPort())
    clean.Update()
    return clean.GetOutput()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ios", type=Path, required=True)
    ap.add_argument("--cbct", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    ios = split_by_label(*read_ply(args.ios))
    cbct = split_by_label(*read_ply(args.cbct))
    order = arch_order(sorted(set(ios) & set(cbct)))
    ios_to_cbct = register(ios, cbct, order)
    args.out.mkdir(parents=True, exist_ok=True)
    for f in order:
        writer = vtk.vtkPLYWriter()
        writer.SetFileName(str(args.out / f"tooth_{f}.ply"))
        writer.SetInputData(fuse_tooth(ios[f], cbct[f], ios_to_cbct[f]))
        writer.SetFileTypeToBinary()
        writer.Write()
    (args.out / "transforms.json").write_text(json.dumps(
        {"ios_to_cbct": {str(f): ios_to_cbct[f].ravel().tolist() for f in order}}, indent=1))


if __name__ == "__main__":
    main()

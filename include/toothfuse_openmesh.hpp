/* toothfuse_openmesh.hpp: header-only adapter between OpenMesh triangle meshes and a toothfuse
 * session (hand-written; include/toothfuse.h is the generated C header it builds on).
 *
 *   #include <toothfuse_openmesh.hpp>
 *   toothfuse::openmesh::add_jaw(session, TOOTHFUSE_MODALITY_IOS, ios_mesh);   // int "label"
 *   toothfuse::openmesh::add_jaw(session, TOOTHFUSE_MODALITY_CBCT, cbct_mesh);
 *   toothfuse_session_fuse(session, &options);
 *   MyMesh fused;
 *   toothfuse::openmesh::fused_mesh(session, 0, fused);   // vertex props "label", "source"
 *
 * Works with any OpenMesh::TriMesh_ArrayKernelT<Traits> whose Point has 3 float or double
 * components (float points are converted exactly to double by the library). Labels are an int
 * vertex or face property (FDI numbers, 0 = gingiva). Functions never throw: they return the
 * toothfuse_status of the first failing call, and the detailed message is on the session
 * (toothfuse_session_last_error). Buffers are copied; nothing of the mesh is kept. */
#ifndef TOOTHFUSE_OPENMESH_HPP
#define TOOTHFUSE_OPENMESH_HPP

#include <toothfuse.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

namespace toothfuse {
namespace openmesh {

namespace detail {

/* The points of a mesh as packed x, y, z in the mesh's own scalar type, the scalar tag, and
 * the triangle indices; false for a face that is not a triangle. */
template <class Mesh>
bool buffers(const Mesh& mesh, std::vector<typename Mesh::Point::value_type>& points,
             toothfuse_scalar& scalar, std::vector<uint32_t>& indices) {
  using S = typename Mesh::Point::value_type;
  static_assert(std::is_same<S, float>::value || std::is_same<S, double>::value,
                "toothfuse::openmesh needs float or double points");
  static_assert(Mesh::Point::size_ == 3, "toothfuse::openmesh needs 3-component points");
  scalar = std::is_same<S, float>::value ? TOOTHFUSE_SCALAR_FLOAT32 : TOOTHFUSE_SCALAR_FLOAT64;
  points.clear();
  points.reserve(3 * mesh.n_vertices());
  for (auto vh : mesh.vertices()) {
    const auto& p = mesh.point(vh);
    points.push_back(p[0]);
    points.push_back(p[1]);
    points.push_back(p[2]);
  }
  indices.clear();
  indices.reserve(3 * mesh.n_faces());
  for (auto fh : mesh.faces()) {
    size_t corners = 0;
    for (auto vh : mesh.fv_range(fh)) {
      indices.push_back(static_cast<uint32_t>(vh.idx()));
      corners++;
    }
    if (corners != 3) return false;
  }
  return true;
}

}  // namespace detail

/* Adds one tooth mesh (IOS crown or closed CBCT tooth) as toothfuse_session_add_tooth.
 * INVALID_ARGUMENT for a mesh with a non-triangle face. */
template <class Mesh>
toothfuse_status add_tooth(toothfuse_session* session, toothfuse_modality modality, int32_t fdi,
                           const Mesh& mesh) {
  std::vector<typename Mesh::Point::value_type> points;
  std::vector<uint32_t> indices;
  toothfuse_scalar scalar = TOOTHFUSE_SCALAR_FLOAT64;
  if (!detail::buffers(mesh, points, scalar, indices)) return TOOTHFUSE_STATUS_INVALID_ARGUMENT;
  return toothfuse_session_add_tooth(session, modality, fdi, points.data(), mesh.n_vertices(),
                                     3 * sizeof(points[0]), scalar, indices.data(),
                                     indices.size());
}

/* Adds a labeled jaw mesh as toothfuse_session_add_jaw: the int vertex property
 * `label_property` (FDI, 0 = gingiva), else the int face property of that name. MISSING_DATA
 * when the mesh has neither; INVALID_ARGUMENT for a non-triangle face. */
template <class Mesh>
toothfuse_status add_jaw(toothfuse_session* session, toothfuse_modality modality,
                         const Mesh& mesh, const char* label_property = "label") {
  std::vector<typename Mesh::Point::value_type> points;
  std::vector<uint32_t> indices;
  toothfuse_scalar scalar = TOOTHFUSE_SCALAR_FLOAT64;
  if (!detail::buffers(mesh, points, scalar, indices)) return TOOTHFUSE_STATUS_INVALID_ARGUMENT;
  std::vector<int32_t> labels;
  toothfuse_label_domain domain = TOOTHFUSE_LABEL_DOMAIN_VERTEX;
  OpenMesh::VPropHandleT<int> vp;
  OpenMesh::FPropHandleT<int> fp;
  if (mesh.get_property_handle(vp, label_property)) {
    for (auto vh : mesh.vertices()) labels.push_back(mesh.property(vp, vh));
  } else if (mesh.get_property_handle(fp, label_property)) {
    domain = TOOTHFUSE_LABEL_DOMAIN_FACE;
    for (auto fh : mesh.faces()) labels.push_back(mesh.property(fp, fh));
  } else {
    return TOOTHFUSE_STATUS_MISSING_DATA;
  }
  return toothfuse_session_add_jaw(session, modality, points.data(), mesh.n_vertices(),
                                   3 * sizeof(points[0]), scalar, indices.data(), indices.size(),
                                   labels.data(), labels.size(), domain);
}

/* Adds one mesh per tooth, `teeth` holding (FDI, mesh) pairs (a std::map<int, Mesh> or a
 * vector of pairs); stops at the first failure and returns its status. */
template <class Teeth>
toothfuse_status add_teeth(toothfuse_session* session, toothfuse_modality modality,
                           const Teeth& teeth) {
  for (const auto& t : teeth) {
    const toothfuse_status st = add_tooth(session, modality, static_cast<int32_t>(t.first),
                                          t.second);
    if (st != TOOTHFUSE_STATUS_OK) return st;
  }
  return TOOTHFUSE_STATUS_OK;
}

/* Replaces `out` by fused mesh `fdi` (0 = the whole jaw) after a fuse, with int vertex
 * properties "source" (TOOTHFUSE_SOURCE_IOS / _BAND / _CBCT) and "label" (the FDI number of
 * every vertex). Points are converted to the mesh's scalar type (exact for double). On failure
 * `out` is left empty. */
template <class Mesh>
toothfuse_status fused_mesh(const toothfuse_session* session, int32_t fdi, Mesh& out) {
  out.clear();
  size_t nv = 0, ni = 0;
  toothfuse_status st = toothfuse_session_fused_size(session, fdi, &nv, &ni);
  if (st != TOOTHFUSE_STATUS_OK) return st;
  std::vector<double> xyz(3 * nv);
  std::vector<uint32_t> idx(ni);
  std::vector<uint8_t> src(nv);
  std::vector<int32_t> labels(nv, fdi);
  if (nv > 0) {
    st = toothfuse_session_copy_fused_vertices(session, fdi, xyz.data(), nv, 3 * sizeof(double),
                                               TOOTHFUSE_SCALAR_FLOAT64);
    if (st == TOOTHFUSE_STATUS_OK) st = toothfuse_session_copy_fused_sources(session, fdi,
                                                                           src.data(), nv);
    if (st == TOOTHFUSE_STATUS_OK && fdi == 0)
      st = toothfuse_session_copy_fused_labels(session, labels.data(), nv);
  }
  if (st == TOOTHFUSE_STATUS_OK && ni > 0)
    st = toothfuse_session_copy_fused_indices(session, fdi, idx.data(), ni);
  if (st != TOOTHFUSE_STATUS_OK) return st;
  using S = typename Mesh::Point::value_type;
  std::vector<typename Mesh::VertexHandle> vh;
  vh.reserve(nv);
  for (size_t i = 0; i < nv; i++) {
    vh.push_back(out.add_vertex(typename Mesh::Point(
        static_cast<S>(xyz[3 * i]), static_cast<S>(xyz[3 * i + 1]),
        static_cast<S>(xyz[3 * i + 2]))));
  }
  for (size_t t = 0; t + 2 < ni; t += 3) {
    out.add_face(vh[idx[t]], vh[idx[t + 1]], vh[idx[t + 2]]);
  }
  OpenMesh::VPropHandleT<int> lp, sp;
  if (!out.get_property_handle(lp, "label")) out.add_property(lp, "label");
  if (!out.get_property_handle(sp, "source")) out.add_property(sp, "source");
  out.property(lp).set_persistent(true);
  out.property(sp).set_persistent(true);
  for (size_t i = 0; i < nv; i++) {
    out.property(lp, vh[i]) = labels[i];
    out.property(sp, vh[i]) = src[i];
  }
  return TOOTHFUSE_STATUS_OK;
}

}  // namespace openmesh
}  // namespace toothfuse

#endif /* TOOTHFUSE_OPENMESH_HPP */

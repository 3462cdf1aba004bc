// The synthetic jaw (TOOTHFUSE_DEMO_DIR from the demo_jaw fixture) through OpenMesh: a float
// TriMesh_ArrayKernelT<> and a double-precision mesh (Vec3d points), fed into a session as
// labeled jaws straight from OpenMesh's contiguous point arrays, read back into new OpenMesh
// meshes per tooth without loss; OpenMesh's own topology agrees with the library's.
#include "test_support.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <cstring>

namespace {

struct DoubleTraits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using MeshF = OpenMesh::TriMesh_ArrayKernelT<>;
using MeshD = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;
static_assert(sizeof(MeshF::Point) == 3 * sizeof(float), "packed float points");
static_assert(sizeof(MeshD::Point) == 3 * sizeof(double), "packed double points");

struct Loaded {
  MeshF mf;
  MeshD md;
  std::vector<uint32_t> tris;
  std::vector<int32_t> labels;
};

// Reads the PLY into a float mesh with its `label` vertex property, and builds the double mesh
// from it. OpenMesh's PLY reader parses coordinates as float, so the double mesh's points get
// a deterministic sub-float offset: they then use all 53 bits and a lossy path would show.
bool load(const std::string& path, Loaded& out) {
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::Custom;
  if (!OpenMesh::IO::read_mesh(out.mf, path, opt)) {
    ADD_FAILURE() << "OpenMesh could not read " << path
                  << " (the demo_jaw fixture should have written it)";
    return false;
  }
  OpenMesh::VPropHandleT<int> lh;
  if (!out.mf.get_property_handle(lh, "label")) {
    ADD_FAILURE() << path << ": no per-vertex `label` property";
    return false;
  }
  for (auto vh : out.mf.vertices()) {
    out.labels.push_back(out.mf.property(lh, vh));
    const MeshF::Point& p = out.mf.point(vh);
    const double off = (1.0 / 3.0) * 1e-7 * static_cast<double>(vh.idx() % 5 + 1);
    out.md.add_vertex(MeshD::Point(p[0] + off, p[1] - off, p[2] + 2 * off));
  }
  for (auto fh : out.mf.faces()) {
    std::vector<MeshD::VertexHandle> f;
    for (auto vh : out.mf.fv_range(fh)) {
      out.tris.push_back(static_cast<uint32_t>(vh.idx()));
      f.push_back(MeshD::VertexHandle(vh.idx()));
    }
    if (f.size() != 3) {
      ADD_FAILURE() << "non-triangle face";
      return false;
    }
    out.md.add_face(f);
  }
  EXPECT_EQ(out.md.n_faces(), out.mf.n_faces()) << "double mesh rejected faces";
  return true;
}

// Number of boundary loops by OpenMesh's half-edge walk.
template <class Mesh>
size_t boundary_loops(const Mesh& m) {
  std::vector<bool> seen(m.n_halfedges(), false);
  size_t loops = 0;
  for (auto heh : m.halfedges()) {
    if (!m.is_boundary(heh) || seen[heh.idx()]) continue;
    loops++;
    auto h = heh;
    do {
      seen[h.idx()] = true;
      h = m.next_halfedge_handle(h);
    } while (h != heh);
  }
  return loops;
}

// Builds an OpenMesh mesh from a tooth's read-back buffers.
template <class Mesh, class Scalar>
Mesh rebuild(const std::vector<Scalar>& xyz, const std::vector<uint32_t>& idx) {
  Mesh m;
  for (size_t i = 0; i < xyz.size() / 3; i++)
    m.add_vertex(typename Mesh::Point(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
  for (size_t f = 0; f < idx.size() / 3; f++)
    m.add_face(typename Mesh::VertexHandle(static_cast<int>(idx[3 * f])),
               typename Mesh::VertexHandle(static_cast<int>(idx[3 * f + 1])),
               typename Mesh::VertexHandle(static_cast<int>(idx[3 * f + 2])));
  return m;
}

void round_trip(const std::string& path, toothfuse_modality m) {
  Loaded in;
  if (!load(path, in)) return;
  const size_t nv = in.mf.n_vertices();
  tf::Session sf, sd;
  ASSERT_EQ(toothfuse_session_add_jaw(sf.get(), m, in.mf.points(), nv, sizeof(MeshF::Point),
                                      TOOTHFUSE_SCALAR_FLOAT32, in.tris.data(), in.tris.size(),
                                      in.labels.data(), in.labels.size(),
                                      TOOTHFUSE_LABEL_DOMAIN_VERTEX),
            TOOTHFUSE_STATUS_OK)
      << sf.error();
  ASSERT_EQ(toothfuse_session_add_jaw(sd.get(), m, in.md.points(), nv, sizeof(MeshD::Point),
                                      TOOTHFUSE_SCALAR_FLOAT64, in.tris.data(), in.tris.size(),
                                      in.labels.data(), in.labels.size(),
                                      TOOTHFUSE_LABEL_DOMAIN_VERTEX),
            TOOTHFUSE_STATUS_OK)
      << sd.error();
  const auto parts = tf::split(in.tris, tf::face_labels_from_vertices(in.tris, in.labels), nv);
  ASSERT_GE(parts.size(), 3u);
  for (const auto& [fdi, part] : parts) {
    SCOPED_TRACE("tooth " + std::to_string(fdi));
    const std::vector<uint32_t> idx = sd.indices(m, fdi);
    ASSERT_EQ(idx, part.indices);
    ASSERT_EQ(sd.sources(m, fdi), part.source);
    ASSERT_EQ(sf.sources(m, fdi), part.source);
    const MeshF tf_mesh = rebuild<MeshF>(sf.positions_f(m, fdi), sf.indices(m, fdi));
    const MeshD td_mesh = rebuild<MeshD>(sd.positions(m, fdi), idx);
    ASSERT_EQ(tf_mesh.n_vertices(), part.source.size());
    ASSERT_EQ(td_mesh.n_faces(), idx.size() / 3) << "OpenMesh rejected faces (complex edges)";
    size_t bad_f = 0, bad_d = 0;
    for (size_t i = 0; i < part.source.size(); i++) {
      const auto src = static_cast<int>(part.source[i]);
      const MeshF::Point& a = in.mf.point(MeshF::VertexHandle(src));
      const MeshF::Point& b = tf_mesh.point(MeshF::VertexHandle(static_cast<int>(i)));
      if (std::memcmp(&a, &b, sizeof a) != 0) bad_f++;
      const MeshD::Point& c = in.md.point(MeshD::VertexHandle(src));
      const MeshD::Point& d = td_mesh.point(MeshD::VertexHandle(static_cast<int>(i)));
      if (std::memcmp(&c, &d, sizeof c) != 0) bad_d++;
    }
    EXPECT_EQ(bad_f, 0u) << "float mesh not recovered exactly";
    EXPECT_EQ(bad_d, 0u) << "double mesh not recovered bit for bit";
    // OpenMesh's independent view of the topology agrees with the library's.
    const toothfuse_mesh_info info = sd.info(m, fdi);
    size_t non_manifold = 0;
    for (auto vh : td_mesh.vertices())
      if (!td_mesh.is_manifold(vh)) non_manifold++;
    EXPECT_EQ(non_manifold, 0u);
    EXPECT_TRUE(info.manifold);
    EXPECT_EQ(boundary_loops(td_mesh), info.boundary_loops);
    if (m == TOOTHFUSE_MODALITY_IOS) {
      EXPECT_EQ(info.boundary_loops, 1u) << "an IOS crown should have exactly one margin loop";
    } else {
      EXPECT_TRUE(info.closed);
      EXPECT_EQ(boundary_loops(td_mesh), 0u);
    }
  }
}

TEST(OpenMeshRoundTrip, IosJawFloatAndDoubleMeshes) {
  const std::string dir = tf::env_or_empty("TOOTHFUSE_DEMO_DIR");
  ASSERT_FALSE(dir.empty()) << "TOOTHFUSE_DEMO_DIR is not set (run through ctest)";
  round_trip(dir + "/ios.ply", TOOTHFUSE_MODALITY_IOS);
}

TEST(OpenMeshRoundTrip, CbctTeethFloatAndDoubleMeshes) {
  const std::string dir = tf::env_or_empty("TOOTHFUSE_DEMO_DIR");
  ASSERT_FALSE(dir.empty()) << "TOOTHFUSE_DEMO_DIR is not set (run through ctest)";
  round_trip(dir + "/cbct.ply", TOOTHFUSE_MODALITY_CBCT);
}

}  // namespace

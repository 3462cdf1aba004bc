// The header-only OpenMesh adapter (include/toothfuse_openmesh.hpp) on jaw_2 of the demo_jaws
// fixture: the IOS jaw from a float TriMesh with its `label` vertex property, the CBCT teeth as
// per-tooth double TriMeshes, fused, and the result back into float and double TriMeshes with
// `label` and `source` properties, checked by OpenMesh's own half-edge topology. Compiled with
// -Wall -Wextra -Werror.
#include "test_support.hpp"

#include <toothfuse_openmesh.hpp>

#include <OpenMesh/Core/IO/MeshIO.hh>

#include <map>
#include <set>

namespace {

struct DoubleTraits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using MeshF = OpenMesh::TriMesh_ArrayKernelT<>;
using MeshD = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

std::string jaw_file(const char* name) {
  const std::string dir = tf::env_or_empty("TOOTHFUSE_JAWS_DIR");
  return dir.empty() ? std::string() : dir + "/jaw_2/" + name;
}

bool read_labeled(const std::string& path, MeshF& mesh) {
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::Custom;
  OpenMesh::VPropHandleT<int> lp;
  return OpenMesh::IO::read_mesh(mesh, path, opt) && mesh.get_property_handle(lp, "label");
}

// The CBCT jaw split into one double mesh per tooth (faces whose corners share a label).
std::map<int, MeshD> split_teeth(const MeshF& jaw) {
  OpenMesh::VPropHandleT<int> lp;
  jaw.get_property_handle(lp, "label");
  std::map<int, MeshD> teeth;
  std::map<int, std::map<int, MeshD::VertexHandle>> remap;
  for (auto fh : jaw.faces()) {
    std::vector<OpenMesh::VertexHandle> vs;
    for (auto v : jaw.fv_range(fh)) vs.push_back(v);
    const int l = jaw.property(lp, vs[0]);
    if (l == 0 || jaw.property(lp, vs[1]) != l || jaw.property(lp, vs[2]) != l) continue;
    std::vector<MeshD::VertexHandle> f;
    for (auto v : vs) {
      auto& m = remap[l];
      auto it = m.find(v.idx());
      if (it == m.end()) {
        const auto& p = jaw.point(v);
        it = m.emplace(v.idx(), teeth[l].add_vertex(MeshD::Point(p[0], p[1], p[2]))).first;
      }
      f.push_back(it->second);
    }
    teeth[l].add_face(f);
  }
  return teeth;
}

template <class Mesh>
size_t boundary_halfedges(const Mesh& m) {
  size_t n = 0;
  for (auto h : m.halfedges()) n += m.is_boundary(h) ? 1 : 0;
  return n;
}

TEST(OpenMeshAdapter, FloatJawAndDoubleTeethInFusedMeshesOut) {
  MeshF ios, cbct;
  const std::string ios_path = jaw_file("ios.ply"), cbct_path = jaw_file("cbct.ply");
  if (ios_path.empty()) GTEST_SKIP() << "TOOTHFUSE_JAWS_DIR not set";
  ASSERT_TRUE(read_labeled(ios_path, ios)) << ios_path;
  ASSERT_TRUE(read_labeled(cbct_path, cbct)) << cbct_path;
  const std::map<int, MeshD> teeth = split_teeth(cbct);
  ASSERT_GE(teeth.size(), 3u);

  tf::Session s;
  namespace tom = toothfuse::openmesh;
  ASSERT_EQ(tom::add_jaw(s.get(), TOOTHFUSE_MODALITY_IOS, ios), TOOTHFUSE_STATUS_OK) << s.error();
  ASSERT_EQ(tom::add_teeth(s.get(), TOOTHFUSE_MODALITY_CBCT, teeth), TOOTHFUSE_STATUS_OK)
      << s.error();
  std::vector<int32_t> want;
  for (const auto& t : teeth) want.push_back(t.first);
  EXPECT_EQ(s.teeth(TOOTHFUSE_MODALITY_CBCT), want);
  toothfuse_options o;
  ASSERT_EQ(toothfuse_options_default(&o), TOOTHFUSE_STATUS_OK);
  ASSERT_EQ(toothfuse_session_fuse(s.get(), &o), TOOTHFUSE_STATUS_OK) << s.error();

  MeshD jaw;
  ASSERT_EQ(tom::fused_mesh(s.get(), 0, jaw), TOOTHFUSE_STATUS_OK) << s.error();
  size_t nv = 0, ni = 0;
  ASSERT_EQ(toothfuse_session_fused_size(s.get(), 0, &nv, &ni), TOOTHFUSE_STATUS_OK);
  EXPECT_EQ(jaw.n_vertices(), nv);
  EXPECT_EQ(3 * jaw.n_faces(), ni);
  EXPECT_EQ(boundary_halfedges(jaw), 0u) << "the fused jaw is watertight";
  OpenMesh::VPropHandleT<int> lp, sp;
  ASSERT_TRUE(jaw.get_property_handle(lp, "label"));
  ASSERT_TRUE(jaw.get_property_handle(sp, "source"));
  std::set<int> labels, sources;
  for (auto v : jaw.vertices()) {
    labels.insert(jaw.property(lp, v));
    sources.insert(jaw.property(sp, v));
  }
  std::set<int> ios_teeth;
  OpenMesh::VPropHandleT<int> ilp;
  ios.get_property_handle(ilp, "label");
  for (auto v : ios.vertices()) ios_teeth.insert(ios.property(ilp, v));
  std::set<int> fused;
  for (int t : want)
    if (ios_teeth.count(t)) fused.insert(t);
  EXPECT_EQ(labels, fused);
  EXPECT_EQ(sources, (std::set<int>{TOOTHFUSE_SOURCE_IOS, TOOTHFUSE_SOURCE_BAND,
                                    TOOTHFUSE_SOURCE_CBCT}));

  // One tooth into a float mesh: closed, labeled with its FDI, positions as float.
  const int fdi = *fused.begin();
  MeshF one;
  ASSERT_EQ(tom::fused_mesh(s.get(), fdi, one), TOOTHFUSE_STATUS_OK) << s.error();
  ASSERT_EQ(toothfuse_session_fused_size(s.get(), fdi, &nv, &ni), TOOTHFUSE_STATUS_OK);
  EXPECT_EQ(one.n_vertices(), nv);
  EXPECT_EQ(boundary_halfedges(one), 0u);
  ASSERT_TRUE(one.get_property_handle(lp, "label"));
  for (auto v : one.vertices()) ASSERT_EQ(one.property(lp, v), fdi);
}

TEST(OpenMeshAdapter, ErrorsAreStatusesWithTheSessionMessage) {
  tf::Session s;
  namespace tom = toothfuse::openmesh;
  MeshD unlabeled;
  auto a = unlabeled.add_vertex(MeshD::Point(0, 0, 0));
  auto b = unlabeled.add_vertex(MeshD::Point(1, 0, 0));
  auto c = unlabeled.add_vertex(MeshD::Point(0, 1, 0));
  unlabeled.add_face(a, b, c);
  EXPECT_EQ(tom::add_jaw(s.get(), TOOTHFUSE_MODALITY_IOS, unlabeled),
            TOOTHFUSE_STATUS_MISSING_DATA);
  // An open triangle is not a CBCT tooth: the library's status and message come through.
  EXPECT_EQ(tom::add_tooth(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, unlabeled),
            TOOTHFUSE_STATUS_NOT_MANIFOLD);
  EXPECT_NE(s.error().find("11"), std::string::npos) << s.error();
  MeshF out;
  EXPECT_EQ(tom::fused_mesh(s.get(), 0, out), TOOTHFUSE_STATUS_WRONG_STATE);
  EXPECT_EQ(out.n_vertices(), 0u);
}

}  // namespace

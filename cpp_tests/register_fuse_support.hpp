// Helpers of the registration and fusion tests: reading a demo jaw (ios.ply, cbct.ply with a
// per-vertex int `label`) with OpenMesh, the ground truth's matrices from truth/truth.json by
// string search, and feeding a jaw into a session.
#pragma once

#include "test_support.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <array>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace tf {

struct DoubleTraits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using MeshF = OpenMesh::TriMesh_ArrayKernelT<>;
using MeshD = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

using Mat4 = std::array<double, 16>;  // row-major

/// A labeled jaw read with OpenMesh: float points as read, double points converted from them.
struct LabeledJaw {
  std::vector<float> fxyz;
  std::vector<double> dxyz;
  std::vector<uint32_t> tris;
  std::vector<int32_t> labels;
};

inline bool read_labeled_jaw(const std::string& path, LabeledJaw& out) {
  MeshF m;
  m.add_property(OpenMesh::VPropHandleT<int>(), "label");
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::Custom;
  if (!OpenMesh::IO::read_mesh(m, path, opt)) {
    ADD_FAILURE() << "OpenMesh could not read " << path;
    return false;
  }
  OpenMesh::VPropHandleT<int> lh;
  if (!m.get_property_handle(lh, "label")) {
    ADD_FAILURE() << path << ": no per-vertex `label` property";
    return false;
  }
  for (auto vh : m.vertices()) {
    const auto& p = m.point(vh);
    for (int k = 0; k < 3; k++) {
      out.fxyz.push_back(p[k]);
      out.dxyz.push_back(p[k]);
    }
    out.labels.push_back(m.property(lh, vh));
  }
  for (auto fh : m.faces())
    for (auto vh : m.fv_range(fh)) out.tris.push_back(static_cast<uint32_t>(vh.idx()));
  return true;
}

/// Adds a labeled jaw (per-vertex labels) as `modality`, float or double coordinates.
inline void add_jaw(Session& s, toothfuse_modality m, const LabeledJaw& j, bool as_float) {
  const void* v = as_float ? static_cast<const void*>(j.fxyz.data())
                           : static_cast<const void*>(j.dxyz.data());
  size_t stride = as_float ? 3 * sizeof(float) : 3 * sizeof(double);
  ASSERT_EQ(toothfuse_session_add_jaw(s.get(), m, v, j.labels.size(), stride,
                                      as_float ? TOOTHFUSE_SCALAR_FLOAT32
                                               : TOOTHFUSE_SCALAR_FLOAT64,
                                      j.tris.data(), j.tris.size(), j.labels.data(),
                                      j.labels.size(), TOOTHFUSE_LABEL_DOMAIN_VERTEX),
            TOOTHFUSE_STATUS_OK)
      << s.error();
}

/// Loads a demo folder's ios.ply and cbct.ply into a session.
inline bool load_demo(Session& s, const std::string& dir, bool as_float) {
  LabeledJaw ios, cbct;
  if (!read_labeled_jaw(dir + "/ios.ply", ios) || !read_labeled_jaw(dir + "/cbct.ply", cbct))
    return false;
  add_jaw(s, TOOTHFUSE_MODALITY_IOS, ios, as_float);
  add_jaw(s, TOOTHFUSE_MODALITY_CBCT, cbct, as_float);
  return !::testing::Test::HasFatalFailure();
}

inline std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// Parses the 16 numbers of the JSON array that follows `pos` (the first '[' after it).
inline Mat4 parse16(const std::string& s, size_t pos) {
  Mat4 m{};
  size_t i = s.find('[', pos);
  const char* p = s.c_str() + i + 1;
  for (double& x : m) {
    while (*p == ' ' || *p == '\n' || *p == ',' || *p == '\r') p++;
    char* end = nullptr;
    x = std::strtod(p, &end);
    p = end;
  }
  return m;
}

/// truth.json: world_to_cbct and per-tooth cbct_to_ios (keys are sorted: `cbct_to_ios` comes
/// before `fdi` in each tooth object).
struct Truth {
  Mat4 world_to_cbct{};
  std::map<int, Mat4> cbct_to_ios;
};

inline Truth read_truth(const std::string& path) {
  Truth t;
  std::string s = slurp(path);
  EXPECT_FALSE(s.empty()) << path;
  size_t w = s.find("\"world_to_cbct\"");
  EXPECT_NE(w, std::string::npos) << path;
  if (w != std::string::npos) t.world_to_cbct = parse16(s, w);
  for (size_t p = s.find("\"cbct_to_ios\""); p != std::string::npos;
       p = s.find("\"cbct_to_ios\"", p + 1)) {
    Mat4 m = parse16(s, p);
    size_t f = s.find("\"fdi\":", p);
    int fdi = std::atoi(s.c_str() + f + 6);
    t.cbct_to_ios[fdi] = m;
  }
  return t;
}

inline std::array<double, 3> apply(const Mat4& m, const double* p) {
  std::array<double, 3> o{};
  for (int r = 0; r < 3; r++)
    o[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
  return o;
}

}  // namespace tf

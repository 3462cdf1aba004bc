// Helpers of the registration and fusion tests: reading a demo jaw (ios.ply, cbct.ply with a
// per-vertex int `label`) with OpenMesh, the ground truth's matrices from truth/truth.json by
// string search, feeding a jaw into a session, and a mesh as VTK polydata.
#pragma once

#include "test_support.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkPLY.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <cstddef>
#include <cstdlib>
#include <cstring>
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

struct PlyVertexD {
  double x, y, z;
};

/// The file's double x/y/z by VTK's low-level PLY reader (OpenMesh and vtkPLYReader parse
/// coordinates as float, which can make thin triangles degenerate).
inline bool read_doubles(const std::string& path, std::vector<double>& xyz) {
  int nelems = 0;
  char** names = nullptr;
  PlyFile* ply = vtkPLY::ply_open_for_reading(path.c_str(), &nelems, &names);
  if (!ply) return false;
  for (int e = 0; e < nelems; e++) {
    int num = 0, nprops = 0;
    vtkPLY::ply_get_element_description(ply, names[e], &num, &nprops);
    if (std::strcmp(names[e], "vertex") != 0) continue;
    PlyProperty props[] = {
        {"x", PLY_DOUBLE, PLY_DOUBLE, static_cast<int>(offsetof(PlyVertexD, x)), 0, 0, 0, 0},
        {"y", PLY_DOUBLE, PLY_DOUBLE, static_cast<int>(offsetof(PlyVertexD, y)), 0, 0, 0, 0},
        {"z", PLY_DOUBLE, PLY_DOUBLE, static_cast<int>(offsetof(PlyVertexD, z)), 0, 0, 0, 0},
    };
    for (PlyProperty& p : props) vtkPLY::ply_get_property(ply, "vertex", &p);
    for (int i = 0; i < num; i++) {
      PlyVertexD v{};
      vtkPLY::ply_get_element(ply, &v);
      xyz.insert(xyz.end(), {v.x, v.y, v.z});
    }
    break;
  }
  vtkPLY::ply_close(ply);
  return true;
}

/// A labeled jaw: float points and faces as OpenMesh reads them, the file's exact doubles.
struct LabeledJaw {
  std::vector<float> fxyz;
  std::vector<double> dxyz;
  std::vector<uint32_t> tris;
  std::vector<int32_t> labels;
};

inline bool read_labeled_jaw(const std::string& path, LabeledJaw& out) {
  MeshF m;
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
  std::vector<double> exact;
  if (!read_doubles(path, exact) || exact.size() != out.dxyz.size()) {
    ADD_FAILURE() << path << ": VTK's PLY reader disagrees with OpenMesh on the vertex count";
    return false;
  }
  out.dxyz = exact;
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

/// A triangle mesh as VTK polydata: double points `xyz` (x, y, z per point), triangles `tris`
/// (three point indices each).
inline vtkSmartPointer<vtkPolyData> polydata(const std::vector<double>& xyz,
                                             const std::vector<uint32_t>& tris) {
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(static_cast<vtkIdType>(xyz.size() / 3));
  for (size_t i = 0; i < xyz.size() / 3; i++)
    pts->SetPoint(static_cast<vtkIdType>(i), &xyz[3 * i]);
  vtkNew<vtkCellArray> polys;
  for (size_t t = 0; t < tris.size() / 3; t++) {
    vtkIdType ids[3] = {tris[3 * t], tris[3 * t + 1], tris[3 * t + 2]};
    polys->InsertNextCell(3, ids);
  }
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  pd->SetPoints(pts);
  pd->SetPolys(polys);
  return pd;
}

}  // namespace tf

// The synthetic jaw written by `toothfuse demo --out DIR` (DIR from TOOTHFUSE_DEMO_DIR, made by
// the demo_jaw ctest fixture), read with VTK, fed into a session as labeled jaws and read back:
// positions bitwise for double input, exact float->double for float input, triangles and the
// vertex map exactly as an independent split computes them, and the topology the demo promises
// (IOS crowns open with one margin loop, CBCT teeth closed).
#include "test_support.hpp"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPLY.h>
#include <vtkPLYReader.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include <cstddef>
#include <cstring>
#include <fstream>

namespace {

struct Jaw {
  std::vector<float> fxyz;   // vtkPLYReader's float points
  std::vector<double> dxyz;  // the file's double coordinates (vtkPLY low-level reader)
  std::vector<uint32_t> tris;
  std::vector<int32_t> labels;  // per vertex
};

struct PlyVertex {
  double x, y, z;
  int label;
};

// Reads the double x/y/z and int `label` of every vertex with VTK's low-level PLY reader
// (vtkPLYReader itself keeps only float points and no custom properties).
void read_doubles_and_labels(const std::string& path, Jaw& jaw) {
  int nelems = 0;
  char** names = nullptr;
  PlyFile* ply = vtkPLY::ply_open_for_reading(path.c_str(), &nelems, &names);
  ASSERT_NE(ply, nullptr) << path;
  bool found = false;
  for (int e = 0; e < nelems && !found; e++) {
    int num = 0, nprops = 0;
    PlyElement* el = vtkPLY::ply_get_element_description(ply, names[e], &num, &nprops);
    if (std::strcmp(names[e], "vertex") != 0) continue;
    found = true;
    bool has_label = false;
    for (int p = 0; p < el->nprops; p++)
      if (std::strcmp(el->props[p]->name, "label") == 0) has_label = true;
    ASSERT_TRUE(has_label) << path << ": no per-vertex int property `label`";
    PlyProperty props[] = {
        {"x", PLY_DOUBLE, PLY_DOUBLE, static_cast<int>(offsetof(PlyVertex, x)), 0, 0, 0, 0},
        {"y", PLY_DOUBLE, PLY_DOUBLE, static_cast<int>(offsetof(PlyVertex, y)), 0, 0, 0, 0},
        {"z", PLY_DOUBLE, PLY_DOUBLE, static_cast<int>(offsetof(PlyVertex, z)), 0, 0, 0, 0},
        {"label", PLY_INT, PLY_INT, static_cast<int>(offsetof(PlyVertex, label)), 0, 0, 0, 0},
    };
    for (PlyProperty& p : props) vtkPLY::ply_get_property(ply, "vertex", &p);
    for (int i = 0; i < num; i++) {
      PlyVertex v{};
      vtkPLY::ply_get_element(ply, &v);
      jaw.dxyz.insert(jaw.dxyz.end(), {v.x, v.y, v.z});
      jaw.labels.push_back(v.label);
    }
  }
  vtkPLY::ply_close(ply);
  ASSERT_TRUE(found) << path << ": no vertex element";
}

Jaw load(const std::string& path) {
  Jaw jaw;
  {
    std::ifstream probe(path);
    EXPECT_TRUE(probe.good()) << path << " is missing: the demo_jaw fixture (toothfuse demo "
                              << "--out DIR) should have written it";
    if (!probe.good()) return jaw;
  }
  vtkNew<vtkPLYReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* pd = reader->GetOutput();
  const vtkIdType n = pd->GetNumberOfPoints();
  EXPECT_GT(n, 0) << path;
  for (vtkIdType i = 0; i < n; i++) {
    double p[3];
    pd->GetPoint(i, p);  // float storage: widening is exact
    for (double c : p) jaw.fxyz.push_back(static_cast<float>(c));
  }
  auto it = vtk::TakeSmartPointer(pd->GetPolys()->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
    vtkIdList* ids = it->GetCurrentCell();
    EXPECT_EQ(ids->GetNumberOfIds(), 3) << "non-triangle face in " << path;
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); k++)
      jaw.tris.push_back(static_cast<uint32_t>(ids->GetId(k)));
  }
  read_doubles_and_labels(path, jaw);
  EXPECT_EQ(jaw.dxyz.size(), jaw.fxyz.size()) << path;
  return jaw;
}

// Feeds `jaw` in as float and as double and checks every tooth against the independent split.
void round_trip(const Jaw& jaw, toothfuse_modality m) {
  ASSERT_FALSE(jaw.tris.empty());
  const size_t nv = jaw.dxyz.size() / 3;
  for (size_t i = 0; i < jaw.fxyz.size(); i++)
    ASSERT_EQ(jaw.fxyz[i], static_cast<float>(jaw.dxyz[i])) << "vtkPLYReader float != (float)double";

  tf::Session sf, sd;
  ASSERT_EQ(toothfuse_session_add_jaw(sf.get(), m, jaw.fxyz.data(), nv, 3 * sizeof(float),
                                      TOOTHFUSE_SCALAR_FLOAT32, jaw.tris.data(), jaw.tris.size(),
                                      jaw.labels.data(), jaw.labels.size(),
                                      TOOTHFUSE_LABEL_DOMAIN_VERTEX),
            TOOTHFUSE_STATUS_OK)
      << sf.error();
  ASSERT_EQ(toothfuse_session_add_jaw(sd.get(), m, jaw.dxyz.data(), nv, 3 * sizeof(double),
                                      TOOTHFUSE_SCALAR_FLOAT64, jaw.tris.data(), jaw.tris.size(),
                                      jaw.labels.data(), jaw.labels.size(),
                                      TOOTHFUSE_LABEL_DOMAIN_VERTEX),
            TOOTHFUSE_STATUS_OK)
      << sd.error();

  const auto parts = tf::split(jaw.tris, tf::face_labels_from_vertices(jaw.tris, jaw.labels), nv);
  std::vector<int32_t> want;
  for (const auto& kv : parts) want.push_back(kv.first);
  ASSERT_GE(want.size(), 3u);
  EXPECT_EQ(sf.teeth(m), want);
  EXPECT_EQ(sd.teeth(m), want);

  for (const auto& [fdi, part] : parts) {
    SCOPED_TRACE("tooth " + std::to_string(fdi));
    EXPECT_EQ(sf.indices(m, fdi), part.indices);
    EXPECT_EQ(sd.indices(m, fdi), part.indices);
    EXPECT_EQ(sf.sources(m, fdi), part.source);
    EXPECT_EQ(sd.sources(m, fdi), part.source);
    const std::vector<double> pf = sf.positions(m, fdi);
    const std::vector<double> pd = sd.positions(m, fdi);
    const std::vector<float> pdf = sd.positions_f(m, fdi);
    ASSERT_EQ(pd.size(), 3 * part.source.size());
    toothfuse_mesh_view view{};
    ASSERT_EQ(toothfuse_session_mesh_view(sd.get(), m, fdi, &view), TOOTHFUSE_STATUS_OK);
    ASSERT_EQ(view.vertex_count, part.source.size());
    size_t bad_f = 0, bad_d = 0, bad_view = 0, bad_down = 0;
    for (size_t i = 0; i < part.source.size(); i++) {
      for (size_t k = 0; k < 3; k++) {
        const size_t j = 3 * part.source[i] + k;
        if (pf[3 * i + k] != static_cast<double>(jaw.fxyz[j])) bad_f++;
        if (std::memcmp(&pd[3 * i + k], &jaw.dxyz[j], sizeof(double)) != 0) bad_d++;
        if (std::memcmp(&view.positions[3 * i + k], &jaw.dxyz[j], sizeof(double)) != 0)
          bad_view++;
        if (pdf[3 * i + k] != static_cast<float>(jaw.dxyz[j])) bad_down++;
      }
    }
    EXPECT_EQ(bad_f, 0u) << "float input not converted exactly";
    EXPECT_EQ(bad_d, 0u) << "double input not kept bit for bit";
    EXPECT_EQ(bad_view, 0u) << "borrowed view differs from the input";
    EXPECT_EQ(bad_down, 0u) << "float copy-out is not the rounded double";
    EXPECT_TRUE(std::equal(view.indices, view.indices + view.index_count, part.indices.begin()));

    const toothfuse_mesh_info info = sd.info(m, fdi);
    EXPECT_TRUE(info.manifold);
    if (m == TOOTHFUSE_MODALITY_IOS) {
      EXPECT_FALSE(info.closed);
      EXPECT_EQ(info.boundary_loops, 1u) << "an IOS crown should have exactly one margin loop";
    } else {
      EXPECT_TRUE(info.closed);
      EXPECT_EQ(info.components, 1u);
      EXPECT_GT(info.signed_volume, 0.0) << "CBCT tooth not outward-oriented";
    }
  }
}

std::string demo_dir() {
  std::string d = tf::env_or_empty("TOOTHFUSE_DEMO_DIR");
  EXPECT_FALSE(d.empty()) << "TOOTHFUSE_DEMO_DIR is not set (run through ctest)";
  return d;
}

TEST(VtkRoundTrip, IosJawFloatAndDoubleLossless) {
  const Jaw jaw = load(demo_dir() + "/ios.ply");
  round_trip(jaw, TOOTHFUSE_MODALITY_IOS);
}

TEST(VtkRoundTrip, CbctTeethFloatAndDoubleLossless) {
  const Jaw jaw = load(demo_dir() + "/cbct.ply");
  round_trip(jaw, TOOTHFUSE_MODALITY_CBCT);
}

}  // namespace

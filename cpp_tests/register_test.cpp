// Registration through the C ABI on the synthetic jaw of the demo_jaw fixture: fed as float
// (vtkPLYReader points) and as double (OpenMesh), registered with the default options; the
// per-tooth TRE (RMS over the true tooth surface, mapped to the CBCT frame by world_to_cbct, of
// |estimated cbct_to_ios(p) - true cbct_to_ios(p)|) is <= 0.5 mm or the tooth carries a warning,
// and the median TRE is <= 0.25 mm.
#include "register_fuse_support.hpp"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPLYReader.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include <algorithm>
#include <cmath>

namespace {

std::string demo_dir() {
  const char* d = std::getenv("TOOTHFUSE_DEMO_DIR");
  return d ? d : "demo";
}

// The VTK float path: vtkPLYReader's float points and triangles, labels from OpenMesh's read of
// the same file (vtkPLYReader drops custom properties; the vertex order is the file's in both).
void add_jaw_vtk(tf::Session& s, toothfuse_modality m, const std::string& path) {
  tf::LabeledJaw om;
  ASSERT_TRUE(tf::read_labeled_jaw(path, om));
  vtkNew<vtkPLYReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* pd = reader->GetOutput();
  ASSERT_EQ(static_cast<size_t>(pd->GetNumberOfPoints()), om.labels.size());
  auto* pts = vtkFloatArray::SafeDownCast(pd->GetPoints()->GetData());
  ASSERT_NE(pts, nullptr) << "vtkPLYReader points are not float";
  std::vector<uint32_t> tris;
  auto it = vtk::TakeSmartPointer(pd->GetPolys()->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    it->GetCurrentCell(n, ids);
    ASSERT_EQ(n, 3);
    for (int k = 0; k < 3; k++) tris.push_back(static_cast<uint32_t>(ids[k]));
  }
  ASSERT_EQ(toothfuse_session_add_jaw(s.get(), m, pts->GetPointer(0), om.labels.size(),
                                      3 * sizeof(float), TOOTHFUSE_SCALAR_FLOAT32, tris.data(),
                                      tris.size(), om.labels.data(), om.labels.size(),
                                      TOOTHFUSE_LABEL_DOMAIN_VERTEX),
            TOOTHFUSE_STATUS_OK)
      << s.error();
}

// TRE of tooth `fdi`: RMS over the true surface (world frame, truth/tooth_<fdi>.ply).
double tre(const tf::Truth& truth, int fdi, const tf::Mat4& est) {
  tf::MeshD m;
  std::string path = demo_dir() + "/truth/tooth_" + std::to_string(fdi) + ".ply";
  if (!OpenMesh::IO::read_mesh(m, path)) {
    ADD_FAILURE() << "cannot read " << path;
    return 1e9;
  }
  const tf::Mat4& t = truth.cbct_to_ios.at(fdi);
  double sum = 0.0;
  for (auto vh : m.vertices()) {
    const auto& p = m.point(vh);
    double w[3] = {p[0], p[1], p[2]};
    auto c = tf::apply(truth.world_to_cbct, w);
    auto a = tf::apply(est, c.data());
    auto b = tf::apply(t, c.data());
    for (int k = 0; k < 3; k++) sum += (a[k] - b[k]) * (a[k] - b[k]);
  }
  return std::sqrt(sum / std::max<size_t>(m.n_vertices(), 1));
}

void check_registration(tf::Session& s, const char* what) {
  toothfuse_options o{};
  ASSERT_EQ(toothfuse_options_default(&o), TOOTHFUSE_STATUS_OK);
  ASSERT_EQ(toothfuse_session_register(s.get(), &o), TOOTHFUSE_STATUS_OK) << s.error();
  int32_t fdis[52];
  size_t n = 0;
  ASSERT_EQ(toothfuse_session_registered_teeth(s.get(), fdis, 52, &n), TOOTHFUSE_STATUS_OK);
  tf::Truth truth = tf::read_truth(demo_dir() + "/truth/truth.json");
  ASSERT_GE(n, 3u);
  std::vector<double> tres;
  for (size_t i = 0; i < n; i++) {
    tf::Mat4 est{};
    ASSERT_EQ(toothfuse_session_transform(s.get(), fdis[i], TOOTHFUSE_TRANSFORM_CBCT_TO_IOS,
                                          est.data()),
              TOOTHFUSE_STATUS_OK);
    ASSERT_TRUE(truth.cbct_to_ios.count(fdis[i])) << "tooth " << fdis[i] << " not in truth";
    double e = tre(truth, fdis[i], est);
    toothfuse_tooth_report r{};
    ASSERT_EQ(toothfuse_session_tooth_report(s.get(), fdis[i], &r), TOOTHFUSE_STATUS_OK);
    EXPECT_TRUE(e <= 0.5 || r.warning_count > 0)
        << what << ": tooth " << fdis[i] << " TRE " << e << " mm without a warning";
    EXPECT_GT(r.sd_mm, 0.0);
    EXPECT_LT(r.sd_mm, 0.5);
    tres.push_back(e);
  }
  std::sort(tres.begin(), tres.end());
  double median = tres[tres.size() / 2];
  std::printf("%s: %zu teeth, median TRE %.4f mm, worst %.4f mm\n", what, tres.size(), median,
              tres.back());
  EXPECT_LE(median, 0.25) << what;
}

TEST(Register, DemoJawFloatThroughVtk) {
  tf::Session s;
  add_jaw_vtk(s, TOOTHFUSE_MODALITY_IOS, demo_dir() + "/ios.ply");
  add_jaw_vtk(s, TOOTHFUSE_MODALITY_CBCT, demo_dir() + "/cbct.ply");
  ASSERT_FALSE(HasFatalFailure());
  check_registration(s, "VTK float");
}

TEST(Register, DemoJawDoubleThroughOpenMesh) {
  tf::Session s;
  ASSERT_TRUE(tf::load_demo(s, demo_dir(), false));
  check_registration(s, "OpenMesh double");
}

TEST(Register, GettersBeforeRegisterAreWrongState) {
  tf::Session s;
  tf::Mat4 m{};
  EXPECT_EQ(toothfuse_session_transform(s.get(), 11, TOOTHFUSE_TRANSFORM_CBCT_TO_IOS, m.data()),
            TOOTHFUSE_STATUS_WRONG_STATE);
  EXPECT_EQ(toothfuse_session_register(s.get(), nullptr), TOOTHFUSE_STATUS_MISSING_DATA);
  EXPECT_NE(s.error().find("at least 3 teeth"), std::string::npos) << s.error();
}

}  // namespace

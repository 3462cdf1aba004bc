// vtkToothfuseFilter with the CBCT as a vtkImageData label volume: jaw_2's CBCT teeth of the
// demo_jaws fixture voxelized (vtkPolyDataToImageStencil) on an oblique grid (rotated direction
// matrix, shifted origin and extent), fused per tooth (FDI labels, in LPS and RAS) and as
// DentalSegmentator's one upper-teeth class split by the IOS; checked for watertightness, fused
// roots on the voxelized CBCT teeth and TRE against the ground truth and against the fusion from
// the CBCT meshes. Part of the vtk_filter_test executable (vtk_filter_test.cpp).
#include "vtk_filter_support.hpp"

namespace {

using namespace vtk_filter_support;

// --- the CBCT as a label volume (vtkImageData) -------------------------------------------------

/// The direction of the label images: 30° about z, then 20° about x (an oblique grid).
vtkSmartPointer<vtkMatrix3x3> oblique() {
  const double a = 30.0 * M_PI / 180.0, b = 20.0 * M_PI / 180.0;
  const double rx[9] = {1, 0, 0, 0, std::cos(b), -std::sin(b), 0, std::sin(b), std::cos(b)};
  const double rz[9] = {std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1};
  auto m = vtkSmartPointer<vtkMatrix3x3>::New();
  vtkMatrix3x3::Multiply3x3(rx, rz, m->GetData());
  return m;
}

/// Tooth `fdi` of a labeled jaw as its own polydata (its triangles, its points mapped by `map`).
template <typename Map>
vtkSmartPointer<vtkPolyData> tooth_mesh(const tf::LabeledJaw& jaw, int fdi, Map map) {
  std::vector<double> xyz;
  std::vector<uint32_t> tris;
  std::map<uint32_t, uint32_t> index;
  for (size_t t = 0; t < jaw.tris.size() / 3; t++) {
    if (jaw.labels[jaw.tris[3 * t]] != fdi) continue;
    for (int k = 0; k < 3; k++) {
      const uint32_t v = jaw.tris[3 * t + k];
      auto it = index.emplace(v, static_cast<uint32_t>(index.size())).first;
      if (it->second == xyz.size() / 3) {
        const std::array<double, 3> q = map(&jaw.dxyz[3 * v]);
        xyz.insert(xyz.end(), q.begin(), q.end());
      }
      tris.push_back(it->second);
    }
  }
  return polydata(xyz, tris);
}

/// The CBCT teeth of demo jaw `d` voxelized into a label image whose world frame is the jaw's
/// CBCT frame: `voxel` mm voxels on an oblique grid (the direction of oblique()), its origin
/// shifted and its extent not starting at 0. A voxel holds the FDI number of the tooth whose
/// closed mesh contains its centre, or `jawClass` for every tooth when that is not 0 (one teeth
/// class per jaw). `scalars` receives the labels.
vtkSmartPointer<vtkImageData> label_image(const Demo& d, vtkDataArray* scalars, double voxel,
                                          int jawClass = 0) {
  vtkSmartPointer<vtkMatrix3x3> dir = oblique();
  // Grid coordinates of a world point: dir^T p (the grid's axes are dir's columns).
  auto to_grid = [&](const double* p) {
    std::array<double, 3> q{};
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) q[r] += dir->GetElement(c, r) * p[c];
    return q;
  };
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  std::set<int> teeth;
  for (size_t i = 0; i < d.cbct.labels.size(); i++) {
    if (d.cbct.labels[i] == 0) continue;
    teeth.insert(d.cbct.labels[i]);
    const std::array<double, 3> q = to_grid(&d.cbct.dxyz[3 * i]);
    for (int a = 0; a < 3; a++) {
      lo[a] = std::min(lo[a], q[a]);
      hi[a] = std::max(hi[a], q[a]);
    }
  }
  const int first[3] = {3, -2, 5};  // the extent's first index on each axis
  int extent[6], n[3];
  double gridOrigin[3];  // grid coordinates of structured index (0, 0, 0)
  for (int a = 0; a < 3; a++) {
    n[a] = static_cast<int>(std::ceil((hi[a] - lo[a] + 2.0) / voxel)) + 1;
    extent[2 * a] = first[a];
    extent[2 * a + 1] = first[a] + n[a] - 1;
    gridOrigin[a] = lo[a] - 1.0 - voxel * first[a];
  }
  scalars->SetName("labels");
  scalars->SetNumberOfComponents(1);
  scalars->SetNumberOfTuples(static_cast<vtkIdType>(n[0]) * n[1] * n[2]);
  scalars->Fill(0);
  for (int fdi : teeth) {
    vtkNew<vtkPolyDataToImageStencil> stencil;
    stencil->SetInputData(tooth_mesh(d.cbct, fdi, to_grid));
    stencil->SetOutputOrigin(gridOrigin);
    stencil->SetOutputSpacing(voxel, voxel, voxel);
    stencil->SetOutputWholeExtent(extent);
    stencil->Update();
    vtkImageStencilData* inside = stencil->GetOutput();
    for (int k = extent[4]; k <= extent[5]; k++)
      for (int j = extent[2]; j <= extent[3]; j++) {
        int r1 = 0, r2 = 0, iter = 0;
        while (inside->GetNextExtent(r1, r2, extent[0], extent[1], j, k, iter))
          for (int i = r1; i <= r2; i++)
            scalars->SetComponent(
                (i - extent[0]) + n[0] * ((j - extent[2]) + static_cast<vtkIdType>(n[1]) *
                                                                (k - extent[4])),
                0, jawClass ? jawClass : fdi);
      }
  }
  // World = origin + dir * spacing * index: the origin is the grid origin mapped by dir.
  double origin[3];
  dir->MultiplyPoint(gridOrigin, origin);
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetExtent(extent);
  image->SetSpacing(voxel, voxel, voxel);
  image->SetOrigin(origin);
  image->SetDirectionMatrix(dir);
  image->GetPointData()->SetScalars(scalars);
  return image;
}

std::string jaw_dir(int k) {
  const char* dir = std::getenv("TOOTHFUSE_JAWS_DIR");
  return std::string(dir ? dir : "") + "/jaw_" + std::to_string(k);
}

/// TRE (mm) of each tooth of a CBCT-frame report: the RMS over the true tooth (in the CBCT frame)
/// of the distance between the truth's CBCT -> IOS map followed by the estimated IOS -> CBCT map
/// (the report's `ios_to_output`) and the identity; both maps rigid, this equals the RMS
/// distance between the estimated and the true CBCT -> IOS maps.
std::map<int, double> tre_by_tooth(const std::string& json, const std::string& jawDir) {
  const tf::Truth truth = tf::read_truth(jawDir + "/truth/truth.json");
  std::map<int, double> tre;
  const size_t teethEnd = json.find("\"skipped\"");
  for (size_t at = json.find("\"fdi\": "); at < teethEnd; at = json.find("\"fdi\": ", at + 1)) {
    const int fdi = std::atoi(json.c_str() + at + 7);
    const tf::Mat4 iosToCbct = tf::parse16(json, json.find("\"ios_to_output\"", at));
    tf::MeshD t;
    const std::string path = jawDir + "/truth/tooth_" + std::to_string(fdi) + ".ply";
    if (!truth.cbct_to_ios.count(fdi) || !OpenMesh::IO::read_mesh(t, path)) {
      ADD_FAILURE() << "tooth " << fdi << ": no truth (" << path << ")";
      continue;
    }
    double sq = 0.0;
    for (auto vh : t.vertices()) {
      const double w[3] = {t.point(vh)[0], t.point(vh)[1], t.point(vh)[2]};
      const auto c = tf::apply(truth.world_to_cbct, w);
      const auto i = tf::apply(truth.cbct_to_ios.at(fdi), c.data());
      const auto e = tf::apply(iosToCbct, i.data());
      for (int a = 0; a < 3; a++) sq += (e[a] - c[a]) * (e[a] - c[a]);
    }
    tre[fdi] = std::sqrt(sq / std::max<size_t>(t.n_vertices(), 1));
  }
  return tre;
}

/// Per fused tooth: where its CBCT root points lie against the CBCT tooth mesh that was
/// voxelized (mean distance, share farther than 0.5 mm) and against all the CBCT teeth (share
/// farther than 0.5 mm from every one), its TRE and its warnings.
struct ImageToothFacts {
  double rootMeanMm = 0.0, rootFarShare = 0.0, rootOffTeethShare = 0.0, treMm = 0.0;
  std::vector<std::string> warnings;
};

/// Demo jaw `d`'s IOS and the label image `cbct` fused through the filter in the CBCT frame with
/// `scheme`: no error, the fused teeth those of `d.both` not reported skipped (with a reason),
/// the whole jaw and each tooth closed and manifold (check_teeth); returns the facts per tooth.
std::map<int, ImageToothFacts> fuse_image(Demo& d, int k, vtkImageData* cbct, int scheme,
                                          bool flipLpsRas = false) {
  vtkNew<vtkToothfuseFilter> f;
  ErrorSink errors(f);
  f->SetIOSInputData(d.iosPd);
  f->SetCBCTInputData(cbct);
  f->SetVolumeScheme(scheme);
  f->SetFlipImageLPSRAS(flipLpsRas);
  f->Update();
  EXPECT_TRUE(errors.messages.empty()) << errors.messages.front();
  EXPECT_EQ(f->GetLastStatus(), static_cast<int>(TOOTHFUSE_STATUS_OK));
  d.expected = d.both;
  for (int fdi : f->GetSkippedTeeth()) {
    std::printf("tooth %d skipped: %s\n", fdi, f->GetSkippedReason(fdi).c_str());
    EXPECT_FALSE(f->GetSkippedReason(fdi).empty()) << "tooth " << fdi;
    d.expected.erase(fdi);
  }
  EXPECT_EQ(std::set<int>(f->GetFusedTeeth().begin(), f->GetFusedTeeth().end()), d.expected);
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->ShallowCopy(f->GetOutput());
  EXPECT_EQ(open_or_non_manifold_edges(out), 0);  // the whole jaw: closed and manifold
  auto roots = check_teeth(d, out, 2);

  std::map<int, ImageToothFacts> facts;
  const std::map<int, double> tre = tre_by_tooth(f->GetReportJSON(), jaw_dir(k));
  // The CBCT frame is the image's world frame: the CBCT teeth as they were read.
  vtkNew<vtkStaticCellLocator> allTeeth;
  allTeeth->SetDataSet(d.cbctPd);
  allTeeth->BuildLocator();
  auto distance = [](vtkStaticCellLocator* locator, const Key& p) {
    double closest[3], d2 = 0.0;
    vtkIdType cell = 0;
    int sub = 0;
    locator->FindClosestPoint(p.data(), closest, cell, sub, d2);
    return std::sqrt(d2);
  };
  for (int fdi : d.expected) {
    vtkNew<vtkStaticCellLocator> own;
    own->SetDataSet(tooth_mesh(d.cbct, fdi, [](const double* p) {
      return std::array<double, 3>{p[0], p[1], p[2]};
    }));
    own->BuildLocator();
    ImageToothFacts& t = facts[fdi];
    size_t far = 0, off = 0;
    for (const Key& p : roots[fdi]) {
      const double e = distance(own, p);
      t.rootMeanMm += e;
      far += e > 0.5 ? 1 : 0;
      off += e > 0.5 && distance(allTeeth, p) > 0.5 ? 1 : 0;
    }
    const double n = static_cast<double>(std::max<size_t>(roots[fdi].size(), 1));
    t.rootMeanMm /= n;
    t.rootFarShare = static_cast<double>(far) / n;
    t.rootOffTeethShare = static_cast<double>(off) / n;
    EXPECT_TRUE(tre.count(fdi)) << "tooth " << fdi << " not in the report";
    t.treMm = tre.count(fdi) ? tre.at(fdi) : 1e9;
    t.warnings = f->GetToothWarnings(fdi);
    for (const std::string& w : t.warnings) std::printf("tooth %d warning: %s\n", fdi, w.c_str());
    std::printf("tooth %d: root to its CBCT tooth: mean %.3f mm, %.1f%% over 0.5 mm (%.1f%% from "
                "every CBCT tooth); TRE %.3f mm\n",
                fdi, t.rootMeanMm, 100.0 * t.rootFarShare, 100.0 * t.rootOffTeethShare, t.treMm);
  }
  return facts;
}

/// TRE per tooth of demo jaw `d` fused from its CBCT meshes (CBCT frame): the reference.
const std::map<int, double>& mesh_path_tre(Demo& d, int k) {
  static std::map<int, std::map<int, double>> cache;
  if (cache.count(k)) return cache[k];
  vtkNew<vtkToothfuseFilter> f;
  f->SetIOSInputData(d.iosPd);
  f->SetCBCTInputData(d.cbctPd);
  f->SetCBCTLabelArrayName("tooth");
  f->Update();
  std::map<int, double>& tre = cache[k];
  tre = tre_by_tooth(f->GetReportJSON(), jaw_dir(k));
  for (const auto& t : tre)
    std::printf("tooth %d from the meshes: TRE %.3f mm\n", t.first, t.second);
  return tre;
}

// jaw_2's CBCT teeth as a per-tooth FDI label image (short scalars, 0.3 mm oblique grid): every
// tooth fused, its root on the voxelized CBCT tooth (the image's placement is right), and TRE as
// good as from the CBCT meshes.
TEST(VtkToothfuseFilter, FusesPerToothLabelImageOnObliqueGrid) {
  Demo& d = demo(2);
  ASSERT_TRUE(d.ok);
  vtkNew<vtkShortArray> labels;
  vtkSmartPointer<vtkImageData> image = label_image(d, labels, 0.3);
  const auto facts = fuse_image(d, 2, image, vtkToothfuseFilter::VOLUME_SCHEME_FDI);
  EXPECT_EQ(d.expected, d.both) << "every tooth of the image fused";
  const std::map<int, double>& ref = mesh_path_tre(d, 2);
  for (const auto& t : facts) {
    SCOPED_TRACE("tooth " + std::to_string(t.first));
    EXPECT_LT(t.second.rootMeanMm, 0.1);
    EXPECT_LT(t.second.rootFarShare, 0.01);
    for (const std::string& w : t.second.warnings)
      EXPECT_EQ(w.find("split"), std::string::npos) << w;
    ASSERT_TRUE(ref.count(t.first));
    EXPECT_LT(t.second.treMm, ref.at(t.first) * 1.1 + 0.05) << "vs " << ref.at(t.first);
  }
}

// The same per-tooth label image with its world in the other of LPS and RAS (origin and
// direction negated in x and y, as a reader of the other convention gives it): with
// FlipImageLPSRAS the filter brings it back to the meshes' frame and fuses it as well.
TEST(VtkToothfuseFilter, FusesLabelImageInTheOtherOfLpsAndRas) {
  Demo& d = demo(2);
  ASSERT_TRUE(d.ok);
  vtkNew<vtkShortArray> labels;
  vtkSmartPointer<vtkImageData> image = label_image(d, labels, 0.3);
  double origin[3];
  image->GetOrigin(origin);
  image->SetOrigin(-origin[0], -origin[1], origin[2]);
  vtkNew<vtkMatrix3x3> dir;
  dir->DeepCopy(image->GetDirectionMatrix());
  for (int r = 0; r < 2; r++)
    for (int c = 0; c < 3; c++) dir->SetElement(r, c, -dir->GetElement(r, c));
  image->SetDirectionMatrix(dir);
  const auto facts = fuse_image(d, 2, image, vtkToothfuseFilter::VOLUME_SCHEME_FDI, true);
  EXPECT_EQ(d.expected, d.both) << "every tooth of the image fused";
  for (const auto& t : facts) {
    SCOPED_TRACE("tooth " + std::to_string(t.first));
    EXPECT_LT(t.second.rootMeanMm, 0.1);
    EXPECT_LT(t.second.rootFarShare, 0.01);
  }
}

// The same teeth as DentalSegmentator's upper-teeth class 3 (unsigned char scalars): the mask is
// split into teeth by the registered IOS crowns, then fused; each tooth's split share of
// contested voxels is among its warnings. Where 11 and 21 touch at the midline, the split's
// long-axis floods keep 11 off 21's root: measured, no tooth's root points over 0.5 mm from its
// own CBCT tooth (before them, 14% of 11's root points lay on 21 with 1.1% of its voxels
// contested), and the TRE equals the per-tooth path's (the registration uses the crowns).
TEST(VtkToothfuseFilter, FusesPerJawTeethMaskSplitByTheIos) {
  Demo& d = demo(2);
  ASSERT_TRUE(d.ok);
  vtkNew<vtkUnsignedCharArray> labels;
  vtkSmartPointer<vtkImageData> image = label_image(d, labels, 0.3, 3);
  const auto facts = fuse_image(d, 2, image, vtkToothfuseFilter::VOLUME_SCHEME_DENTALSEGMENTATOR);
  EXPECT_EQ(d.expected, d.both) << "every tooth split out and fused";
  const std::map<int, double>& ref = mesh_path_tre(d, 2);
  double farShare = 0.0;
  for (const auto& t : facts) {
    SCOPED_TRACE("tooth " + std::to_string(t.first));
    farShare += t.second.rootFarShare / static_cast<double>(facts.size());
    EXPECT_LT(t.second.rootFarShare, 0.02) << "root points off the tooth's own CBCT tooth";
    EXPECT_LT(t.second.rootOffTeethShare, 0.05) << "root points off every CBCT tooth";
    size_t split = 0;
    for (const std::string& w : t.second.warnings)
      split += w.find("split from the per-jaw teeth mask") != std::string::npos &&
               w.find("contested") != std::string::npos;
    EXPECT_EQ(split, 1u) << "the split's share of contested voxels among the warnings";
    ASSERT_TRUE(ref.count(t.first));
    EXPECT_LT(t.second.treMm, ref.at(t.first) * 1.5) << "vs " << ref.at(t.first);
  }
  EXPECT_LT(farShare, 0.01) << "mean share of root points off their own CBCT tooth";
}

}  // namespace

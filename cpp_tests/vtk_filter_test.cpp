// vtkToothfuseFilter (bindings/vtk) on two synthetic jaws of the demo_jaws fixture (partial
// arches: jaw_2 upper, jaw_7 lower), checked with VTK's own filters: per tooth (vtkThreshold on the
// output "label"), vtkFeatureEdges finds no boundary or non-manifold edge,
// vtkPolyDataConnectivityFilter one region, vtkMassProperties a positive volume; every source-0
// (IOS) point is an input IOS point of that tooth, bit for bit, and there are exactly as many
// as the tooth's crown has (IOS frame); every source-2 (CBCT) point is an input CBCT point of
// that tooth (CBCT frame). The CBCT as a vtkImageData label volume: jaw_2's CBCT teeth
// voxelized (vtkPolyDataToImageStencil) on an oblique grid (rotated direction matrix, shifted
// origin and extent), fused per tooth (FDI labels) and as DentalSegmentator's one upper-teeth
// class split by the IOS; checked for watertightness, fused roots on the voxelized CBCT teeth and
// TRE against the ground truth. Error paths: a missing label array, a non-FDI label, too few
// teeth, float or multi-component image scalars, a negative label in copied image scalars give
// one clean vtkError naming the cause (toothfuse's own message for library errors) and an empty
// output; the volume scheme reaches the library (label 5: refused as FDI, added as Universal).
#include "register_fuse_support.hpp"

#include <vtkCallbackCommand.h>
#include <vtkExecutive.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFeatureEdges.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkGeometryFilter.h>
#include <vtkImageData.h>
#include <vtkImageStencilData.h>
#include <vtkIntArray.h>
#include <vtkLongLongArray.h>
#include <vtkMassProperties.h>
#include <vtkMatrix3x3.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkPolyDataToImageStencil.h>
#include <vtkShortArray.h>
#include <vtkSmartPointer.h>
#include <vtkStaticCellLocator.h>
#include <vtkStringArray.h>
#include <vtkThreshold.h>
#include <vtkToothfuseFilter.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <set>

namespace {

using Key = std::array<double, 3>;

/// Collects the messages of vtkErrorMacro (ErrorEvent) of a filter (`messages`) and of its
/// executive (`pipeline`: "returned failure for request" when RequestData failed).
struct ErrorSink {
  std::vector<std::string> messages, pipeline;
  vtkNew<vtkCallbackCommand> cb, pcb;
  explicit ErrorSink(vtkAlgorithm* a) {
    cb->SetClientData(&messages);
    pcb->SetClientData(&pipeline);
    for (vtkCallbackCommand* c : {cb.Get(), pcb.Get()})
      c->SetCallback([](vtkObject*, unsigned long, void* list, void* data) {
        static_cast<std::vector<std::string>*>(list)->emplace_back(
            static_cast<const char*>(data));
      });
    a->AddObserver(vtkCommand::ErrorEvent, cb);
    a->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, pcb);
  }
};

vtkSmartPointer<vtkPolyData> polydata(const std::vector<double>& xyz,
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

struct Demo {
  tf::LabeledJaw ios, cbct;
  vtkSmartPointer<vtkPolyData> iosPd, cbctPd;
  std::set<int> both;      // labels in both modalities
  std::set<int> expected;  // fused teeth: `both` less the teeth the filter reports skipped
  bool ok = false;
};

/// Boundary and non-manifold edges of `mesh`, by VTK's vtkFeatureEdges (0: closed, manifold).
vtkIdType open_or_non_manifold_edges(vtkPolyData* mesh) {
  vtkNew<vtkFeatureEdges> fe;
  fe->SetInputData(mesh);
  fe->BoundaryEdgesOn();
  fe->NonManifoldEdgesOn();
  fe->FeatureEdgesOff();
  fe->ManifoldEdgesOff();
  fe->Update();
  return fe->GetOutput()->GetNumberOfCells();
}

/// jaw_<k> of the demo_jaws fixture as VTK inputs.
Demo& demo(int k) {
  static std::map<int, Demo> cache;
  if (cache.count(k)) return cache[k];
  Demo& d = cache[k];
  {
    const char* dir = std::getenv("TOOTHFUSE_JAWS_DIR");
    if (!dir) {
      ADD_FAILURE() << "TOOTHFUSE_JAWS_DIR is not set (the demo_jaws fixture)";
      return d;
    }
    const std::string jaw = std::string(dir) + "/jaw_" + std::to_string(k);
    if (!tf::read_labeled_jaw(jaw + "/ios.ply", d.ios) ||
        !tf::read_labeled_jaw(jaw + "/cbct.ply", d.cbct))
      return d;
    // IOS: per-point int labels under the default name "label".
    d.iosPd = polydata(d.ios.dxyz, d.ios.tris);
    vtkNew<vtkIntArray> il;
    il->SetName("label");
    for (int32_t l : d.ios.labels) il->InsertNextValue(l);
    d.iosPd->GetPointData()->AddArray(il);
    // CBCT: per-cell short labels named "tooth" (teeth are separate components, so a face's
    // vertices share one label).
    d.cbctPd = polydata(d.cbct.dxyz, d.cbct.tris);
    vtkNew<vtkShortArray> cl;
    cl->SetName("tooth");
    for (size_t t = 0; t < d.cbct.tris.size() / 3; t++)
      cl->InsertNextValue(static_cast<short>(d.cbct.labels[d.cbct.tris[3 * t]]));
    d.cbctPd->GetCellData()->AddArray(cl);
    std::set<int> a(d.ios.labels.begin(), d.ios.labels.end());
    for (int32_t l : d.cbct.labels)
      if (l != 0 && a.count(l)) d.both.insert(l);
    d.ok = true;
  }
  return d;
}

vtkSmartPointer<vtkPolyData> tooth_of(vtkPolyData* jaw, int fdi) {
  vtkNew<vtkThreshold> th;
  th->SetInputData(jaw);
  th->SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, "label");
  th->SetLowerThreshold(fdi - 0.5);
  th->SetUpperThreshold(fdi + 0.5);
  th->SetThresholdFunction(vtkThreshold::THRESHOLD_BETWEEN);
  th->AllScalarsOn();
  vtkNew<vtkGeometryFilter> geom;
  geom->SetInputConnection(th->GetOutputPort());
  geom->MergingOff();
  geom->Update();
  return geom->GetOutput();
}

/// Demo jaw `d` fused with `frame`; checks the whole-jaw facts and returns the output.
vtkSmartPointer<vtkPolyData> fuse_demo(Demo& d, int frame) {
  vtkNew<vtkToothfuseFilter> f;
  ErrorSink errors(f);
  f->SetIOSInputData(d.iosPd);
  f->SetCBCTInputData(d.cbctPd);
  f->SetCBCTLabelArrayName("tooth");
  f->SetFrame(frame);
  f->Update();
  EXPECT_TRUE(errors.messages.empty()) << errors.messages.front();
  EXPECT_TRUE(errors.pipeline.empty()) << errors.pipeline.front();
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->ShallowCopy(f->GetOutput());
  // Skipped teeth: reported with a reason, in the field data too, absent from the output.
  d.expected = d.both;
  auto* skipped = vtkIntArray::SafeDownCast(out->GetFieldData()->GetArray("skipped_fdi"));
  EXPECT_TRUE(skipped && skipped->GetNumberOfTuples() ==
                             static_cast<vtkIdType>(f->GetSkippedTeeth().size()));
  for (size_t i = 0; i < f->GetSkippedTeeth().size(); i++) {
    int fdi = f->GetSkippedTeeth()[i];
    EXPECT_FALSE(f->GetSkippedReason(fdi).empty()) << "tooth " << fdi;
    if (skipped && static_cast<vtkIdType>(i) < skipped->GetNumberOfTuples()) {
      EXPECT_EQ(skipped->GetValue(static_cast<vtkIdType>(i)), fdi);
    }
    std::printf("tooth %d skipped: %s\n", fdi, f->GetSkippedReason(fdi).c_str());
    d.expected.erase(fdi);
  }
  EXPECT_GE(d.expected.size(), 2u);
  EXPECT_EQ(std::set<int>(f->GetFusedTeeth().begin(), f->GetFusedTeeth().end()), d.expected);
  auto* json =
      vtkStringArray::SafeDownCast(out->GetFieldData()->GetAbstractArray("toothfuse_report"));
  EXPECT_TRUE(json && json->GetValue(0).find(frame == vtkToothfuseFilter::FRAME_IOS
                                                 ? "\"frame\": \"ios\""
                                                 : "\"frame\": \"cbct\"") != std::string::npos)
      << (json ? json->GetValue(0).substr(0, 200) : "no toothfuse_report");

  vtkDataArray* label = out->GetPointData()->GetArray("label");
  vtkDataArray* source = out->GetPointData()->GetArray("source");
  EXPECT_TRUE(label && source);
  if (!label || !source) return out;
  std::set<int> labels;
  for (vtkIdType i = 0; i < out->GetNumberOfPoints(); i++) {
    labels.insert(static_cast<int>(label->GetComponent(i, 0)));
    double s = source->GetComponent(i, 0);
    EXPECT_TRUE(s == 0 || s == 1 || s == 2) << "point " << i << " source " << s;
  }
  EXPECT_EQ(labels, d.expected);
  EXPECT_EQ(open_or_non_manifold_edges(out), 0);  // the whole jaw: closed and manifold
  return out;
}

/// Per tooth: closed, manifold, one region, positive volume, all three sources present;
/// returns, per tooth, the points of source `src`.
std::map<int, std::vector<Key>> check_teeth(const Demo& d, vtkPolyData* out, int src) {
  std::map<int, std::vector<Key>> points;
  for (int fdi : d.expected) {
    SCOPED_TRACE("tooth " + std::to_string(fdi));
    vtkSmartPointer<vtkPolyData> t = tooth_of(out, fdi);
    EXPECT_GT(t->GetNumberOfCells(), 0);
    if (t->GetNumberOfCells() == 0) continue;
    EXPECT_EQ(open_or_non_manifold_edges(t), 0) << "boundary or non-manifold edges";
    vtkNew<vtkPolyDataConnectivityFilter> cc;
    cc->SetInputData(t);
    cc->SetExtractionModeToAllRegions();
    cc->Update();
    EXPECT_EQ(cc->GetNumberOfExtractedRegions(), 1);
    vtkNew<vtkMassProperties> mp;
    mp->SetInputData(t);
    mp->Update();
    EXPECT_GT(mp->GetVolume(), 50.0);  // a real tooth, mm^3
    std::array<size_t, 3> per{};
    vtkDataArray* source = t->GetPointData()->GetArray("source");
    std::set<vtkIdType> used;  // vtkGeometryFilter keeps unused points: count used ones only
    for (vtkIdType c = 0; c < t->GetNumberOfCells(); c++) {
      vtkIdType n = 0;
      const vtkIdType* ids = nullptr;
      t->GetCellPoints(c, n, ids);
      used.insert(ids, ids + n);
    }
    for (vtkIdType i : used) {
      int s = static_cast<int>(source->GetComponent(i, 0));
      per[s]++;
      if (s == src) {
        double p[3];
        t->GetPoint(i, p);
        points[fdi].push_back({p[0], p[1], p[2]});
      }
    }
    EXPECT_GT(per[0], 100u) << "IOS crown points";
    EXPECT_GT(per[1], 10u) << "band points";
    EXPECT_GT(per[2], 100u) << "CBCT root points";
  }
  return points;
}

// jaw_2: seed 3, partial upper arch (5 teeth).
TEST(VtkToothfuseFilter, FusesDemoJawInIosFrameKeepingEveryCrownVertex) {
  Demo& d = demo(2);
  ASSERT_TRUE(d.ok);
  ASSERT_GE(d.both.size(), 3u);
  vtkSmartPointer<vtkPolyData> out = fuse_demo(d, vtkToothfuseFilter::FRAME_IOS);
  auto crown = check_teeth(d, out, 0);
  // The crown of tooth L: the IOS vertices of triangles whose three vertices are labeled L.
  std::map<int, std::set<Key>> expected;
  const auto& ios = d.ios;
  for (size_t t = 0; t < ios.tris.size() / 3; t++) {
    const uint32_t* v = &ios.tris[3 * t];
    int l = ios.labels[v[0]];
    if (l == 0 || ios.labels[v[1]] != l || ios.labels[v[2]] != l) continue;
    for (int k = 0; k < 3; k++)
      expected[l].insert({ios.dxyz[3 * v[k]], ios.dxyz[3 * v[k] + 1], ios.dxyz[3 * v[k] + 2]});
  }
  for (int fdi : d.expected) {
    const std::set<Key> got(crown[fdi].begin(), crown[fdi].end());
    EXPECT_EQ(got.size(), crown[fdi].size()) << "tooth " << fdi << ": repeated crown points";
    EXPECT_EQ(got, expected[fdi]) << "tooth " << fdi << ": crown points differ from the input";
  }
}

// MaxThreads 1 runs the update on the calling thread: the same output, point for point and
// triangle for triangle, as an update on as many threads as the CPUs allow.
TEST(VtkToothfuseFilter, OneThreadGivesTheSameOutput) {
  Demo& d = demo(2);
  ASSERT_TRUE(d.ok);
  auto run = [&](int threads) {
    vtkNew<vtkToothfuseFilter> f;
    ErrorSink errors(f);
    f->SetIOSInputData(d.iosPd);
    f->SetCBCTInputData(d.cbctPd);
    f->SetCBCTLabelArrayName("tooth");
    f->SetMaxThreads(threads);
    EXPECT_EQ(f->GetMaxThreads(), threads < 0 ? 0 : threads);
    f->Update();
    EXPECT_TRUE(errors.messages.empty()) << errors.messages.front();
    auto out = vtkSmartPointer<vtkPolyData>::New();
    out->ShallowCopy(f->GetOutput());
    return out;
  };
  vtkSmartPointer<vtkPolyData> one = run(1), free = run(0);
  run(-3);  // clamped to 0
  ASSERT_GT(one->GetNumberOfPoints(), 1000);
  ASSERT_EQ(one->GetNumberOfPoints(), free->GetNumberOfPoints());
  ASSERT_EQ(one->GetNumberOfCells(), free->GetNumberOfCells());
  for (vtkIdType i = 0; i < one->GetNumberOfPoints(); i++) {
    double a[3], b[3];
    one->GetPoint(i, a);
    free->GetPoint(i, b);
    ASSERT_TRUE(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]) << "point " << i;
  }
  for (vtkIdType c = 0; c < one->GetNumberOfCells(); c++) {
    vtkIdType na = 0, nb = 0;
    const vtkIdType *pa = nullptr, *pb = nullptr;
    one->GetCellPoints(c, na, pa);
    free->GetCellPoints(c, nb, pb);
    ASSERT_EQ(na, nb);
    for (vtkIdType k = 0; k < na; k++) ASSERT_EQ(pa[k], pb[k]) << "cell " << c;
  }
}

// The update's progress comes as ProgressEvent, rising from 0 to 1 on the updating thread;
// SetAbortExecute(1) from an observer during the stitching cancels it: an empty output, no
// error, status CANCELLED; the next update without the abort fuses the jaw as before.
TEST(VtkToothfuseFilter, ReportsProgressAndAbortsFromAnObserver) {
  Demo& d = demo(2);
  ASSERT_TRUE(d.ok);
  struct Watch {
    vtkToothfuseFilter* filter = nullptr;
    std::vector<double> seen;
    double abortAt = 2.0;  // never
  } w;
  vtkNew<vtkToothfuseFilter> f;
  w.filter = f;
  ErrorSink errors(f);
  vtkNew<vtkCallbackCommand> cb;
  cb->SetClientData(&w);
  cb->SetCallback([](vtkObject*, unsigned long, void* client, void* data) {
    auto* w = static_cast<Watch*>(client);
    double p = *static_cast<double*>(data);
    w->seen.push_back(p);
    if (p >= w->abortAt) w->filter->SetAbortExecute(1);
  });
  f->AddObserver(vtkCommand::ProgressEvent, cb);
  f->SetIOSInputData(d.iosPd);
  f->SetCBCTInputData(d.cbctPd);
  f->SetCBCTLabelArrayName("tooth");
  f->Update();
  EXPECT_TRUE(errors.messages.empty()) << errors.messages.front();
  EXPECT_EQ(f->GetLastStatus(), 0);
  const vtkIdType points = f->GetOutput()->GetNumberOfPoints();
  ASSERT_GT(points, 1000);
  ASSERT_GE(w.seen.size(), 4u);
  EXPECT_TRUE(std::is_sorted(w.seen.begin(), w.seen.end())) << ::testing::PrintToString(w.seen);
  EXPECT_EQ(w.seen.back(), 1.0);
  EXPECT_TRUE(std::any_of(w.seen.begin(), w.seen.end(),
                          [](double p) { return p > 0.35 && p < 1.0; }))
      << "no report within the stitching";

  // Aborted within the stitching.
  w.seen.clear();
  w.abortAt = 0.4;
  f->Modified();
  f->Update();
  EXPECT_TRUE(errors.messages.empty()) << errors.messages.front();
  EXPECT_TRUE(errors.pipeline.empty()) << errors.pipeline.front();
  EXPECT_EQ(f->GetLastStatus(), static_cast<int>(TOOTHFUSE_STATUS_CANCELLED));
  EXPECT_EQ(f->GetOutput()->GetNumberOfPoints(), 0);
  ASSERT_FALSE(w.seen.empty());
  EXPECT_LT(w.seen.back(), 1.0) << "the update ran to its end";

  // Without the abort, the same jaw again.
  w.abortAt = 2.0;
  f->SetAbortExecute(0);
  f->Modified();
  f->Update();
  EXPECT_EQ(f->GetLastStatus(), 0);
  EXPECT_EQ(f->GetOutput()->GetNumberOfPoints(), points);
}

// jaw_7: seed 8, partial lower arch (3 teeth; a tooth whose fusion fails is reported skipped).
TEST(VtkToothfuseFilter, FusesDemoJawInCbctFrameWithCbctRootPoints) {
  Demo& d = demo(7);
  ASSERT_TRUE(d.ok);
  ASSERT_GE(d.both.size(), 3u);
  vtkSmartPointer<vtkPolyData> out = fuse_demo(d, vtkToothfuseFilter::FRAME_CBCT);
  auto root = check_teeth(d, out, 2);
  std::map<int, std::set<Key>> cbct;
  for (size_t i = 0; i < d.cbct.labels.size(); i++)
    cbct[d.cbct.labels[i]].insert({d.cbct.dxyz[3 * i], d.cbct.dxyz[3 * i + 1],
                                   d.cbct.dxyz[3 * i + 2]});
  for (int fdi : d.expected) {
    size_t foreign = 0;
    for (const Key& k : root[fdi]) foreign += cbct[fdi].count(k) ? 0 : 1;
    EXPECT_EQ(foreign, 0u) << "tooth " << fdi << ": root points not in the input CBCT tooth";
    EXPECT_LT(root[fdi].size(), cbct[fdi].size()) << "tooth " << fdi << ": crown not removed";
  }
}

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

// --- error paths -------------------------------------------------------------------------------

// An open box (5 faces: crown-like, one boundary loop) and a closed box, side 8 mm.
const std::vector<double> kBox = {0, 0, 0, 8, 0, 0, 8, 8, 0, 0, 8, 0,
                                  0, 0, 8, 8, 0, 8, 8, 8, 8, 0, 8, 8};
const std::vector<uint32_t> kClosed = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                       1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
const std::vector<uint32_t> kOpen(kClosed.begin() + 6, kClosed.end());

vtkSmartPointer<vtkPolyData> labeled_box(const std::vector<uint32_t>& tris, int label,
                                         const char* name = "label") {
  auto pd = polydata(kBox, tris);
  vtkNew<vtkIntArray> l;
  l->SetName(name);
  for (int i = 0; i < 8; i++) l->InsertNextValue(label);
  pd->GetPointData()->AddArray(l);
  return pd;
}

/// Runs the filter and returns its one error message (and checks the output is empty).
std::string run_expecting_error(vtkPolyData* ios, vtkPolyData* cbct) {
  vtkNew<vtkToothfuseFilter> f;
  ErrorSink errors(f);
  f->SetIOSInputData(ios);
  f->SetCBCTInputData(cbct);
  f->Update();
  EXPECT_EQ(errors.messages.size(), 1u);
  EXPECT_EQ(errors.pipeline.size(), 1u);  // the request failed
  EXPECT_EQ(f->GetOutput()->GetNumberOfPoints(), 0);
  EXPECT_TRUE(f->GetFusedTeeth().empty());
  return errors.messages.empty() ? std::string() : errors.messages[0];
}

TEST(VtkToothfuseFilter, MissingLabelArrayIsACleanError) {
  auto ios = labeled_box(kOpen, 11, "tooth_id");
  auto cbct = labeled_box(kClosed, 11);
  std::string m = run_expecting_error(ios, cbct);
  EXPECT_NE(m.find("IOS input has no point or cell data array named \"label\""),
            std::string::npos) << m;
  // The name setter fixes it for IOS; the CBCT's wrong name is then the error.
  vtkNew<vtkToothfuseFilter> f;
  ErrorSink errors(f);
  f->SetIOSInputData(ios);
  f->SetCBCTInputData(cbct);
  f->SetIOSLabelArrayName("tooth_id");
  f->SetCBCTLabelArrayName("fdi");
  f->Update();
  ASSERT_EQ(errors.messages.size(), 1u);
  EXPECT_NE(errors.messages[0].find("CBCT input has no point or cell data array named \"fdi\""),
            std::string::npos) << errors.messages[0];
}

TEST(VtkToothfuseFilter, LibraryErrorsCarryToothfuseMessage) {
  // A non-FDI label: toothfuse's message names the label and the vertex.
  std::string m = run_expecting_error(labeled_box(kOpen, 19), labeled_box(kClosed, 11));
  EXPECT_NE(m.find("toothfuse_session_add_jaw (IOS) failed (invalid argument"),
            std::string::npos) << m;
  EXPECT_NE(m.find("label 19 (on vertex"), std::string::npos) << m;
  // An open CBCT tooth.
  m = run_expecting_error(labeled_box(kOpen, 11), labeled_box(kOpen, 11));
  EXPECT_NE(m.find("toothfuse_session_add_jaw (CBCT) failed"), std::string::npos) << m;
  EXPECT_NE(m.find("tooth 11"), std::string::npos) << m;
  // One tooth is too few to register.
  m = run_expecting_error(labeled_box(kOpen, 11), labeled_box(kClosed, 11));
  EXPECT_NE(m.find("toothfuse_session_fuse failed (missing data"), std::string::npos) << m;
  // Quads with per-cell labels are triangulated (labels follow): both jaws are accepted, and
  // the fuse itself is what fails.
  const std::vector<std::vector<vtkIdType>> quads = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                     {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  vtkSmartPointer<vtkPolyData> qbox[2];
  for (int k = 0; k < 2; k++) {  // k = 0: open (no bottom quad), 1: closed
    qbox[k] = polydata(kBox, {});
    vtkNew<vtkCellArray> polys;
    vtkNew<vtkIntArray> cl;
    cl->SetName("label");
    for (size_t q = 1 - k; q < quads.size(); q++) {
      polys->InsertNextCell(4, quads[q].data());
      cl->InsertNextValue(11);
    }
    qbox[k]->SetPolys(polys);
    qbox[k]->GetCellData()->AddArray(cl);
  }
  m = run_expecting_error(qbox[0], qbox[1]);
  EXPECT_NE(m.find("toothfuse_session_fuse failed (missing data"), std::string::npos) << m;
  // Non-integer labels are refused before the library is called.
  auto bad = labeled_box(kOpen, 11);
  vtkNew<vtkDoubleArray> frac;
  frac->SetName("label");
  for (int i = 0; i < 8; i++) frac->InsertNextValue(i == 5 ? 11.5 : 11.0);
  bad->GetPointData()->AddArray(frac);  // replaces the int array of that name
  m = run_expecting_error(bad, labeled_box(kClosed, 11));
  EXPECT_NE(m.find("value 11.5 at point 5 is not an integer tooth label"), std::string::npos)
      << m;
}

TEST(VtkToothfuseFilter, UnsupportedImageScalarsAreACleanError) {
  // A 6x6x6 grid of 1 mm voxels holding a 4-voxel cube (64 mm^3) of label `label`.
  auto image_of = [](vtkDataArray* scalars, int components, int label) {
    auto image = vtkSmartPointer<vtkImageData>::New();
    image->SetDimensions(6, 6, 6);
    scalars->SetName("labels");
    scalars->SetNumberOfComponents(components);
    scalars->SetNumberOfTuples(216);
    scalars->Fill(0);
    for (int k = 1; k < 5; k++)
      for (int j = 1; j < 5; j++)
        for (int i = 1; i < 5; i++) scalars->SetComponent(i + 6 * (j + 6 * k), 0, label);
    image->GetPointData()->SetScalars(scalars);
    return image;
  };
  auto run = [](vtkDataObject* cbct, int* status, int scheme) {
    vtkNew<vtkToothfuseFilter> f;
    ErrorSink errors(f);
    f->SetIOSInputData(labeled_box(kOpen, 11));
    f->SetCBCTInputData(cbct);
    f->SetVolumeScheme(scheme);
    f->Update();
    EXPECT_EQ(errors.messages.size(), 1u);
    EXPECT_EQ(errors.pipeline.size(), 1u);  // the request failed
    EXPECT_EQ(f->GetOutput()->GetNumberOfPoints(), 0);
    *status = f->GetLastStatus();
    return errors.messages.empty() ? std::string() : errors.messages[0];
  };
  const int fdi = vtkToothfuseFilter::VOLUME_SCHEME_FDI;
  int status = 0;
  vtkNew<vtkFloatArray> floats;
  std::string m = run(image_of(floats, 1, 11), &status, fdi);
  EXPECT_NE(m.find("CBCT image scalars \"labels\" are of type float: a label volume holds "
                   "integer labels"),
            std::string::npos)
      << m;
  EXPECT_EQ(status, static_cast<int>(TOOTHFUSE_STATUS_INVALID_ARGUMENT));
  vtkNew<vtkUnsignedCharArray> rgb;
  m = run(image_of(rgb, 3, 11), &status, fdi);
  EXPECT_NE(m.find("CBCT image scalars \"labels\" have 3 components"), std::string::npos) << m;
  EXPECT_EQ(status, static_cast<int>(TOOTHFUSE_STATUS_INVALID_ARGUMENT));
  // Other integer types are copied, refusing what no label type holds.
  vtkNew<vtkLongLongArray> wide;
  vtkSmartPointer<vtkImageData> image = image_of(wide, 1, 11);
  wide->SetComponent(100, 0, -1);
  m = run(image, &status, fdi);
  EXPECT_NE(m.find("CBCT image scalars \"labels\": label -1 at voxel 100 is outside 0-65535"),
            std::string::npos)
      << m;
  EXPECT_EQ(status, static_cast<int>(TOOTHFUSE_STATUS_INVALID_ARGUMENT));
  // Integer scalars reach the library, whose message names the fault: label 19 is no FDI tooth.
  vtkNew<vtkIntArray> ints;
  image = image_of(ints, 1, 11);
  ints->SetComponent(100, 0, 19);
  m = run(image, &status, fdi);
  EXPECT_NE(m.find("toothfuse_session_add_label_volume (CBCT) failed (invalid argument"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("19"), std::string::npos) << m;
  EXPECT_EQ(status, static_cast<int>(TOOTHFUSE_STATUS_INVALID_ARGUMENT));
  // The scheme reaches the library: label 5 is no FDI tooth but Universal tooth 5 (FDI 14),
  // added, and then too few teeth to fuse.
  vtkNew<vtkShortArray> shorts;
  image = image_of(shorts, 1, 5);
  m = run(image, &status, fdi);
  EXPECT_NE(m.find("toothfuse_session_add_label_volume (CBCT) failed"), std::string::npos) << m;
  m = run(image, &status, vtkToothfuseFilter::VOLUME_SCHEME_UNIVERSAL);
  EXPECT_NE(m.find("toothfuse_session_fuse failed (missing data"), std::string::npos) << m;
}

}  // namespace

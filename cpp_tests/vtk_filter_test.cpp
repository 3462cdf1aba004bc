// vtkToothfuseFilter (bindings/vtk) on two synthetic jaws of the demo_jaws fixture (partial
// arches: jaw_2 upper, jaw_7 lower), checked with VTK's own filters: per tooth (vtkThreshold on the
// output "label"), vtkFeatureEdges finds no boundary or non-manifold edge,
// vtkPolyDataConnectivityFilter one region, vtkMassProperties a positive volume; every source-0
// (IOS) point is an input IOS point of that tooth, bit for bit, and there are exactly as many
// as the tooth's crown has (IOS frame); every source-2 (CBCT) point is an input CBCT point of
// that tooth (CBCT frame). Error paths: a missing label array, a non-FDI label and too few
// teeth give one clean vtkError naming the cause (toothfuse's own message for library errors)
// and an empty output.
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
#include <vtkGeometryFilter.h>
#include <vtkIntArray.h>
#include <vtkMassProperties.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkShortArray.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkThreshold.h>
#include <vtkToothfuseFilter.h>

#include <array>
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
  vtkNew<vtkFeatureEdges> fe;  // the whole jaw: closed and manifold
  fe->SetInputData(out);
  fe->BoundaryEdgesOn();
  fe->NonManifoldEdgesOn();
  fe->FeatureEdgesOff();
  fe->ManifoldEdgesOff();
  fe->Update();
  EXPECT_EQ(fe->GetOutput()->GetNumberOfCells(), 0);
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
    vtkNew<vtkFeatureEdges> fe;
    fe->SetInputData(t);
    fe->BoundaryEdgesOn();
    fe->NonManifoldEdgesOn();
    fe->FeatureEdgesOff();
    fe->ManifoldEdgesOff();
    fe->Update();
    EXPECT_EQ(fe->GetOutput()->GetNumberOfCells(), 0) << "boundary or non-manifold edges";
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

}  // namespace

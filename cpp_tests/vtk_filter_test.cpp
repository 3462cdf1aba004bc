// vtkToothfuseFilter (bindings/vtk) on two synthetic jaws of the demo_jaws fixture (partial
// arches: jaw_2 upper, jaw_7 lower), checked with VTK's own filters: per tooth (vtkThreshold on the
// output "label"), vtkFeatureEdges finds no boundary or non-manifold edge,
// vtkPolyDataConnectivityFilter one region, vtkMassProperties a positive volume; every source-0
// (IOS) point is an input IOS point of that tooth, bit for bit, and there are exactly as many
// as the tooth's crown has (IOS frame); every source-2 (CBCT) point is an input CBCT point of
// that tooth (CBCT frame). Error paths: a missing label array, a non-FDI label, too few teeth,
// float or multi-component image scalars, a negative label in copied image scalars give one
// clean vtkError naming the cause (toothfuse's own message for library errors) and an empty
// output; the volume scheme reaches the library (label 5: refused as FDI, added as Universal).
// The CBCT as a label image: vtk_filter_image_test.cpp (the same test executable).
#include "vtk_filter_support.hpp"

namespace {

using namespace vtk_filter_support;

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

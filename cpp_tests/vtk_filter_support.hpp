// Helpers of the vtkToothfuseFilter tests (vtk_filter_test.cpp, vtk_filter_image_test.cpp):
// the demo_jaws fixture's jaws as VTK inputs, the filter run on them with its error messages
// collected, and the per-tooth checks with VTK's own filters.
#pragma once

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

namespace vtk_filter_support {


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

using tf::polydata;

struct Demo {
  tf::LabeledJaw ios, cbct;
  vtkSmartPointer<vtkPolyData> iosPd, cbctPd;
  std::set<int> both;      // labels in both modalities
  std::set<int> expected;  // fused teeth: `both` less the teeth the filter reports skipped
  bool ok = false;
};

/// Boundary and non-manifold edges of `mesh`, by VTK's vtkFeatureEdges (0: closed, manifold).
inline vtkIdType open_or_non_manifold_edges(vtkPolyData* mesh) {
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
inline Demo& demo(int k) {
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

inline vtkSmartPointer<vtkPolyData> tooth_of(vtkPolyData* jaw, int fdi) {
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
inline vtkSmartPointer<vtkPolyData> fuse_demo(Demo& d, int frame) {
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
inline std::map<int, std::vector<Key>> check_teeth(const Demo& d, vtkPolyData* out, int src) {
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

}  // namespace vtk_filter_support

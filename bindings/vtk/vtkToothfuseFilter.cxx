// vtkToothfuseFilter: converts the two VTK inputs to toothfuse C API buffers (the CBCT either
// as tooth meshes or as a label volume), runs toothfuse_session_fuse (register + cut + stitch)
// and converts the fused jaw back. Only the public C API of toothfuse.h is used.
#include "vtkToothfuseFilter.h"

#include "toothfuse.h"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkMatrix3x3.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>
#include <vtkType.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>

vtkStandardNewMacro(vtkToothfuseFilter);

namespace {

struct SessionFree {
  void operator()(toothfuse_session* s) const { toothfuse_session_free(s); }
};
using SessionPtr = std::unique_ptr<toothfuse_session, SessionFree>;

/// The session's progress callback: the filter's progress (a label image's surfacing 0-0.1,
/// registration 0.1-0.25, crown cut 0.25-0.35, stitching 0.35-1) through UpdateProgress, and its
/// AbortExecute flag as the cancel.
int32_t ReportProgress(void* filter, toothfuse_stage stage, size_t done, size_t total) {
  // Each stage spans [bound[k], bound[k + 1]] in the order surface, register, cut, stitch; a
  // stage's end is exactly the next one's start, so the reports never decrease.
  static const double bound[] = {0.0, 0.1, 0.25, 0.35, 1.0};
  size_t k = 0;  // surfacing, and any stage this build does not know
  if (stage == TOOTHFUSE_STAGE_REGISTER) k = 1;
  if (stage == TOOTHFUSE_STAGE_CUT) k = 2;
  if (stage == TOOTHFUSE_STAGE_STITCH) k = 3;
  const double a = bound[k], b = bound[k + 1];
  const double within = total > 0 ? double(done) / double(total) : 0.0;
  auto* f = static_cast<vtkToothfuseFilter*>(filter);
  try {
    f->UpdateProgress(std::min(b, a + (b - a) * within));
  } catch (...) {
    return 1;  // an observer threw: nothing may unwind through the library
  }
  return f->GetAbortExecute() ? 1 : 0;
}

/// One input as C API buffers. Vertices point into `mesh` (kept alive here) or `xyz`.
struct JawBuffers {
  vtkSmartPointer<vtkPolyData> mesh;
  std::vector<double> xyz;
  const void* vertices = nullptr;
  size_t vertexCount = 0;
  size_t stride = 0;
  toothfuse_scalar scalar = TOOTHFUSE_SCALAR_FLOAT64;
  std::vector<uint32_t> indices;
  std::vector<int32_t> labels;
  toothfuse_label_domain domain = TOOTHFUSE_LABEL_DOMAIN_VERTEX;
};

/// True when `pd` holds only triangle polygons (no verts, lines, strips or larger polygons).
bool OnlyTriangles(vtkPolyData* pd) {
  if (pd->GetNumberOfVerts() || pd->GetNumberOfLines() || pd->GetNumberOfStrips()) return false;
  vtkCellArray* polys = pd->GetPolys();
  return polys->IsHomogeneous() == 3 || polys->GetNumberOfCells() == 0;
}

/// Fills `out` from input `pd`; on failure returns false with the reason in `err`.
bool PrepareJaw(vtkPolyData* input, const char* arrayName, const char* what, JawBuffers& out,
                std::string& err) {
  std::ostringstream msg;
  if (!input || input->GetNumberOfPoints() == 0 || input->GetNumberOfPolys() +
                                                          input->GetNumberOfStrips() == 0) {
    msg << what << " input has no points or no polygons";
    err = msg.str();
    return false;
  }
  if (!arrayName || !*arrayName) {
    err = std::string(what) + " label array name is empty";
    return false;
  }
  // Polygons and strips become triangles (cell data follows); verts and lines are dropped.
  if (OnlyTriangles(input)) {
    out.mesh = input;
  } else {
    vtkNew<vtkTriangleFilter> tri;
    tri->SetInputData(input);
    tri->PassVertsOff();
    tri->PassLinesOff();
    tri->Update();
    out.mesh = tri->GetOutput();
  }
  vtkPolyData* pd = out.mesh;

  vtkDataArray* labels = pd->GetPointData()->GetArray(arrayName);
  out.domain = TOOTHFUSE_LABEL_DOMAIN_VERTEX;
  if (!labels) {
    labels = pd->GetCellData()->GetArray(arrayName);
    out.domain = TOOTHFUSE_LABEL_DOMAIN_FACE;
  }
  if (!labels) {
    msg << what << " input has no point or cell data array named \"" << arrayName
        << "\" (the FDI tooth labels; set the name with Set" << what << "LabelArrayName)";
    err = msg.str();
    return false;
  }
  if (labels->GetNumberOfComponents() != 1) {
    msg << what << " label array \"" << arrayName << "\" has " << labels->GetNumberOfComponents()
        << " components, expected 1";
    err = msg.str();
    return false;
  }
  const vtkIdType nLabels = labels->GetNumberOfTuples();
  out.labels.resize(static_cast<size_t>(nLabels));
  for (vtkIdType i = 0; i < nLabels; i++) {
    const double v = labels->GetComponent(i, 0);
    if (!(v == std::floor(v)) || v < std::numeric_limits<int32_t>::min() ||
        v > std::numeric_limits<int32_t>::max()) {
      msg << what << " label array \"" << arrayName << "\": value " << v << " at "
          << (out.domain == TOOTHFUSE_LABEL_DOMAIN_VERTEX ? "point " : "cell ") << i
          << " is not an integer tooth label";
      err = msg.str();
      return false;
    }
    out.labels[static_cast<size_t>(i)] = static_cast<int32_t>(v);
  }

  // Points: float or double arrays go to the library as they are; anything else as doubles.
  vtkDataArray* pts = pd->GetPoints()->GetData();
  out.vertexCount = static_cast<size_t>(pd->GetNumberOfPoints());
  if (vtkFloatArray* f = vtkArrayDownCast<vtkFloatArray>(pts)) {
    out.vertices = f->GetPointer(0);
    out.stride = 3 * sizeof(float);
    out.scalar = TOOTHFUSE_SCALAR_FLOAT32;
  } else if (vtkDoubleArray* d = vtkArrayDownCast<vtkDoubleArray>(pts)) {
    out.vertices = d->GetPointer(0);
    out.stride = 3 * sizeof(double);
    out.scalar = TOOTHFUSE_SCALAR_FLOAT64;
  } else {
    out.xyz.resize(3 * out.vertexCount);
    for (size_t i = 0; i < out.vertexCount; i++)
      pd->GetPoint(static_cast<vtkIdType>(i), &out.xyz[3 * i]);
    out.vertices = out.xyz.data();
    out.stride = 3 * sizeof(double);
    out.scalar = TOOTHFUSE_SCALAR_FLOAT64;
  }
  if (out.vertexCount > std::numeric_limits<uint32_t>::max()) {
    msg << what << " input has " << out.vertexCount << " points, more than 2^32 - 1";
    err = msg.str();
    return false;
  }

  vtkCellArray* polys = pd->GetPolys();
  out.indices.reserve(3 * static_cast<size_t>(polys->GetNumberOfCells()));
  auto it = vtk::TakeSmartPointer(polys->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    it->GetCurrentCell(n, ids);
    if (n != 3) {  // cannot happen after vtkTriangleFilter; kept as a guard
      msg << what << " input: cell " << it->GetCurrentCellId() << " has " << n << " points";
      err = msg.str();
      return false;
    }
    for (vtkIdType k = 0; k < 3; k++) out.indices.push_back(static_cast<uint32_t>(ids[k]));
  }
  return true;
}

/// A CBCT label image as the arguments of toothfuse_session_add_label_volume. Labels point into
/// the image's scalars (kept alive by the pipeline during RequestData) or into `copy`.
struct VolumeBuffers {
  size_t dims[3] = {0, 0, 0};
  double voxelToWorld[16] = {};
  const void* labels = nullptr;
  size_t count = 0;
  toothfuse_label_type type = TOOTHFUSE_LABEL_TYPE_INT32;
  std::vector<int32_t> copy;
};

/// Fills `out` from the label image `image` (world x and y negated when `flipLpsRas`: LPS <->
/// RAS); on failure returns false with the reason in `err`.
bool PrepareVolume(vtkImageData* image, bool flipLpsRas, VolumeBuffers& out, std::string& err) {
  std::ostringstream msg;
  int dims[3];
  image->GetDimensions(dims);
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (dims[0] < 1 || dims[1] < 1 || dims[2] < 1 || !scalars) {
    msg << "CBCT image has no voxels or no point scalars (the tooth labels)";
    err = msg.str();
    return false;
  }
  const char* name = scalars->GetName() ? scalars->GetName() : "(unnamed)";
  if (scalars->GetNumberOfComponents() != 1) {
    msg << "CBCT image scalars \"" << name << "\" have " << scalars->GetNumberOfComponents()
        << " components: a label volume has one integer label per voxel";
    err = msg.str();
    return false;
  }
  for (int a = 0; a < 3; a++) out.dims[a] = static_cast<size_t>(dims[a]);
  out.count = out.dims[0] * out.dims[1] * out.dims[2];
  if (static_cast<size_t>(scalars->GetNumberOfTuples()) != out.count) {
    msg << "CBCT image scalars \"" << name << "\" hold " << scalars->GetNumberOfTuples()
        << " values for " << out.count << " voxels";
    err = msg.str();
    return false;
  }
  // The four label types of the C API are passed as they are; other integers are copied.
  out.labels = scalars->GetVoidPointer(0);
  switch (scalars->GetDataType()) {
    case VTK_UNSIGNED_CHAR:
      out.type = TOOTHFUSE_LABEL_TYPE_UINT8;
      break;
    case VTK_UNSIGNED_SHORT:
      out.type = TOOTHFUSE_LABEL_TYPE_UINT16;
      break;
    case VTK_SHORT:
      out.type = TOOTHFUSE_LABEL_TYPE_INT16;
      break;
    case VTK_INT:
      out.type = TOOTHFUSE_LABEL_TYPE_INT32;
      break;
    case VTK_CHAR:
    case VTK_SIGNED_CHAR:
    case VTK_UNSIGNED_INT:
    case VTK_LONG:
    case VTK_UNSIGNED_LONG:
    case VTK_LONG_LONG:
    case VTK_UNSIGNED_LONG_LONG:
    case VTK_ID_TYPE:
      out.copy.resize(out.count);
      for (size_t i = 0; i < out.count; i++) {
        const double v = scalars->GetComponent(static_cast<vtkIdType>(i), 0);
        if (v < 0 || v > 65535) {
          msg << "CBCT image scalars \"" << name << "\": label " << v << " at voxel " << i
              << " is outside 0-65535";
          err = msg.str();
          return false;
        }
        out.copy[i] = static_cast<int32_t>(v);
      }
      out.labels = out.copy.data();
      out.type = TOOTHFUSE_LABEL_TYPE_INT32;
      break;
    default:
      msg << "CBCT image scalars \"" << name << "\" are of type "
          << scalars->GetDataTypeAsString()
          << ": a label volume holds integer labels (unsigned char, unsigned short, short or int;"
             " cast integer-valued float labels with vtkImageCast)";
      err = msg.str();
      return false;
  }
  // Voxel (i, j, k) of the buffer is structured index extent_min + (i, j, k); world =
  // origin + direction * diag(spacing) * index.
  const int* extent = image->GetExtent();
  const double* spacing = image->GetSpacing();
  const double* origin = image->GetOrigin();
  vtkMatrix3x3* direction = image->GetDirectionMatrix();
  for (int r = 0; r < 3; r++) {
    double t = origin[r];
    for (int c = 0; c < 3; c++) {
      const double a = direction->GetElement(r, c) * spacing[c];
      out.voxelToWorld[4 * r + c] = a;
      t += a * extent[2 * c];
    }
    out.voxelToWorld[4 * r + 3] = t;
  }
  // LPS <-> RAS: world x and y negated (rows 0 and 1 of the voxel-to-world matrix).
  if (flipLpsRas)
    for (int e = 0; e < 8; e++) out.voxelToWorld[e] = -out.voxelToWorld[e];
  out.voxelToWorld[15] = 1.0;
  return true;
}

}  // namespace

vtkToothfuseFilter::vtkToothfuseFilter() {
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(1);
  this->SetIOSLabelArrayName("label");
  this->SetCBCTLabelArrayName("label");
}

vtkToothfuseFilter::~vtkToothfuseFilter() {
  this->SetIOSLabelArrayName(nullptr);
  this->SetCBCTLabelArrayName(nullptr);
}

int vtkToothfuseFilter::FillInputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  if (port == 1) info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

std::string vtkToothfuseFilter::GetSkippedReason(int fdi) const {
  for (size_t i = 0; i < this->SkippedTeeth.size(); i++)
    if (this->SkippedTeeth[i] == fdi) return this->SkippedReasons[i];
  return std::string();
}

std::vector<std::string> vtkToothfuseFilter::GetToothWarnings(int fdi) const {
  auto it = this->ToothWarnings.find(fdi);
  return it == this->ToothWarnings.end() ? std::vector<std::string>() : it->second;
}

int vtkToothfuseFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                    vtkInformationVector* outputVector) {
  this->FusedTeeth.clear();
  this->SkippedTeeth.clear();
  this->SkippedReasons.clear();
  this->ToothWarnings.clear();
  this->ReportJSON.clear();
  this->LastStatus = 0;
  vtkPolyData* iosIn = vtkPolyData::GetData(inputVector[0], 0);
  vtkImageData* cbctImage = vtkImageData::GetData(inputVector[1], 0);
  vtkPolyData* cbctIn = cbctImage ? nullptr : vtkPolyData::GetData(inputVector[1], 0);
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  output->Initialize();

  JawBuffers ios, cbct;
  VolumeBuffers volume;
  std::string err;
  if (!PrepareJaw(iosIn, this->IOSLabelArrayName, "IOS", ios, err) ||
      (cbctImage ? !PrepareVolume(cbctImage, this->FlipImageLPSRAS, volume, err)
                 : !PrepareJaw(cbctIn, this->CBCTLabelArrayName, "CBCT", cbct, err))) {
    this->LastStatus = static_cast<int>(TOOTHFUSE_STATUS_INVALID_ARGUMENT);
    vtkErrorMacro(<< err);
    return 0;
  }

  toothfuse_session* raw = nullptr;
  toothfuse_status st = toothfuse_session_new(&raw);
  SessionPtr session(raw);  // freed on every return below
  if (st != TOOTHFUSE_STATUS_OK) {
    vtkErrorMacro(<< "toothfuse_session_new failed: " << toothfuse_status_string(st));
    return 0;
  }
  toothfuse_session* s = session.get();
  auto failed = [&](const char* call) {
    this->LastStatus = static_cast<int>(st);
    vtkErrorMacro(<< call << " failed (" << toothfuse_status_string(st)
                  << "): " << toothfuse_session_last_error(s));
    return 0;
  };

  st = toothfuse_session_set_max_threads(s, static_cast<uint32_t>(this->MaxThreads));
  if (st != TOOTHFUSE_STATUS_OK) return failed("toothfuse_session_set_max_threads");
  // Aborted (SetAbortExecute): an empty output, no error, the status kept.
  auto cancelled = [&]() {
    this->LastStatus = static_cast<int>(st);
    vtkDebugMacro(<< "fusion cancelled: " << toothfuse_session_last_error(s));
    return 1;
  };
  st = toothfuse_session_set_progress(s, ReportProgress, this);
  if (st != TOOTHFUSE_STATUS_OK) return failed("toothfuse_session_set_progress");
  if (this->IOSRepair) {
    st = toothfuse_session_set_ios_repair(s, true, this->MaxHoleFraction);
    if (st != TOOTHFUSE_STATUS_OK) return failed("toothfuse_session_set_ios_repair");
  }
  // The IOS first: a per-jaw label volume is split by the IOS crowns the session holds.
  auto addJaw = [&](toothfuse_modality modality, const JawBuffers& jaw) {
    return toothfuse_session_add_jaw(s, modality, jaw.vertices, jaw.vertexCount, jaw.stride,
                                     jaw.scalar, jaw.indices.data(), jaw.indices.size(),
                                     jaw.labels.data(), jaw.labels.size(), jaw.domain);
  };
  if ((st = addJaw(TOOTHFUSE_MODALITY_IOS, ios)) != TOOTHFUSE_STATUS_OK)
    return failed("toothfuse_session_add_jaw (IOS)");
  if (!cbctImage) {
    if ((st = addJaw(TOOTHFUSE_MODALITY_CBCT, cbct)) != TOOTHFUSE_STATUS_OK)
      return failed("toothfuse_session_add_jaw (CBCT)");
  } else {
    st = toothfuse_session_add_label_volume(
        s, volume.dims, volume.voxelToWorld, nullptr, nullptr, volume.labels, volume.count,
        volume.type, static_cast<toothfuse_volume_scheme>(this->VolumeScheme), nullptr);
    if (st == TOOTHFUSE_STATUS_CANCELLED) return cancelled();
    if (st != TOOTHFUSE_STATUS_OK) return failed("toothfuse_session_add_label_volume (CBCT)");
  }

  toothfuse_options options;
  if ((st = toothfuse_options_default(&options)) != TOOTHFUSE_STATUS_OK)
    return failed("toothfuse_options_default");
  options.preset = static_cast<toothfuse_preset>(this->Preset);
  options.frame = static_cast<toothfuse_frame>(this->Frame);
  options.accept_questionable = this->AcceptQuestionable ? 1u : 0u;
  st = toothfuse_session_fuse(s, &options);
  if (st == TOOTHFUSE_STATUS_CANCELLED) return cancelled();
  if (st != TOOTHFUSE_STATUS_OK) return failed("toothfuse_session_fuse");

  // Results: fused and skipped teeth, report JSON.
  int32_t fdi[52];
  size_t count = 0;
  if ((st = toothfuse_session_fused_teeth(s, fdi, 52, &count)) != TOOTHFUSE_STATUS_OK)
    return failed("toothfuse_session_fused_teeth");
  this->FusedTeeth.assign(fdi, fdi + count);
  for (int f : this->FusedTeeth) {
    toothfuse_tooth_report report;
    if ((st = toothfuse_session_tooth_report(s, f, &report)) != TOOTHFUSE_STATUS_OK)
      return failed("toothfuse_session_tooth_report");
    std::vector<std::string>& warnings = this->ToothWarnings[f];
    for (size_t i = 0; i < report.warning_count; i++) {
      const char* w = nullptr;
      if ((st = toothfuse_session_tooth_warning(s, f, i, &w)) != TOOTHFUSE_STATUS_OK)
        return failed("toothfuse_session_tooth_warning");
      warnings.emplace_back(w ? w : "");
    }
  }
  size_t skipped = 0;
  if ((st = toothfuse_session_skipped_count(s, &skipped)) != TOOTHFUSE_STATUS_OK)
    return failed("toothfuse_session_skipped_count");
  for (size_t i = 0; i < skipped; i++) {
    int32_t f = 0;
    const char* reason = nullptr;
    if ((st = toothfuse_session_skipped(s, i, &f, &reason)) != TOOTHFUSE_STATUS_OK)
      return failed("toothfuse_session_skipped");
    this->SkippedTeeth.push_back(f);
    this->SkippedReasons.emplace_back(reason ? reason : "");
  }
  size_t len = 0;
  if ((st = toothfuse_session_report_json(s, nullptr, 0, &len)) != TOOTHFUSE_STATUS_OK)
    return failed("toothfuse_session_report_json");
  std::vector<char> json(len + 1);
  if ((st = toothfuse_session_report_json(s, json.data(), json.size(), &len)) !=
      TOOTHFUSE_STATUS_OK)
    return failed("toothfuse_session_report_json");
  this->ReportJSON.assign(json.data(), len);

  vtkNew<vtkIntArray> skippedArray;
  skippedArray->SetName("skipped_fdi");
  for (int f : this->SkippedTeeth) skippedArray->InsertNextValue(f);
  vtkNew<vtkStringArray> reportArray;
  reportArray->SetName("toothfuse_report");
  reportArray->InsertNextValue(this->ReportJSON);
  output->GetFieldData()->AddArray(skippedArray);
  output->GetFieldData()->AddArray(reportArray);
  for (size_t i = 0; i < this->SkippedTeeth.size(); i++)
    vtkWarningMacro(<< "tooth " << this->SkippedTeeth[i]
                    << " not fused: " << this->SkippedReasons[i]);
  if (this->FusedTeeth.empty()) {
    vtkWarningMacro(<< "no tooth was fused; the output is empty");
    return 1;
  }

  // The whole fused jaw (fdi 0), copied out of the session before it is freed.
  toothfuse_fused_view view;
  if ((st = toothfuse_session_fused_view(s, 0, &view)) != TOOTHFUSE_STATUS_OK)
    return failed("toothfuse_session_fused_view");
  const vtkIdType nv = static_cast<vtkIdType>(view.vertex_count);
  const vtkIdType ni = static_cast<vtkIdType>(view.index_count);
  vtkNew<vtkDoubleArray> xyz;
  xyz->SetNumberOfComponents(3);
  xyz->SetNumberOfTuples(nv);
  std::memcpy(xyz->GetPointer(0), view.positions, 3 * view.vertex_count * sizeof(double));
  vtkNew<vtkPoints> points;
  points->SetData(xyz);
  vtkNew<vtkIdTypeArray> conn;
  conn->SetNumberOfTuples(ni);
  for (vtkIdType i = 0; i < ni; i++) conn->SetValue(i, static_cast<vtkIdType>(view.indices[i]));
  vtkNew<vtkCellArray> polys;
  polys->SetData(3, conn);
  vtkNew<vtkIntArray> label;
  label->SetName("label");
  label->SetNumberOfTuples(nv);
  vtkNew<vtkUnsignedCharArray> source;
  source->SetName("source");
  source->SetNumberOfTuples(nv);
  for (vtkIdType i = 0; i < nv; i++) {
    label->SetValue(i, view.labels ? view.labels[i] : 0);
    source->SetValue(i, view.source[i]);
  }
  output->SetPoints(points);
  output->SetPolys(polys);
  output->GetPointData()->AddArray(label);
  output->GetPointData()->AddArray(source);
  output->GetPointData()->SetActiveScalars("label");
  return 1;
}

void vtkToothfuseFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "IOSLabelArrayName: "
     << (this->IOSLabelArrayName ? this->IOSLabelArrayName : "(none)") << "\n";
  os << indent << "CBCTLabelArrayName: "
     << (this->CBCTLabelArrayName ? this->CBCTLabelArrayName : "(none)") << "\n";
  os << indent << "Preset: " << (this->Preset == PRESET_PAPER ? "paper" : "default") << "\n";
  os << indent << "Frame: " << (this->Frame == FRAME_IOS ? "IOS" : "CBCT") << "\n";
  static const char* const schemes[] = {"FDI", "Universal", "ToothFairy2", "DentalSegmentator"};
  os << indent << "VolumeScheme: " << schemes[this->VolumeScheme] << "\n";
  os << indent << "FlipImageLPSRAS: " << this->FlipImageLPSRAS << "\n";
  os << indent << "IOSRepair: " << this->IOSRepair << " (MaxHoleFraction "
     << this->MaxHoleFraction << ")\n";
  os << indent << "AcceptQuestionable: " << this->AcceptQuestionable << "\n";
  os << indent << "MaxThreads: " << this->MaxThreads << "\n";
  os << indent << "LastStatus: " << this->LastStatus << "\n";
  os << indent << "FusedTeeth: " << this->FusedTeeth.size()
     << ", SkippedTeeth: " << this->SkippedTeeth.size() << "\n";
}

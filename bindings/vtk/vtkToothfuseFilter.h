// vtkToothfuseFilter: the toothfuse one-call fuse as a VTK pipeline filter, built only on the
// public C API (toothfuse.h).
//
//   vtkNew<vtkToothfuseFilter> fuse;
//   fuse->SetIOSInputConnection(iosReader->GetOutputPort());    // input port 0
//   fuse->SetCBCTInputConnection(cbctReader->GetOutputPort());  // input port 1
//   fuse->SetFrameToIOS();                                      // default: CBCT frame
//   fuse->Update();
//   vtkPolyData* jaw = fuse->GetOutput();  // point arrays "label" (FDI), "source" (0/1/2)
//
// Input port 0: the intraoral scan (IOS) jaw, input port 1: the CBCT teeth. Each is a polydata
// of polygons (triangles; other polygons and strips are triangulated) with an integer FDI tooth
// label per point or per cell (0 = gingiva / background, dropped): the array named by
// IOSLabelArrayName / CBCTLabelArrayName (default "label"), looked up in the point data first,
// then in the cell data. Coordinates in millimetres; float or double points are passed to the
// library without conversion.
//
// Output port 0: the fused jaw, one closed, manifold mesh per fused tooth (IOS crown + band +
// CBCT root), double points in the chosen frame, triangles, point arrays "label" (int, FDI) and
// "source" (unsigned char: 0 IOS crown, 1 band, 2 CBCT root), and field data "skipped_fdi"
// (int: teeth not fused, see GetSkippedReason) and "toothfuse_report" (string: the report JSON).
//
// Errors of the library (bad label, non-manifold tooth, too few teeth, ...) are reported with
// vtkErrorMacro carrying toothfuse's detailed message, and the request fails with an empty
// output. The toothfuse session lives only during RequestData and is always freed.
#ifndef vtkToothfuseFilter_h
#define vtkToothfuseFilter_h

#include <vtkPolyDataAlgorithm.h>

#include <string>
#include <vector>

class vtkToothfuseFilter : public vtkPolyDataAlgorithm {
 public:
  static vtkToothfuseFilter* New();
  vtkTypeMacro(vtkToothfuseFilter, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Preset values (same numbers as TOOTHFUSE_PRESET_* in toothfuse.h).
  enum Preset { PRESET_PAPER = 0, PRESET_DEFAULT = 1 };
  /// Output frame values (same numbers as TOOTHFUSE_FRAME_* in toothfuse.h).
  enum Frame { FRAME_CBCT = 0, FRAME_IOS = 1 };

  /// The IOS jaw (input port 0) and the CBCT teeth (input port 1).
  void SetIOSInputConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(0, output); }
  void SetCBCTInputConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetIOSInputData(vtkDataObject* input) { this->SetInputData(0, input); }
  void SetCBCTInputData(vtkDataObject* input) { this->SetInputData(1, input); }

  /// Name of the integer FDI label array of each input (point data, else cell data).
  vtkSetStringMacro(IOSLabelArrayName);
  vtkGetStringMacro(IOSLabelArrayName);
  vtkSetStringMacro(CBCTLabelArrayName);
  vtkGetStringMacro(CBCTLabelArrayName);

  /// Registration/fusion preset: PRESET_DEFAULT (default, measured better) or PRESET_PAPER.
  vtkSetClampMacro(Preset, int, PRESET_PAPER, PRESET_DEFAULT);
  vtkGetMacro(Preset, int);
  void SetPresetToDefault() { this->SetPreset(PRESET_DEFAULT); }
  void SetPresetToPaper() { this->SetPreset(PRESET_PAPER); }

  /// Frame of the output: FRAME_CBCT (default; overlays the CBCT volume) or FRAME_IOS.
  vtkSetClampMacro(Frame, int, FRAME_CBCT, FRAME_IOS);
  vtkGetMacro(Frame, int);
  void SetFrameToCBCT() { this->SetFrame(FRAME_CBCT); }
  void SetFrameToIOS() { this->SetFrame(FRAME_IOS); }

  /// Repair IOS crowns on entry (real scans need it; off by default) and the largest hole, as
  /// a fraction (0..1) of the margin's perimeter, that repair fills.
  vtkSetMacro(IOSRepair, bool);
  vtkGetMacro(IOSRepair, bool);
  vtkBooleanMacro(IOSRepair, bool);
  vtkSetClampMacro(MaxHoleFraction, double, 0.0, 1.0);
  vtkGetMacro(MaxHoleFraction, double);

  /// Fuse even when toothfuse's registration gate finds the data questionable (mirrored,
  /// another patient, shifted or misnumbered labels; off by default: such data fail the request
  /// with TOOTHFUSE_STATUS_MIRRORED or TOOTHFUSE_STATUS_REGISTRATION_REJECTED, misnumbered teeth
  /// are skipped). The findings are then in the report JSON under "questionable_findings".
  vtkSetMacro(AcceptQuestionable, bool);
  vtkGetMacro(AcceptQuestionable, bool);
  vtkBooleanMacro(AcceptQuestionable, bool);

  /// The toothfuse status of the last update (TOOTHFUSE_STATUS_OK = 0 after a success; e.g.
  /// TOOTHFUSE_STATUS_UNIT_MISMATCH for input not in millimetres).
  int GetLastStatus() const { return this->LastStatus; }

  /// After an update: the FDI numbers fused, the teeth skipped (with reasons) and the report
  /// JSON of the last successful run (empty after a failed one).
  const std::vector<int>& GetFusedTeeth() const { return this->FusedTeeth; }
  const std::vector<int>& GetSkippedTeeth() const { return this->SkippedTeeth; }
  std::string GetSkippedReason(int fdi) const;
  const std::string& GetReportJSON() const { return this->ReportJSON; }

 protected:
  vtkToothfuseFilter();
  ~vtkToothfuseFilter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  char* IOSLabelArrayName = nullptr;
  char* CBCTLabelArrayName = nullptr;
  int Preset = PRESET_DEFAULT;
  int Frame = FRAME_CBCT;
  bool IOSRepair = false;
  double MaxHoleFraction = 0.5;
  bool AcceptQuestionable = false;
  int LastStatus = 0;

  std::vector<int> FusedTeeth;
  std::vector<int> SkippedTeeth;
  std::vector<std::string> SkippedReasons;
  std::string ReportJSON;

 private:
  vtkToothfuseFilter(const vtkToothfuseFilter&) = delete;
  void operator=(const vtkToothfuseFilter&) = delete;
};

#endif

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
// Input port 0: the intraoral scan (IOS) jaw, a polydata of polygons (triangles; other polygons
// and strips are triangulated) with an integer FDI tooth label per point or per cell (0 =
// gingiva / background, dropped): the array named by IOSLabelArrayName (default "label"), looked
// up in the point data first, then in the cell data. Coordinates in millimetres; float or double
// points are passed to the library without conversion.
//
// Input port 1: the CBCT teeth, either
//  - a polydata like the IOS one (closed teeth; array named by CBCTLabelArrayName), or
//  - a vtkImageData label volume (a CBCT tooth segmentation): its active point scalars, one
//    component of an integer type (unsigned char, unsigned short, short and int are passed
//    without a copy; other integer types are copied as int; float and double are refused),
//    numbered as VolumeScheme says (FDI by default, Universal, ToothFairy2, or DentalSegmentator's
//    one teeth class per jaw, split into teeth by the IOS crowns). Its extent, spacing
//    (millimetres), origin and direction matrix place the voxels in the world frame, which is
//    the CBCT frame, used as it is; when the image's world is LPS and the meshes' RAS (or the
//    reverse), FlipImageLPSRAS negates its x and y first, so that the CBCT frame is the meshes'.
//    Each tooth label is surfaced by toothfuse (closed meshes at the mask's 0.5 level).
//
// Output port 0: the fused jaw, one closed, manifold mesh per fused tooth (IOS crown + band +
// CBCT root), double points in the chosen frame, triangles, point arrays "label" (int, FDI) and
// "source" (unsigned char: 0 IOS crown, 1 band, 2 CBCT root), and field data "skipped_fdi"
// (int: teeth not fused, see GetSkippedReason) and "toothfuse_report" (string: the report JSON).
//
// Errors of the library (bad label, non-manifold tooth, too few teeth, ...) and inputs the
// filter cannot pass (missing label array, float or multi-component image scalars, ...) are
// reported with one vtkErrorMacro carrying the detailed message (toothfuse's own for library
// errors), GetLastStatus() gives the status, and the request fails with an empty output. The
// toothfuse session lives only during RequestData and is always freed.
#ifndef vtkToothfuseFilter_h
#define vtkToothfuseFilter_h

#include <vtkPolyDataAlgorithm.h>

#include <map>
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
  /// Label volume numbering (same numbers as TOOTHFUSE_VOLUME_SCHEME_* in toothfuse.h).
  enum VolumeScheme {
    VOLUME_SCHEME_FDI = 0,
    VOLUME_SCHEME_UNIVERSAL = 1,
    VOLUME_SCHEME_TOOTHFAIRY2 = 2,
    VOLUME_SCHEME_DENTALSEGMENTATOR = 3
  };

  /// The IOS jaw (input port 0) and the CBCT teeth (input port 1: polydata or label image).
  void SetIOSInputConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(0, output); }
  void SetCBCTInputConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetIOSInputData(vtkDataObject* input) { this->SetInputData(0, input); }
  void SetCBCTInputData(vtkDataObject* input) { this->SetInputData(1, input); }

  /// Name of the integer FDI label array of each polydata input (point data, else cell data).
  vtkSetStringMacro(IOSLabelArrayName);
  vtkGetStringMacro(IOSLabelArrayName);
  vtkSetStringMacro(CBCTLabelArrayName);
  vtkGetStringMacro(CBCTLabelArrayName);

  /// Numbering of a CBCT label image's values (unused for a polydata CBCT input):
  /// VOLUME_SCHEME_FDI (default; one label per tooth, STS 2024 and most models), _UNIVERSAL
  /// (1-32), _TOOTHFAIRY2 (teeth at FDI numbers, other structures skipped) or
  /// _DENTALSEGMENTATOR (3 upper teeth, 4 lower teeth: each jaw's mask is split into teeth by
  /// the registered IOS crowns; teeth whose split cannot be trusted are skipped with a reason).
  vtkSetClampMacro(VolumeScheme, int, VOLUME_SCHEME_FDI, VOLUME_SCHEME_DENTALSEGMENTATOR);
  vtkGetMacro(VolumeScheme, int);
  void SetVolumeSchemeToFDI() { this->SetVolumeScheme(VOLUME_SCHEME_FDI); }
  void SetVolumeSchemeToUniversal() { this->SetVolumeScheme(VOLUME_SCHEME_UNIVERSAL); }
  void SetVolumeSchemeToToothFairy2() { this->SetVolumeScheme(VOLUME_SCHEME_TOOTHFAIRY2); }
  void SetVolumeSchemeToDentalSegmentator() {
    this->SetVolumeScheme(VOLUME_SCHEME_DENTALSEGMENTATOR);
  }

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

  /// For an image CBCT input whose world coordinates are LPS while the meshes (IOS, the CBCT
  /// frame the output overlays) are RAS, or the reverse: negate the image's world x and y (off
  /// by default: the image's world frame is the CBCT frame as it is).
  vtkSetMacro(FlipImageLPSRAS, bool);
  vtkGetMacro(FlipImageLPSRAS, bool);
  vtkBooleanMacro(FlipImageLPSRAS, bool);

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

  /// Most threads an update uses in all, the calling thread's included (0, the default: as many
  /// as the CPUs allow, at most 4 per step; 1: everything on the calling thread, none spawned).
  /// The output is the same bit for bit whatever the value.
  vtkSetClampMacro(MaxThreads, int, 0, 1 << 20);
  vtkGetMacro(MaxThreads, int);

  /// Progress and abort: an update reports the fusion's progress as ProgressEvent (a label
  /// image's surfacing 0-0.1, the registration 0.1-0.25, the crown cut 0.25-0.35, the stitching
  /// 0.35-1; on the updating thread, between teeth and band builds), and SetAbortExecute(1),
  /// from a ProgressEvent observer or
  /// another thread, cancels it within about one band build: the output is then empty, no error
  /// is raised and GetLastStatus() is TOOTHFUSE_STATUS_CANCELLED. The output does not depend on
  /// the observers.
  ///
  /// The toothfuse status of the last update (TOOTHFUSE_STATUS_OK = 0 after a success; e.g.
  /// TOOTHFUSE_STATUS_UNIT_MISMATCH for input not in millimetres).
  int GetLastStatus() const { return this->LastStatus; }

  /// After an update: the FDI numbers fused, the teeth skipped (with reasons), the warnings of a
  /// fused tooth (registration and fusion; for a tooth split from a per-jaw label image, the
  /// share of its voxels whose assignment was contested) and the report JSON of the last
  /// successful run (empty after a failed one).
  const std::vector<int>& GetFusedTeeth() const { return this->FusedTeeth; }
  const std::vector<int>& GetSkippedTeeth() const { return this->SkippedTeeth; }
  std::string GetSkippedReason(int fdi) const;
  std::vector<std::string> GetToothWarnings(int fdi) const;
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
  int VolumeScheme = VOLUME_SCHEME_FDI;
  bool FlipImageLPSRAS = false;
  bool IOSRepair = false;
  double MaxHoleFraction = 0.5;
  bool AcceptQuestionable = false;
  int MaxThreads = 0;
  int LastStatus = 0;

  std::vector<int> FusedTeeth;
  std::vector<int> SkippedTeeth;
  std::vector<std::string> SkippedReasons;
  std::map<int, std::vector<std::string>> ToothWarnings;
  std::string ReportJSON;

 private:
  vtkToothfuseFilter(const vtkToothfuseFilter&) = delete;
  void operator=(const vtkToothfuseFilter&) = delete;
};

#endif

// Independent checkers of the one-call fuse on the synthetic jaws of the demo_jaws fixture
// (TOOTHFUSE_JAWS_DIR/jaw_<k>, every variant, both jaws): every fused tooth must be closed and
// manifold for VTK (vtkFeatureEdges: 0 boundary and 0 non-manifold edges; vtkMassProperties
// volume > 0) and for OpenMesh (every face accepted by add_face, no boundary halfedge, no
// non-manifold vertex, one component), and every IOS crown vertex must be in the fused tooth
// (source IOS) at its position mapped by the tooth's IOS->output transform. The two-stage path
// (register -> cut -> stitch) gives the one-call fuse's meshes exactly, and each cut root is an
// open surface whose one boundary loop is the reported cut loop, for VTK and OpenMesh.
#include "register_fuse_support.hpp"

#include <vtkCellArray.h>
#include <vtkFeatureEdges.h>
#include <vtkMassProperties.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace {

struct Fused {
  std::vector<double> xyz;
  std::vector<uint32_t> tris;
  std::vector<uint8_t> source;
};

Fused fused(tf::Session& s, int32_t fdi) {
  Fused f;
  size_t nv = 0, ni = 0;
  EXPECT_EQ(toothfuse_session_fused_size(s.get(), fdi, &nv, &ni), TOOTHFUSE_STATUS_OK);
  f.xyz.resize(3 * nv);
  f.tris.resize(ni);
  f.source.resize(nv);
  EXPECT_EQ(toothfuse_session_copy_fused_vertices(s.get(), fdi, f.xyz.data(), nv,
                                                  3 * sizeof(double), TOOTHFUSE_SCALAR_FLOAT64),
            TOOTHFUSE_STATUS_OK);
  EXPECT_EQ(toothfuse_session_copy_fused_indices(s.get(), fdi, f.tris.data(), ni),
            TOOTHFUSE_STATUS_OK);
  EXPECT_EQ(toothfuse_session_copy_fused_sources(s.get(), fdi, f.source.data(), nv),
            TOOTHFUSE_STATUS_OK);
  return f;
}

using tf::polydata;

// vtkFeatureEdges: the number of boundary (or non-manifold) edges of a surface.
vtkIdType feature_edges(vtkPolyData* pd, bool boundary) {
  vtkNew<vtkFeatureEdges> fe;
  fe->SetInputData(pd);
  fe->SetBoundaryEdges(boundary);
  fe->SetNonManifoldEdges(!boundary);
  fe->FeatureEdgesOff();
  fe->ManifoldEdgesOff();
  fe->Update();
  return fe->GetOutput()->GetNumberOfCells();
}

// VTK: 0 boundary and 0 non-manifold edges, positive volume.
std::string vtk_check(const Fused& f) {
  auto pd = polydata(f.xyz, f.tris);
  vtkIdType bad = feature_edges(pd, true) + feature_edges(pd, false);
  vtkNew<vtkMassProperties> mp;
  mp->SetInputData(pd);
  mp->Update();
  double vol = mp->GetVolume();
  std::string err;
  if (bad != 0) err += "VTK: " + std::to_string(bad) + " boundary/non-manifold edges; ";
  if (!(vol > 0.0)) err += "VTK: volume " + std::to_string(vol) + "; ";
  return err;
}

// OpenMesh: every face accepted, no boundary halfedge, no non-manifold vertex, one component.
std::string openmesh_check(const Fused& f) {
  tf::MeshD m;
  std::vector<tf::MeshD::VertexHandle> vh;
  for (size_t i = 0; i < f.xyz.size() / 3; i++)
    vh.push_back(m.add_vertex(tf::MeshD::Point(f.xyz[3 * i], f.xyz[3 * i + 1], f.xyz[3 * i + 2])));
  std::string err;
  size_t rejected = 0;
  for (size_t t = 0; t < f.tris.size() / 3; t++)
    if (!m.add_face(vh[f.tris[3 * t]], vh[f.tris[3 * t + 1]], vh[f.tris[3 * t + 2]]).is_valid())
      rejected++;
  if (rejected) err += "OpenMesh: " + std::to_string(rejected) + " faces rejected; ";
  size_t boundary = 0, nonmanifold = 0;
  for (auto h : m.halfedges())
    if (m.is_boundary(h)) boundary++;
  for (auto v : m.vertices())
    if (!m.is_manifold(v)) nonmanifold++;
  if (boundary) err += "OpenMesh: " + std::to_string(boundary) + " boundary halfedges; ";
  if (nonmanifold) err += "OpenMesh: " + std::to_string(nonmanifold) + " non-manifold vertices; ";
  // Components by a flood fill over face neighbours.
  std::vector<int> comp(m.n_faces(), -1);
  int ncomp = 0;
  for (auto f0 : m.faces()) {
    if (comp[f0.idx()] >= 0) continue;
    std::vector<tf::MeshD::FaceHandle> stack{f0};
    comp[f0.idx()] = ncomp;
    while (!stack.empty()) {
      auto fh = stack.back();
      stack.pop_back();
      for (auto g : m.ff_range(fh))
        if (comp[g.idx()] < 0) {
          comp[g.idx()] = ncomp;
          stack.push_back(g);
        }
    }
    ncomp++;
  }
  if (ncomp != 1) err += "OpenMesh: " + std::to_string(ncomp) + " components; ";
  return err;
}

// What the crown check allows: the share of a crown's vertices trimmed from its margin fringe,
// and the crossing pairs the fusion added (with a band face or a face added to the crown) that
// the library reports left.
struct CrownLimits {
  double maxTrimShare;
  size_t maxBandCrossings;
  bool dropsAllowed;  // stray tooth-labelled islands the crown repair gives back to the gingiva
  double maxTrimReach;  // mm from the margin (the default fringe reaches 0.3 mm)
};
// The contract on the clean phantom: at most 0.5 % trimmed within 0.3 mm of the margin, no
// crossing added, nothing dropped.
constexpr CrownLimits kClean{0.005, 0, false, 0.3};

// Every IOS crown vertex of the session, mapped by IOS->output, is a source-IOS vertex (to
// 1e-9 mm: the library applies the same transform in Rust), except the ones the library reports
// trimmed from the margin fringe (all within 0.3 mm of the margin); the trims and the band's
// crossings the library reports stay within `lim`.
std::string crown_check(tf::Session& s, int32_t fdi, const Fused& f,
                        const CrownLimits& lim = kClean) {
  tf::Mat4 m{};
  if (toothfuse_session_transform(s.get(), fdi, TOOTHFUSE_TRANSFORM_IOS_TO_OUTPUT, m.data()) !=
      TOOTHFUSE_STATUS_OK)
    return "no transform; ";
  std::vector<std::array<double, 3>> kept;
  for (size_t i = 0; i < f.source.size(); i++)
    if (f.source[i] == TOOTHFUSE_SOURCE_IOS)
      kept.push_back({f.xyz[3 * i], f.xyz[3 * i + 1], f.xyz[3 * i + 2]});
  std::sort(kept.begin(), kept.end());
  std::vector<double> crown = s.positions(TOOTHFUSE_MODALITY_IOS, fdi);
  size_t missing = 0;
  for (size_t i = 0; i < crown.size() / 3; i++) {
    auto q = tf::apply(m, &crown[3 * i]);
    auto lo = std::lower_bound(kept.begin(), kept.end(),
                               std::array<double, 3>{q[0] - 1e-9, -1e300, -1e300});
    bool found = false;
    for (auto it = lo; it != kept.end() && (*it)[0] <= q[0] + 1e-9 && !found; ++it)
      found = std::abs((*it)[1] - q[1]) <= 1e-9 && std::abs((*it)[2] - q[2]) <= 1e-9;
    if (!found) missing++;
  }
  // The only crown vertices that may be missing are the ones trimmed from the folded margin
  // fringe, counted by the library and all within the fringe reach of the margin.
  size_t trimmed = 0;
  double reach = 0;
  if (toothfuse_session_fused_trim(s.get(), fdi, &trimmed, &reach) != TOOTHFUSE_STATUS_OK)
    return "no trim report; ";
  size_t dropped = 0;
  if (toothfuse_session_fused_dropped(s.get(), fdi, &dropped) != TOOTHFUSE_STATUS_OK)
    return "no dropped-vertex report; ";
  if (dropped > 0 && !lim.dropsAllowed)
    return std::to_string(dropped) + " IOS crown vertices dropped by the repair; ";
  if (missing != trimmed + dropped)
    return std::to_string(missing) + " IOS crown vertices missing, " + std::to_string(trimmed) +
           " reported trimmed, " + std::to_string(dropped) + " dropped; ";
  if (reach > lim.maxTrimReach ||
      static_cast<double>(trimmed) > lim.maxTrimShare * (crown.size() / 3))
    return "trimmed " + std::to_string(trimmed) + " of " + std::to_string(crown.size() / 3) +
           " vertices up to " + std::to_string(reach) + " mm from the margin; ";
  // No crossing added by the fusion (the contract on clean crowns), as the library counts it.
  size_t band = 0, own = 0;
  if (toothfuse_session_fused_crossings(s.get(), fdi, &band, &own) != TOOTHFUSE_STATUS_OK)
    return "no crossing report; ";
  if (band > lim.maxBandCrossings)
    return std::to_string(band) + " crossing pairs added (with a band face or a hole's cap); ";
  return "";
}

// Loads the demo jaw in `jd` into `s` and fuses it in one call; `fdis` receives the fused teeth
// and `skipped` each tooth not fused with the reason.
void fuse_demo_jaw(tf::Session& s, const std::string& jd, std::vector<int32_t>& fdis,
                   std::vector<std::pair<int32_t, std::string>>& skipped) {
  ASSERT_TRUE(tf::load_demo(s, jd, false)) << jd;
  ASSERT_EQ(toothfuse_session_fuse(s.get(), nullptr), TOOTHFUSE_STATUS_OK)
      << jd << ": " << s.error();
  fdis.assign(52, 0);
  size_t n = 0;
  ASSERT_EQ(toothfuse_session_fused_teeth(s.get(), fdis.data(), fdis.size(), &n),
            TOOTHFUSE_STATUS_OK);
  fdis.resize(n);
  size_t nskip = 0;
  ASSERT_EQ(toothfuse_session_skipped_count(s.get(), &nskip), TOOTHFUSE_STATUS_OK);
  skipped.clear();
  for (size_t i = 0; i < nskip; i++) {
    int32_t f = 0;
    const char* why = nullptr;
    ASSERT_EQ(toothfuse_session_skipped(s.get(), i, &f, &why), TOOTHFUSE_STATUS_OK);
    skipped.emplace_back(f, why);
  }
}

// The demo jaw directories `$env/jaw_0`, `jaw_1`, ... that hold an ios.ply, in order; none (and
// a test failure) when the fixture did not set `env`.
std::vector<std::string> demo_jaw_dirs(const char* env, const char* fixture) {
  std::vector<std::string> out;
  const char* dir = std::getenv(env);
  if (dir == nullptr) {
    ADD_FAILURE() << env << " unset (the " << fixture << " fixture sets it)";
    return out;
  }
  for (int k = 0;; k++) {
    std::string jd = std::string(dir) + "/jaw_" + std::to_string(k);
    if (!std::ifstream(jd + "/ios.ply").good()) break;
    out.push_back(jd);
  }
  return out;
}

TEST(FuseCheckers, EveryToothOfTwentySyntheticJawsIsClosedAndManifold) {
  size_t jaws = 0, teeth = 0, skipped = 0, failed = 0;
  for (const std::string& jd : demo_jaw_dirs("TOOTHFUSE_JAWS_DIR", "demo_jaws")) {
    tf::Session s;
    std::vector<int32_t> fdis;
    std::vector<std::pair<int32_t, std::string>> notFused;
    fuse_demo_jaw(s, jd, fdis, notFused);
    if (HasFatalFailure()) return;
    jaws++;
    for (const auto& [f, why] : notFused) {
      std::printf("%s: tooth %d skipped: %s\n", jd.c_str(), f, why.c_str());
      if (why.rfind("fusion failed", 0) == 0) {
        failed++;
        // A failed tooth is reported, not delivered; the others are.
        EXPECT_EQ(std::count(fdis.begin(), fdis.end(), f), 0) << jd << ": tooth " << f;
      } else {
        skipped++;
      }
    }
    for (size_t i = 0; i < fdis.size(); i++) {
      Fused f = fused(s, fdis[i]);
      std::string err = vtk_check(f) + openmesh_check(f) + crown_check(s, fdis[i], f);
      EXPECT_TRUE(err.empty()) << jd << " tooth " << fdis[i] << ": " << err;
      toothfuse_fused_quality q{};
      ASSERT_EQ(toothfuse_session_fused_quality(s.get(), fdis[i], &q), TOOTHFUSE_STATUS_OK);
      EXPECT_TRUE(q.closed && q.manifold && q.watertight) << jd << " tooth " << fdis[i];
      teeth++;
    }
  }
  std::printf("checked %zu fused teeth of %zu jaws (%zu teeth skipped: one modality only; %zu "
              "fusion failures)\n",
              teeth, jaws, skipped, failed);
  EXPECT_GE(jaws, 20u);
  EXPECT_GE(teeth, 200u);
  // Every tooth present in both modalities fuses (measured: 219 of 219 with the chart band;
  // 3 lower incisors failed with the earlier loft band) and passes both checkers.
  EXPECT_EQ(failed, 0u) << "fusion failures";
}

// Two rough IOS exports (rough_jaws fixture: a rough partial upper arch and a coarse lower arch
// with missing teeth): every tooth in both modalities fuses, closed and manifold for VTK and
// OpenMesh, with every IOS crown vertex kept but the ones reported trimmed (all within 0.3 mm of
// the margin) or dropped (label-noise islands apart from the crown), and no crossing pair the
// fusion added left (with a band face or a face added to the crown; the library's exact count,
// as the Rust test fuse_rough asserts on 20 rough jaws). Measured: the coarse crowns lose up to
// ~7 % of their vertices to the fringe trim (the 0.5 % of the clean contract is not met there),
// and where the band still crosses the crown after the 0.3 mm fringe, the wider fringe (0.6,
// then 0.9 mm) trims a few teeth farther (fuse_rough: 12 teeth of 20 jaws, up to 0.52 mm); as
// there, at most 0.9 mm and at most 2 teeth per jaw beyond 0.3 mm.
TEST(FuseCheckers, RoughExportsAreClosedManifoldAndKeepTheirCrowns) {
  const CrownLimits rough{0.08, 30, true, 0.9};
  size_t jaws = 0, teeth = 0, crossings = 0, trimmedTeeth = 0;
  for (const std::string& jd : demo_jaw_dirs("TOOTHFUSE_ROUGH_JAWS_DIR", "rough_jaws")) {
    tf::Session s;
    std::vector<int32_t> fdis;
    std::vector<std::pair<int32_t, std::string>> notFused;
    fuse_demo_jaw(s, jd, fdis, notFused);
    if (HasFatalFailure()) return;
    jaws++;
    size_t widened = 0;
    for (const auto& [f, why] : notFused)
      EXPECT_NE(why.rfind("fusion failed", 0), 0u) << jd << ": tooth " << f << " lost: " << why;
    for (size_t i = 0; i < fdis.size(); i++) {
      Fused f = fused(s, fdis[i]);
      std::string err = vtk_check(f) + openmesh_check(f) + crown_check(s, fdis[i], f, rough);
      EXPECT_TRUE(err.empty()) << jd << " tooth " << fdis[i] << ": " << err;
      size_t band = 0, own = 0, trimmed = 0;
      double reach = 0;
      ASSERT_EQ(toothfuse_session_fused_crossings(s.get(), fdis[i], &band, &own),
                TOOTHFUSE_STATUS_OK);
      ASSERT_EQ(toothfuse_session_fused_trim(s.get(), fdis[i], &trimmed, &reach),
                TOOTHFUSE_STATUS_OK);
      crossings += band;
      trimmedTeeth += trimmed > 0;
      widened += reach > 0.3;
      teeth++;
    }
    EXPECT_LE(widened, 2u) << jd << ": teeth trimmed beyond 0.3 mm of the margin";
  }
  std::printf("rough exports: %zu fused teeth of %zu jaws, %zu with trimmed fringe vertices, %zu "
              "crossing pairs added by the fusion left in all\n",
              teeth, jaws, trimmedTeeth, crossings);
  EXPECT_EQ(jaws, 2u);
  EXPECT_GE(teeth, 12u);
  EXPECT_EQ(crossings, 0u) << "crossing pairs added by the fusion";
}

// The cut root of tooth `fdi` (the cut stage's result) and its cut loop.
struct CutRoot {
  std::vector<double> xyz;
  std::vector<uint32_t> tris;
  std::vector<uint32_t> loop;
};

CutRoot cut_root(tf::Session& s, int32_t fdi) {
  CutRoot r;
  size_t nv = 0, ni = 0, nl = 0;
  EXPECT_EQ(toothfuse_session_cut_size(s.get(), fdi, &nv, &ni, &nl), TOOTHFUSE_STATUS_OK);
  r.xyz.resize(3 * nv);
  r.tris.resize(ni);
  r.loop.resize(nl);
  EXPECT_EQ(toothfuse_session_copy_cut_vertices(s.get(), fdi, r.xyz.data(), nv,
                                                3 * sizeof(double), TOOTHFUSE_SCALAR_FLOAT64),
            TOOTHFUSE_STATUS_OK);
  EXPECT_EQ(toothfuse_session_copy_cut_indices(s.get(), fdi, r.tris.data(), ni),
            TOOTHFUSE_STATUS_OK);
  EXPECT_EQ(toothfuse_session_copy_cut_loop(s.get(), fdi, r.loop.data(), nl),
            TOOTHFUSE_STATUS_OK);
  return r;
}

// register -> cut -> stitch through the C API gives the one-call fuse's meshes exactly (same
// counts, same vertices, triangles and sources), and every cut root is open with one boundary
// loop: vtkFeatureEdges' boundary edges = the cut loop's length, no non-manifold edge; OpenMesh
// accepts every face, its boundary is one loop of that length through the cut loop's vertices.
TEST(FuseCheckers, RegisterCutStitchEqualsOneCallFuse) {
  const char* dir = std::getenv("TOOTHFUSE_JAWS_DIR");
  ASSERT_NE(dir, nullptr) << "TOOTHFUSE_JAWS_DIR unset (the demo_jaws fixture sets it)";
  std::string jd = std::string(dir) + "/jaw_2";  // seed 3, partial upper arch: small
  tf::Session staged, one;
  ASSERT_TRUE(tf::load_demo(staged, jd, false)) << jd;
  ASSERT_TRUE(tf::load_demo(one, jd, false)) << jd;
  EXPECT_EQ(toothfuse_session_stitch(staged.get(), nullptr), TOOTHFUSE_STATUS_WRONG_STATE);
  ASSERT_EQ(toothfuse_session_register(staged.get(), nullptr), TOOTHFUSE_STATUS_OK)
      << staged.error();
  ASSERT_EQ(toothfuse_session_cut(staged.get(), nullptr), TOOTHFUSE_STATUS_OK) << staged.error();
  int32_t cut[52];
  size_t ncut = 0;
  ASSERT_EQ(toothfuse_session_cut_teeth(staged.get(), cut, 52, &ncut), TOOTHFUSE_STATUS_OK);
  ASSERT_GE(ncut, 3u);
  for (size_t i = 0; i < ncut; i++) {
    CutRoot r = cut_root(staged, cut[i]);
    auto pd = polydata(r.xyz, r.tris);
    EXPECT_EQ(feature_edges(pd, true), static_cast<vtkIdType>(r.loop.size()))
        << "tooth " << cut[i] << ": VTK boundary edges vs cut loop";
    EXPECT_EQ(feature_edges(pd, false), 0) << "tooth " << cut[i];
    tf::MeshD m;
    std::vector<tf::MeshD::VertexHandle> vh;
    for (size_t v = 0; v < r.xyz.size() / 3; v++)
      vh.push_back(m.add_vertex(tf::MeshD::Point(r.xyz[3 * v], r.xyz[3 * v + 1], r.xyz[3 * v + 2])));
    size_t rejected = 0;
    for (size_t t = 0; t < r.tris.size() / 3; t++)
      if (!m.add_face(vh[r.tris[3 * t]], vh[r.tris[3 * t + 1]], vh[r.tris[3 * t + 2]]).is_valid())
        rejected++;
    EXPECT_EQ(rejected, 0u) << "tooth " << cut[i];
    size_t boundary = 0;
    for (auto h : m.halfedges())
      if (m.is_boundary(h)) boundary++;
    EXPECT_EQ(boundary, r.loop.size()) << "tooth " << cut[i] << ": one boundary loop";
    // Walk OpenMesh's boundary from the loop's first vertex: it visits exactly the loop.
    auto h0 = m.halfedge_handle(vh[r.loop[0]]);
    ASSERT_TRUE(m.is_boundary(h0)) << "tooth " << cut[i];
    std::vector<uint32_t> walk;
    auto h = h0;
    do {
      walk.push_back(static_cast<uint32_t>(m.from_vertex_handle(h).idx()));
      h = m.next_halfedge_handle(h);
    } while (h != h0 && walk.size() <= r.loop.size());
    std::vector<uint32_t> a = walk, b = r.loop;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b) << "tooth " << cut[i] << ": boundary walk vs cut loop";
  }
  ASSERT_EQ(toothfuse_session_stitch(staged.get(), nullptr), TOOTHFUSE_STATUS_OK)
      << staged.error();
  ASSERT_EQ(toothfuse_session_fuse(one.get(), nullptr), TOOTHFUSE_STATUS_OK) << one.error();
  int32_t a[52], b[52];
  size_t na = 0, nb = 0;
  ASSERT_EQ(toothfuse_session_fused_teeth(staged.get(), a, 52, &na), TOOTHFUSE_STATUS_OK);
  ASSERT_EQ(toothfuse_session_fused_teeth(one.get(), b, 52, &nb), TOOTHFUSE_STATUS_OK);
  ASSERT_EQ(std::vector<int32_t>(a, a + na), std::vector<int32_t>(b, b + nb));
  ASSERT_EQ(std::vector<int32_t>(a, a + na), std::vector<int32_t>(cut, cut + ncut));
  for (size_t i = 0; i < na; i++) {
    Fused x = fused(staged, a[i]), y = fused(one, a[i]);
    EXPECT_EQ(x.xyz.size(), y.xyz.size()) << "tooth " << a[i];
    EXPECT_EQ(x.tris.size(), y.tris.size()) << "tooth " << a[i];
    EXPECT_TRUE(x.xyz == y.xyz) << "tooth " << a[i] << ": vertices differ";
    EXPECT_TRUE(x.tris == y.tris) << "tooth " << a[i] << ": triangles differ";
    EXPECT_TRUE(x.source == y.source) << "tooth " << a[i] << ": sources differ";
    std::string err = vtk_check(x) + openmesh_check(x);
    EXPECT_TRUE(err.empty()) << "tooth " << a[i] << ": " << err;
  }
}

}  // namespace

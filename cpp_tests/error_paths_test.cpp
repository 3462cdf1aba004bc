// Error paths of the C ABI: every failure returns the right status, leaves a message that
// names the fault, writes no output, and leaves the session holding exactly what it held.
#include "test_support.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace {

// Cube [0,4]^3, 8 vertices, 12 outward triangles.
const std::vector<double> kCube = {0, 0, 0, 4, 0, 0, 4, 4, 0, 0, 4, 0,
                                   0, 0, 4, 4, 0, 4, 4, 4, 4, 0, 4, 4};
const std::vector<uint32_t> kCubeTris = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                         1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};

class ErrorPaths : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(add(TOOTHFUSE_MODALITY_CBCT, 11, kCube, kCubeTris), TOOTHFUSE_STATUS_OK)
        << s.error();
  }
  toothfuse_status add(toothfuse_modality m, int32_t fdi, const std::vector<double>& v,
                       const std::vector<uint32_t>& t, size_t stride = 24) {
    return toothfuse_session_add_tooth(s.get(), m, fdi, v.data(), v.size() / 3, stride,
                                       TOOTHFUSE_SCALAR_FLOAT64, t.data(), t.size());
  }
  // The session still holds CBCT tooth 11 = kCube and nothing else.
  void ExpectUnchanged() {
    EXPECT_EQ(s.teeth(TOOTHFUSE_MODALITY_CBCT), std::vector<int32_t>{11});
    EXPECT_TRUE(s.teeth(TOOTHFUSE_MODALITY_IOS).empty());
    EXPECT_EQ(s.positions(TOOTHFUSE_MODALITY_CBCT, 11), kCube);
    EXPECT_EQ(s.indices(TOOTHFUSE_MODALITY_CBCT, 11), kCubeTris);
  }
  tf::Session s;
};

TEST_F(ErrorPaths, NullPointersRejectMalformed) {
  EXPECT_EQ(toothfuse_session_add_tooth(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, nullptr, 8, 24,
                                        TOOTHFUSE_SCALAR_FLOAT64, kCubeTris.data(), 36),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  EXPECT_EQ(s.error(), "tooth 11: parameter `vertices` is NULL but 192 elements were announced");
  EXPECT_EQ(toothfuse_session_add_tooth(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, kCube.data(), 8,
                                        24, TOOTHFUSE_SCALAR_FLOAT64, nullptr, 36),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  EXPECT_EQ(toothfuse_session_add_tooth(nullptr, TOOTHFUSE_MODALITY_CBCT, 11, kCube.data(), 8,
                                        24, TOOTHFUSE_SCALAR_FLOAT64, kCubeTris.data(), 36),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  EXPECT_STREQ(toothfuse_session_last_error(nullptr), "session is NULL");
  size_t n = 0;
  EXPECT_EQ(toothfuse_session_tooth_count(s.get(), TOOTHFUSE_MODALITY_CBCT, nullptr),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  EXPECT_EQ(s.error(), "parameter `count_out` is NULL");
  EXPECT_EQ(toothfuse_session_tooth_count(nullptr, TOOTHFUSE_MODALITY_CBCT, &n),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  EXPECT_EQ(toothfuse_session_mesh_view(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, nullptr),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  EXPECT_EQ(toothfuse_session_mesh_info(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, nullptr),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  EXPECT_EQ(toothfuse_session_copy_indices(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, nullptr, 36),
            TOOTHFUSE_STATUS_NULL_PARAMETER);
  ExpectUnchanged();
}

TEST_F(ErrorPaths, OutOfRangeIndicesRejectMalformed) {
  std::vector<uint32_t> t = kCubeTris;
  t[20] = 8;
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_CBCT, 11, kCube, t), TOOTHFUSE_STATUS_INDEX_OUT_OF_BOUNDS);
  EXPECT_EQ(s.error(), "tooth 11: face 6 refers to vertex 8, but the mesh has only 8 vertices");
  t[20] = std::numeric_limits<uint32_t>::max();
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_IOS, 12, kCube, t), TOOTHFUSE_STATUS_INDEX_OUT_OF_BOUNDS);
  EXPECT_NE(s.error().find("tooth 12: face 6 refers to vertex 4294967295"), std::string::npos)
      << s.error();
  ExpectUnchanged();
}

TEST_F(ErrorPaths, NanAndInfinityRejectMalformed) {
  std::vector<double> v = kCube;
  v[3 * 6 + 2] = std::nan("");
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_CBCT, 11, v, kCubeTris), TOOTHFUSE_STATUS_NON_FINITE);
  EXPECT_EQ(s.error(), "tooth 11: vertex 6 has a non-finite coordinate (NaN or infinity)");
  v = kCube;
  v[0] = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_CBCT, 12, v, kCubeTris), TOOTHFUSE_STATUS_NON_FINITE);
  EXPECT_EQ(s.error(), "tooth 12: vertex 0 has a non-finite coordinate (NaN or infinity)");
  ExpectUnchanged();
}

TEST_F(ErrorPaths, WrongStrideAndScalarRejectMalformed) {
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_CBCT, 11, kCube, kCubeTris, 16),
            TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(s.error().find("vertex stride 16 bytes is smaller than one vertex (24 bytes"),
            std::string::npos)
      << s.error();
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_CBCT, 11, kCube, kCubeTris, 0),
            TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  // count * stride overflows size_t.
  EXPECT_EQ(toothfuse_session_add_tooth(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, kCube.data(),
                                        SIZE_MAX / 8, 24, TOOTHFUSE_SCALAR_FLOAT64,
                                        kCubeTris.data(), 36),
            TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(s.error().find("overflow"), std::string::npos) << s.error();
  EXPECT_EQ(toothfuse_session_add_tooth(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, kCube.data(), 8,
                                        24, 2, kCubeTris.data(), 36),
            TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(s.error().find("scalar type 2"), std::string::npos) << s.error();
  EXPECT_EQ(add(5, 11, kCube, kCubeTris), TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(s.error().find("modality 5"), std::string::npos) << s.error();
  // Index count not a multiple of 3.
  EXPECT_EQ(toothfuse_session_add_tooth(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, kCube.data(), 8,
                                        24, TOOTHFUSE_SCALAR_FLOAT64, kCubeTris.data(), 34),
            TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(s.error().find("index count 34 is not a multiple of 3"), std::string::npos)
      << s.error();
  ExpectUnchanged();
}

TEST_F(ErrorPaths, TopologyAndNumberingRejectMalformed) {
  // Open surface as CBCT.
  std::vector<uint32_t> open(kCubeTris.begin() + 6, kCubeTris.end());
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_CBCT, 11, kCube, open), TOOTHFUSE_STATUS_NOT_MANIFOLD);
  EXPECT_EQ(s.error().rfind("tooth 11: mesh is not closed: 4 boundary edges", 0), 0u) << s.error();
  // Duplicate face.
  std::vector<uint32_t> dup = kCubeTris;
  dup.insert(dup.end(), {2, 1, 0});
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_IOS, 11, kCube, dup), TOOTHFUSE_STATUS_NOT_MANIFOLD);
  // An IOS crown refused as given says how to have it repaired on entry.
  EXPECT_EQ(s.error().rfind("tooth 11: face 12 duplicates face 0 (same three vertices); ", 0), 0u)
      << s.error();
  EXPECT_NE(s.error().find("toothfuse_session_set_ios_repair"), std::string::npos) << s.error();
  // Degenerate face.
  std::vector<uint32_t> deg = kCubeTris;
  deg[5] = deg[4];
  EXPECT_EQ(add(TOOTHFUSE_MODALITY_IOS, 11, kCube, deg), TOOTHFUSE_STATUS_NOT_MANIFOLD);
  EXPECT_EQ(s.error().rfind("tooth 11: face 1 is degenerate (repeated vertex or zero area); ", 0),
            0u)
      << s.error();
  // Non-FDI numbers.
  for (int32_t bad : {0, 10, 19, 29, 49, 56, 91, -11}) {
    EXPECT_EQ(add(TOOTHFUSE_MODALITY_CBCT, bad, kCube, kCubeTris),
              TOOTHFUSE_STATUS_INVALID_ARGUMENT);
    EXPECT_NE(s.error().find(std::to_string(bad) + " is not an FDI tooth number"),
              std::string::npos)
        << s.error();
  }
  ExpectUnchanged();
}

TEST_F(ErrorPaths, BufferTooSmallWritesNothing) {
  std::vector<double> v(3 * 7, -1.0);
  EXPECT_EQ(toothfuse_session_copy_vertices(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, v.data(), 7, 24,
                                            TOOTHFUSE_SCALAR_FLOAT64),
            TOOTHFUSE_STATUS_BUFFER_TOO_SMALL);
  EXPECT_EQ(s.error(), "tooth 11: 8 vertices to copy but the buffer has room for 7");
  for (double x : v) EXPECT_EQ(x, -1.0);
  std::vector<uint32_t> idx(35, 77);
  EXPECT_EQ(toothfuse_session_copy_indices(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, idx.data(), 35),
            TOOTHFUSE_STATUS_BUFFER_TOO_SMALL);
  for (uint32_t i : idx) EXPECT_EQ(i, 77u);
  std::vector<uint32_t> src(7, 77);
  EXPECT_EQ(toothfuse_session_copy_source_vertices(s.get(), TOOTHFUSE_MODALITY_CBCT, 11,
                                                   src.data(), 7),
            TOOTHFUSE_STATUS_BUFFER_TOO_SMALL);
  int32_t fdis[1] = {-5};
  size_t written = 42;
  EXPECT_EQ(toothfuse_session_list_teeth(s.get(), TOOTHFUSE_MODALITY_CBCT, fdis, 0, &written),
            TOOTHFUSE_STATUS_BUFFER_TOO_SMALL);
  EXPECT_EQ(written, 42u);
  EXPECT_EQ(fdis[0], -5);
  // Asking for a tooth not held.
  size_t nv = 42, ni = 42;
  EXPECT_EQ(toothfuse_session_mesh_size(s.get(), TOOTHFUSE_MODALITY_IOS, 11, &nv, &ni),
            TOOTHFUSE_STATUS_MISSING_DATA);
  EXPECT_EQ(s.error(), "missing data: no IOS tooth 11 in the session (IOS teeth held: none)");
  EXPECT_EQ(nv, 42u);
  // The last error is cleared by the next successful call.
  EXPECT_EQ(toothfuse_session_mesh_size(s.get(), TOOTHFUSE_MODALITY_CBCT, 11, &nv, &ni),
            TOOTHFUSE_STATUS_OK);
  EXPECT_EQ(s.error(), "");
  EXPECT_EQ(nv, 8u);
  EXPECT_EQ(ni, 36u);
  ExpectUnchanged();
}

TEST_F(ErrorPaths, JawLabelsRejectMalformedAllOrNothing) {
  // Jaw: the cube as tooth 21 plus a separate open square of gingiva.
  std::vector<double> v = kCube;
  v.insert(v.end(), {10, 0, 0, 11, 0, 0, 11, 1, 0, 10, 1, 0});
  std::vector<uint32_t> t = kCubeTris;
  t.insert(t.end(), {8, 9, 10, 8, 10, 11});
  std::vector<int32_t> labels(12, 21);
  labels.insert(labels.end(), {0, 0});
  auto add_jaw = [&](const std::vector<int32_t>& l, toothfuse_label_domain d) {
    return toothfuse_session_add_jaw(s.get(), TOOTHFUSE_MODALITY_CBCT, v.data(), v.size() / 3, 24,
                                     TOOTHFUSE_SCALAR_FLOAT64, t.data(), t.size(), l.data(),
                                     l.size(), d);
  };
  std::vector<int32_t> bad = labels;
  bad[13] = 60;
  EXPECT_EQ(add_jaw(bad, TOOTHFUSE_LABEL_DOMAIN_FACE), TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(s.error().rfind("invalid argument: label 60 (on face 13) is not an FDI tooth number",
                            0),
            0u)
      << s.error();
  bad = labels;
  bad[3] = 0;  // tooth 21 loses a face: not closed
  EXPECT_EQ(add_jaw(bad, TOOTHFUSE_LABEL_DOMAIN_FACE), TOOTHFUSE_STATUS_NOT_MANIFOLD);
  EXPECT_EQ(s.error().rfind("tooth 21: mesh is not closed", 0), 0u) << s.error();
  EXPECT_EQ(add_jaw(labels, TOOTHFUSE_LABEL_DOMAIN_VERTEX), TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(s.error(),
            "invalid argument: 14 labels given but the jaw mesh has 12 vertices (one label per "
            "vertex)");
  EXPECT_EQ(add_jaw(labels, 9), TOOTHFUSE_STATUS_INVALID_ARGUMENT);
  std::vector<int32_t> none(14, 0);
  EXPECT_EQ(add_jaw(none, TOOTHFUSE_LABEL_DOMAIN_FACE), TOOTHFUSE_STATUS_MISSING_DATA);
  ExpectUnchanged();
  // And the valid jaw goes in: 21 added next to 11.
  EXPECT_EQ(add_jaw(labels, TOOTHFUSE_LABEL_DOMAIN_FACE), TOOTHFUSE_STATUS_OK) << s.error();
  EXPECT_EQ(s.teeth(TOOTHFUSE_MODALITY_CBCT), (std::vector<int32_t>{11, 21}));
}

TEST(Versions, HeaderMatchesLibrary) {
  EXPECT_EQ(toothfuse_abi_version(), static_cast<uint32_t>(TOOTHFUSE_ABI_VERSION));
  EXPECT_EQ(std::string(toothfuse_version()),
            std::to_string(TOOTHFUSE_VERSION_MAJOR) + "." +
                std::to_string(TOOTHFUSE_VERSION_MINOR) + "." +
                std::to_string(TOOTHFUSE_VERSION_PATCH));
  for (uint32_t st = 0; st <= TOOTHFUSE_STATUS_CANCELLED; st++)
    EXPECT_GT(std::strlen(toothfuse_status_string(st)), 1u) << st;
}

}  // namespace

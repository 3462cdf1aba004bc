// Helpers shared by the C++ tests: an RAII session, read-back helpers, and an independent
// re-implementation of the label split (to check the library's split against).
#pragma once

#include "toothfuse.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace tf {

class Session {
 public:
  Session() { EXPECT_EQ(toothfuse_session_new(&s_), TOOTHFUSE_STATUS_OK); }
  ~Session() { toothfuse_session_free(s_); }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  toothfuse_session* get() const { return s_; }
  std::string error() const { return toothfuse_session_last_error(s_); }

  std::vector<int32_t> teeth(toothfuse_modality m) const {
    size_t n = 0, written = 0;
    EXPECT_EQ(toothfuse_session_tooth_count(s_, m, &n), TOOTHFUSE_STATUS_OK) << error();
    std::vector<int32_t> out(n);
    EXPECT_EQ(toothfuse_session_list_teeth(s_, m, out.data(), out.size(), &written),
              TOOTHFUSE_STATUS_OK)
        << error();
    EXPECT_EQ(written, n);
    return out;
  }

  std::vector<double> positions(toothfuse_modality m, int32_t fdi) const {
    size_t nv = 0, ni = 0;
    EXPECT_EQ(toothfuse_session_mesh_size(s_, m, fdi, &nv, &ni), TOOTHFUSE_STATUS_OK) << error();
    std::vector<double> out(3 * nv);
    EXPECT_EQ(toothfuse_session_copy_vertices(s_, m, fdi, out.data(), nv, 3 * sizeof(double),
                                              TOOTHFUSE_SCALAR_FLOAT64),
              TOOTHFUSE_STATUS_OK)
        << error();
    return out;
  }

  std::vector<float> positions_f(toothfuse_modality m, int32_t fdi) const {
    size_t nv = 0, ni = 0;
    EXPECT_EQ(toothfuse_session_mesh_size(s_, m, fdi, &nv, &ni), TOOTHFUSE_STATUS_OK) << error();
    std::vector<float> out(3 * nv);
    EXPECT_EQ(toothfuse_session_copy_vertices(s_, m, fdi, out.data(), nv, 3 * sizeof(float),
                                              TOOTHFUSE_SCALAR_FLOAT32),
              TOOTHFUSE_STATUS_OK)
        << error();
    return out;
  }

  std::vector<uint32_t> indices(toothfuse_modality m, int32_t fdi) const {
    size_t nv = 0, ni = 0;
    EXPECT_EQ(toothfuse_session_mesh_size(s_, m, fdi, &nv, &ni), TOOTHFUSE_STATUS_OK) << error();
    std::vector<uint32_t> out(ni);
    EXPECT_EQ(toothfuse_session_copy_indices(s_, m, fdi, out.data(), ni), TOOTHFUSE_STATUS_OK)
        << error();
    return out;
  }

  std::vector<uint32_t> sources(toothfuse_modality m, int32_t fdi) const {
    size_t nv = 0, ni = 0;
    EXPECT_EQ(toothfuse_session_mesh_size(s_, m, fdi, &nv, &ni), TOOTHFUSE_STATUS_OK) << error();
    std::vector<uint32_t> out(nv);
    EXPECT_EQ(toothfuse_session_copy_source_vertices(s_, m, fdi, out.data(), nv),
              TOOTHFUSE_STATUS_OK)
        << error();
    return out;
  }

  toothfuse_mesh_info info(toothfuse_modality m, int32_t fdi) const {
    toothfuse_mesh_info i{};
    EXPECT_EQ(toothfuse_session_mesh_info(s_, m, fdi, &i), TOOTHFUSE_STATUS_OK) << error();
    return i;
  }

 private:
  toothfuse_session* s_ = nullptr;
};

/// One label's part of a mesh, split independently of the library: faces in input order,
/// vertices numbered by first use.
struct Part {
  std::vector<uint32_t> indices;  // local
  std::vector<uint32_t> source;   // local vertex -> input vertex
};

/// Face labels from per-vertex labels: a face gets L when all three corners are L, else -1.
inline std::vector<int32_t> face_labels_from_vertices(const std::vector<uint32_t>& tris,
                                                      const std::vector<int32_t>& vlabels) {
  std::vector<int32_t> out(tris.size() / 3);
  for (size_t f = 0; f < out.size(); f++) {
    int32_t l = vlabels[tris[3 * f]];
    out[f] = (vlabels[tris[3 * f + 1]] == l && vlabels[tris[3 * f + 2]] == l) ? l : -1;
  }
  return out;
}

inline std::map<int32_t, Part> split(const std::vector<uint32_t>& tris,
                                     const std::vector<int32_t>& face_labels, size_t nverts) {
  std::map<int32_t, Part> parts;
  std::map<int32_t, std::vector<int64_t>> local;
  for (size_t f = 0; f < face_labels.size(); f++) {
    int32_t l = face_labels[f];
    if (l <= 0) continue;
    Part& p = parts[l];
    std::vector<int64_t>& map = local[l];
    if (map.empty()) map.assign(nverts, -1);
    for (int k = 0; k < 3; k++) {
      uint32_t v = tris[3 * f + k];
      if (map[v] < 0) {
        map[v] = static_cast<int64_t>(p.source.size());
        p.source.push_back(v);
      }
      p.indices.push_back(static_cast<uint32_t>(map[v]));
    }
  }
  return parts;
}

/// Independent non-manifold census of a triangle mesh: edges used by more than two faces (or
/// twice in one direction), and vertices whose faces form more than one edge-connected fan.
struct Manifoldness {
  size_t bad_edges = 0;
  size_t bad_vertices = 0;
  bool ok() const { return bad_edges == 0 && bad_vertices == 0; }
};

inline Manifoldness manifoldness(const std::vector<uint32_t>& tris, size_t nverts) {
  Manifoldness m;
  std::map<std::pair<uint32_t, uint32_t>, std::pair<int, int>> edges;  // (lo,hi) -> (fwd, back)
  for (size_t f = 0; f < tris.size() / 3; f++)
    for (int k = 0; k < 3; k++) {
      uint32_t a = tris[3 * f + k], b = tris[3 * f + (k + 1) % 3];
      auto& e = edges[{std::min(a, b), std::max(a, b)}];
      (a < b ? e.first : e.second)++;
    }
  for (const auto& kv : edges)
    if (kv.second.first + kv.second.second > 2 || kv.second.first > 1 || kv.second.second > 1)
      m.bad_edges++;
  // Fans: per vertex, union the incident faces that share another vertex with each other.
  std::vector<std::vector<uint32_t>> faces_of(nverts);
  for (size_t f = 0; f < tris.size() / 3; f++)
    for (int k = 0; k < 3; k++) faces_of[tris[3 * f + k]].push_back(static_cast<uint32_t>(f));
  for (size_t v = 0; v < nverts; v++) {
    const auto& fs = faces_of[v];
    if (fs.size() < 2) continue;
    std::vector<size_t> parent(fs.size());
    for (size_t i = 0; i < fs.size(); i++) parent[i] = i;
    auto find = [&](size_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    std::map<uint32_t, size_t> first_with;  // other vertex -> first fan face using it
    for (size_t i = 0; i < fs.size(); i++)
      for (int k = 0; k < 3; k++) {
        uint32_t w = tris[3 * fs[i] + k];
        if (w == v) continue;
        auto it = first_with.find(w);
        if (it == first_with.end())
          first_with[w] = i;
        else
          parent[find(i)] = find(it->second);
      }
    size_t roots = 0;
    for (size_t i = 0; i < fs.size(); i++) roots += find(i) == i;
    if (roots > 1) m.bad_vertices++;
  }
  return m;
}

inline std::string env_or_empty(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::string(v) : std::string();
}

}  // namespace tf

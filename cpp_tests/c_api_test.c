/* Pure C11 test of the toothfuse C ABI (compiled with -Wall -Wextra -Wpedantic -Werror).
 * Includes the header twice (include guard) and links a second translation unit that does the
 * same, so a missing guard or a non-inline definition in the header fails the build. */
#include "toothfuse.h"
#include "toothfuse.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

int toothfuse_double_include_probe(void);

/* A progress callback as a C host writes one: counts its reports, never cancels. */
static int32_t count_reports(void *user_data, toothfuse_stage stage, size_t done, size_t total) {
  (void)stage;
  (void)done;
  (void)total;
  ++*(int *)user_data;
  return 0;
}

static int failures = 0;

#define CHECK(cond)                                                                  \
  do {                                                                               \
    if (!(cond)) {                                                                   \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);       \
      failures++;                                                                    \
    }                                                                                \
  } while (0)

#define CHECK_STATUS(expr, want)                                                     \
  do {                                                                               \
    toothfuse_status st_ = (expr);                                                   \
    if (st_ != (want)) {                                                             \
      fprintf(stderr, "%s:%d: %s returned %u (%s), want %u; last error: %s\n", __FILE__, \
              __LINE__, #expr, (unsigned)st_, toothfuse_status_string((uint32_t)st_), \
              (unsigned)(want), toothfuse_session_last_error(session));              \
      failures++;                                                                    \
    }                                                                                \
  } while (0)

/* A tetrahedron, outward-oriented, as float with a 16-byte stride (x, y, z, pad). */
static const float tet_f[4][4] = {
    {0.1f, 0.2f, 0.3f, -7.0f}, {5.1f, 0.2f, 0.3f, -7.0f},
    {0.1f, 5.2f, 0.3f, -7.0f}, {0.1f, 0.2f, 5.3f, -7.0f}};
static const uint32_t tet_t[12] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};

int main(void) {
  toothfuse_session *session = NULL;
  char want_version[64];

  /* Versions. */
  snprintf(want_version, sizeof want_version, "%d.%d.%d", TOOTHFUSE_VERSION_MAJOR,
           TOOTHFUSE_VERSION_MINOR, TOOTHFUSE_VERSION_PATCH);
  CHECK(strcmp(toothfuse_version(), want_version) == 0);
  CHECK(toothfuse_abi_version() == TOOTHFUSE_ABI_VERSION);
  CHECK(strcmp(toothfuse_status_string(TOOTHFUSE_STATUS_OK), "ok") == 0);
  CHECK(strcmp(toothfuse_status_string(12345u), "unknown status") == 0);
  CHECK(toothfuse_double_include_probe() == TOOTHFUSE_ABI_VERSION);

  /* Lifetime. */
  CHECK(toothfuse_session_new(NULL) == TOOTHFUSE_STATUS_NULL_PARAMETER);
  toothfuse_session_free(NULL);
  CHECK_STATUS(toothfuse_session_new(&session), TOOTHFUSE_STATUS_OK);
  if (session == NULL) return 1;

  /* Thread cap: per session, any value; this test's calls then run on this thread alone. */
  CHECK(toothfuse_session_set_max_threads(NULL, 1) == TOOTHFUSE_STATUS_NULL_PARAMETER);
  CHECK_STATUS(toothfuse_session_set_max_threads(session, 0), TOOTHFUSE_STATUS_OK);
  CHECK_STATUS(toothfuse_session_set_max_threads(session, 1), TOOTHFUSE_STATUS_OK);

  /* Add a CBCT tooth from float vertices with padding. */
  CHECK_STATUS(toothfuse_session_add_tooth(session, TOOTHFUSE_MODALITY_CBCT, 21, tet_f, 4,
                                           sizeof tet_f[0], TOOTHFUSE_SCALAR_FLOAT32, tet_t, 12),
               TOOTHFUSE_STATUS_OK);
  CHECK(strcmp(toothfuse_session_last_error(session), "") == 0);

  {
    size_t n = 0, written = 0;
    int32_t fdis[4] = {0, 0, 0, 0};
    CHECK_STATUS(toothfuse_session_tooth_count(session, TOOTHFUSE_MODALITY_CBCT, &n),
                 TOOTHFUSE_STATUS_OK);
    CHECK(n == 1);
    CHECK_STATUS(toothfuse_session_list_teeth(session, TOOTHFUSE_MODALITY_CBCT, fdis, 0, &written),
                 TOOTHFUSE_STATUS_BUFFER_TOO_SMALL);
    CHECK(written == 0);
    CHECK_STATUS(toothfuse_session_list_teeth(session, TOOTHFUSE_MODALITY_CBCT, fdis, 4, &written),
                 TOOTHFUSE_STATUS_OK);
    CHECK(written == 1 && fdis[0] == 21);
    CHECK_STATUS(toothfuse_session_tooth_count(session, TOOTHFUSE_MODALITY_IOS, &n),
                 TOOTHFUSE_STATUS_OK);
    CHECK(n == 0);
  }

  /* Read back: view (double, exact float->double) and copy-out as float. */
  {
    struct toothfuse_mesh_view view;
    toothfuse_mesh_info info;
    float back[4][3];
    uint32_t idx[12];
    size_t nv = 0, ni = 0, i, k;
    memset(&view, 0, sizeof view);
    CHECK_STATUS(toothfuse_session_mesh_size(session, TOOTHFUSE_MODALITY_CBCT, 21, &nv, &ni),
                 TOOTHFUSE_STATUS_OK);
    CHECK(nv == 4 && ni == 12);
    CHECK_STATUS(toothfuse_session_mesh_view(session, TOOTHFUSE_MODALITY_CBCT, 21, &view),
                 TOOTHFUSE_STATUS_OK);
    CHECK(view.vertex_count == 4 && view.index_count == 12);
    for (i = 0; i < 4; i++)
      for (k = 0; k < 3; k++) CHECK(view.positions[3 * i + k] == (double)tet_f[i][k]);
    for (i = 0; i < 12; i++) CHECK(view.indices[i] == tet_t[i]);
    CHECK_STATUS(toothfuse_session_copy_vertices(session, TOOTHFUSE_MODALITY_CBCT, 21, back, 4,
                                                 sizeof back[0], TOOTHFUSE_SCALAR_FLOAT32),
                 TOOTHFUSE_STATUS_OK);
    for (i = 0; i < 4; i++)
      for (k = 0; k < 3; k++) CHECK(back[i][k] == tet_f[i][k]);
    CHECK_STATUS(toothfuse_session_copy_indices(session, TOOTHFUSE_MODALITY_CBCT, 21, idx, 11),
                 TOOTHFUSE_STATUS_BUFFER_TOO_SMALL);
    CHECK(strstr(toothfuse_session_last_error(session), "12 indices") != NULL);
    CHECK_STATUS(toothfuse_session_copy_indices(session, TOOTHFUSE_MODALITY_CBCT, 21, idx, 12),
                 TOOTHFUSE_STATUS_OK);
    CHECK(memcmp(idx, tet_t, sizeof idx) == 0);
    CHECK_STATUS(toothfuse_session_mesh_info(session, TOOTHFUSE_MODALITY_CBCT, 21, &info),
                 TOOTHFUSE_STATUS_OK);
    CHECK(info.closed && info.manifold && info.boundary_loops == 0 && info.components == 1);
    CHECK(fabs(info.signed_volume - 125.0 / 6.0) < 1e-4);
  }

  /* Errors keep the session as it was. */
  {
    float bad[4][4];
    size_t n = 0;
    memcpy(bad, tet_f, sizeof bad);
    bad[2][1] = NAN;
    CHECK_STATUS(toothfuse_session_add_tooth(session, TOOTHFUSE_MODALITY_CBCT, 21, bad, 4,
                                             sizeof bad[0], TOOTHFUSE_SCALAR_FLOAT32, tet_t, 12),
                 TOOTHFUSE_STATUS_NON_FINITE);
    CHECK(strcmp(toothfuse_session_last_error(session),
                 "tooth 21: vertex 2 has a non-finite coordinate (NaN or infinity)") == 0);
    CHECK_STATUS(toothfuse_session_add_tooth(session, TOOTHFUSE_MODALITY_CBCT, 21, tet_f, 4, 8,
                                             TOOTHFUSE_SCALAR_FLOAT32, tet_t, 12),
                 TOOTHFUSE_STATUS_INVALID_ARGUMENT);
    CHECK_STATUS(toothfuse_session_add_tooth(session, TOOTHFUSE_MODALITY_CBCT, 21, NULL, 4, 16,
                                             TOOTHFUSE_SCALAR_FLOAT32, tet_t, 12),
                 TOOTHFUSE_STATUS_NULL_PARAMETER);
    CHECK_STATUS(toothfuse_session_add_tooth(session, TOOTHFUSE_MODALITY_CBCT, 21, tet_f, 4, 16,
                                             TOOTHFUSE_SCALAR_FLOAT32, tet_t, 9),
                 TOOTHFUSE_STATUS_NOT_MANIFOLD);
    CHECK(strstr(toothfuse_session_last_error(session), "tooth 21: mesh is not closed") != NULL);
    CHECK_STATUS(toothfuse_session_tooth_count(session, TOOTHFUSE_MODALITY_CBCT, &n),
                 TOOTHFUSE_STATUS_OK);
    CHECK(n == 1);
    {
      struct toothfuse_mesh_view view;
      CHECK_STATUS(toothfuse_session_mesh_view(session, TOOTHFUSE_MODALITY_CBCT, 21, &view),
                   TOOTHFUSE_STATUS_OK);
      CHECK(view.positions[7] == (double)tet_f[2][1]);
    }
  }

  /* A labeled jaw: one crown-sized IOS crown (an open tetrahedron fan, 8 mm: the unit check
     refuses millimetre meshes the size of centimetre ones) with per-face labels. */
  {
    static const double jaw_v[5][3] = {
        {0, 0, 0}, {8, 0, 0}, {0, 8, 0}, {0, 0, 8}, {24, 24, 24}};
    static const uint32_t jaw_t[9] = {0, 1, 3, 1, 2, 3, 2, 4, 1};
    int32_t labels[3] = {36, 36, 0};
    toothfuse_mesh_info info;
    uint32_t src[3];
    CHECK_STATUS(toothfuse_session_add_jaw(session, TOOTHFUSE_MODALITY_IOS, jaw_v, 5,
                                           sizeof jaw_v[0], TOOTHFUSE_SCALAR_FLOAT64, jaw_t, 9,
                                           labels, 3, TOOTHFUSE_LABEL_DOMAIN_FACE),
                 TOOTHFUSE_STATUS_OK);
    CHECK_STATUS(toothfuse_session_mesh_info(session, TOOTHFUSE_MODALITY_IOS, 36, &info),
                 TOOTHFUSE_STATUS_OK);
    CHECK(!info.closed && info.manifold && info.boundary_loops == 1 && info.vertex_count == 4);
    CHECK_STATUS(toothfuse_session_copy_source_vertices(session, TOOTHFUSE_MODALITY_IOS, 36, src, 3),
                 TOOTHFUSE_STATUS_BUFFER_TOO_SMALL);
    labels[2] = 99;
    CHECK_STATUS(toothfuse_session_add_jaw(session, TOOTHFUSE_MODALITY_IOS, jaw_v, 5,
                                           sizeof jaw_v[0], TOOTHFUSE_SCALAR_FLOAT64, jaw_t, 9,
                                           labels, 3, TOOTHFUSE_LABEL_DOMAIN_FACE),
                 TOOTHFUSE_STATUS_INVALID_ARGUMENT);
    CHECK(strstr(toothfuse_session_last_error(session), "label 99 (on face 2)") != NULL);
  }

  /* The progress callback from C: set (a plain C function), refused on NULL, removed. A call
   * that fails before any stage starts reports nothing. */
  {
    int reports = 0;
    toothfuse_progress_fn cb = count_reports;
    CHECK(toothfuse_session_set_progress(NULL, cb, &reports) == TOOTHFUSE_STATUS_NULL_PARAMETER);
    CHECK_STATUS(toothfuse_session_set_progress(session, cb, &reports), TOOTHFUSE_STATUS_OK);
    CHECK_STATUS(toothfuse_session_cut(session, NULL), TOOTHFUSE_STATUS_WRONG_STATE);
    CHECK(reports == 0);
    CHECK_STATUS(toothfuse_session_set_progress(session, NULL, NULL), TOOTHFUSE_STATUS_OK);
    CHECK(strcmp(toothfuse_status_string(TOOTHFUSE_STATUS_CANCELLED),
                 "cancelled by the progress callback") == 0);
  }

  /* The fusion stages from C: no registration yet, so no cut; no cut, so no stitch. */
  {
    size_t nv = 0, ni = 0, nl = 0;
    CHECK(toothfuse_session_cut(NULL, NULL) == TOOTHFUSE_STATUS_NULL_PARAMETER);
    CHECK(toothfuse_session_stitch(NULL, NULL) == TOOTHFUSE_STATUS_NULL_PARAMETER);
    CHECK_STATUS(toothfuse_session_cut(session, NULL), TOOTHFUSE_STATUS_WRONG_STATE);
    CHECK(strstr(toothfuse_session_last_error(session), "registration") != NULL);
    CHECK_STATUS(toothfuse_session_stitch(session, NULL), TOOTHFUSE_STATUS_WRONG_STATE);
    CHECK(strstr(toothfuse_session_last_error(session), "cut") != NULL);
    CHECK_STATUS(toothfuse_session_cut_size(session, 21, &nv, &ni, &nl),
                 TOOTHFUSE_STATUS_WRONG_STATE);
  }

  toothfuse_session_free(session);
  if (failures != 0) {
    fprintf(stderr, "%d check(s) failed\n", failures);
    return 1;
  }
  printf("c_api_test: all checks passed\n");
  return 0;
}

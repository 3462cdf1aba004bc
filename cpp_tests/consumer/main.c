/* Outside consumer: links the installed toothfuse, adds a tetrahedron, reads it back. */
#include <toothfuse.h>

#include <stdio.h>
#include <string.h>

int main(void) {
  static const double v[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  static const uint32_t t[12] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
  toothfuse_session *s = NULL;
  toothfuse_mesh_info info;
  if (toothfuse_abi_version() != TOOTHFUSE_ABI_VERSION) return 1;
  if (toothfuse_session_new(&s) != TOOTHFUSE_STATUS_OK) return 2;
  if (toothfuse_session_add_tooth(s, TOOTHFUSE_MODALITY_CBCT, 46, v, 4, 3 * sizeof(double),
                                  TOOTHFUSE_SCALAR_FLOAT64, t, 12) != TOOTHFUSE_STATUS_OK) {
    fprintf(stderr, "add_tooth: %s\n", toothfuse_session_last_error(s));
    return 3;
  }
  if (toothfuse_session_mesh_info(s, TOOTHFUSE_MODALITY_CBCT, 46, &info) != TOOTHFUSE_STATUS_OK ||
      !info.closed || info.vertex_count != 4)
    return 4;
  printf("toothfuse %s: tooth 46 closed, volume %.6f mm^3\n", toothfuse_version(),
         info.signed_volume);
  toothfuse_session_free(s);
  return 0;
}

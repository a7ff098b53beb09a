/* fuzz_inp.c - the Abaqus .inp reader (palp_fem_inp_read) on arbitrary files. */
#include "fuzz_util.h"
#include "palp_fem.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_file(data, size, ".inp");
  palp_fem_mesh m;
  char err[512];
  if (palp_fem_inp_read(path, &m, err, sizeof err) == 0) palp_fem_mesh_destroy(&m);
  return 0;
}

/* fuzz_scene.c - palp_scene_parse on arbitrary text; a scene it accepts is also serialised
 * back (palp_scene_to_json) and must parse again. */
#include "fuzz_util.h"
#include "palp.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *json = fuzz_cstr(data, size);
  palp_scene s;
  char err[512];
  if (palp_scene_parse(json, &s, err, sizeof err) == 0) {
    char *back = palp_scene_to_json(&s);
    if (back) {
      palp_scene t;
      if (palp_scene_parse(back, &t, err, sizeof err) != 0) {
        fprintf(stderr, "a scene palp_scene_to_json wrote does not parse: %s\n", err);
        abort();
      }
      free(back);
    }
  }
  free(json);
  return 0;
}

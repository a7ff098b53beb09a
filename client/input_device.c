/* input_device.c - loads a haptic device driver from a shared object. */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>

#include "input.h"
#include "palp_haptic.h"

int palp_cli_device_input(const char *path, const char *arg, palp_cli_input *out, char *err, size_t errlen) {
  void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!h) {
    snprintf(err, errlen, "device driver %s: %s", path, dlerror());
    return PALP_EIO;
  }
  /* POSIX guarantees data and function pointers convert through dlsym. */
  palp_cli_device_entry entry;
  *(void **)(&entry) = dlsym(h, "palp_cli_device_driver");
  if (!entry) {
    snprintf(err, errlen, "device driver %s: no symbol palp_cli_device_driver", path);
    dlclose(h);
    return PALP_EINVAL;
  }
  *out = (palp_cli_input){0}; /* a driver built against an older header leaves the newer fields zero */
  int rc = entry(arg ? arg : "", out);
  if (rc < 0) {
    snprintf(err, errlen, "device driver %s: initialisation failed (%s)", path, palp_strerror(rc));
    dlclose(h);
    return rc;
  }
  /* A haptic device (read_position and write_force) runs on the haptic thread, which never calls
   * poll (client/input.h); a force-driven source needs poll. Such a driver was refused for lacking
   * poll, and its context left allocated: now only one with neither is, and closed first. */
  if (!out->poll && !(out->read_position && out->write_force)) {
    snprintf(err, errlen, "device driver %s: gives neither read_position and write_force (a haptic device) "
             "nor poll (a force-driven source)", path);
    if (out->close) out->close(out->ctx);
    dlclose(h);
    return PALP_EINVAL;
  }
  /* The handle stays open for the life of the process: the driver's code runs
   * until palp-client exits. */
  return 0;
}

int palp_cli_device_force(palp_vec3 f, double max_force, palp_vec3 *out) {
  /* the renderer's own limit (src/haptic.c): magnitude, and 0 N for what is not finite */
  unsigned flags = 0;
  *out = palp_haptic_clamp(f, max_force, &flags);
  const double mag = sqrt(f.x * f.x + f.y * f.y + f.z * f.z); /* [N]: NaN or inf if any part is */
  if (!isfinite(mag) || !(max_force > 0)) {
    *out = (palp_vec3){0, 0, 0};
    return PALP_EINVAL;
  }
  return (flags & PALP_HAPTIC_LIMITED) ? 1 : 0;
}

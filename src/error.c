#include "palp.h"

const char *palp_strerror(int err) {
  switch (err) {
  case PALP_OK: return "ok";
  case PALP_EINVAL: return "invalid argument or parameter";
  case PALP_ENOMEM: return "out of memory";
  case PALP_ERANGE: return "index out of range";
  case PALP_EPARSE: return "malformed input";
  case PALP_EIO: return "input/output error";
  case PALP_EUNSTABLE: return "state became non-finite";
  case PALP_EFULL: return "no free slot";
  case PALP_ESOLVER: return "sparse factorisation failed";
  case PALP_EBUSY: return "a deferred refactorisation is due but its host has not handed it back";
  default: return "unknown error";
  }
}

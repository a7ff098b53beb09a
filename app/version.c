/* version.c - the version every palp program prints and every log records (palp_app.h). Alone in its
 * file so that a new version recompiles only this; palp_version.h is written at every build by
 * cmake/PalpVersion.cmake (rewritten only when the version changed). */
#include "palp_app.h"

#include "palp_version.h"

const char *palp_app_version(void) { return PALP_VERSION_STRING; }

/* fem_run.c - placeholder */
#include "fem_internal.h"

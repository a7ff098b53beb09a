/* fem_cache.c - placeholder */
#include "fem_internal.h"

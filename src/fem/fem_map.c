/* fem_map.c - placeholder */
#include "fem_internal.h"

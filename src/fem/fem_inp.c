/* fem_inp.c - placeholder */
#include "fem_internal.h"

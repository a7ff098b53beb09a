/* placeholder until the statistics module lands */
#include "palp.h"

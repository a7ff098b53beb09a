/* placeholder until the model lands */
#include "palp.h"

#include "frame.h"
#include "izb.h"
#include "shadow_common.h"
#include "shadows/izb_common.glsl"

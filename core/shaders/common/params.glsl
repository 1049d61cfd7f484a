// The uniform block shared by every march kernel (layout in layout.h).
#include "layout.h"

layout(std140, binding = kBindingParams) uniform b_MarchParams {
    MarchParams u;
};

float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

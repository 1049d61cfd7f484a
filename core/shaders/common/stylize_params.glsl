// The stylizer's uniform block (layout in layout.h).
#include "layout.h"

layout(std140, binding = kBindingParams) uniform b_StylizeParams {
    StylizeParams u;
};

#include "protocol/build_version.h"

namespace volstyle::protocol {

const char* versionString() { return VOLSTYLE_VERSION; }

}  // namespace volstyle::protocol

// libFuzzer harness: an uploaded target or weight image, decoded from memory as the server does
// (sniffed format, the size checked from the header before any pixel is decoded, non-finite
// values refused). Refusals are volstyle errors; anything else is a bug.
#include <cstddef>
#include <cstdint>

#include "core/base/errors.h"
#include "core/image/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        volstyle::core::loadImageFromMemory(data, size, "fuzz", 256, [](int w, int h) {
            if (size_t(w) * size_t(h) > 128 * 128) throw volstyle::InvalidArgument("larger than the fuzzed view");
        });
    } catch (const volstyle::Error&) {
    }
    return 0;
}

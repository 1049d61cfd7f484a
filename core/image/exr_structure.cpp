#include "core/image/exr_structure.h"

#include <cstdint>
#include <cstring>
#include <string>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

// OpenEXR file layout (openexr.com, "OpenEXR File Layout"): magic, a version word, then the
// header(s): attributes of (name\0, type\0, int32 size, size bytes), each header ended by \0; a
// multi-part file ends its list of headers with one more \0.
constexpr uint32_t kLongNames = 0x400;
constexpr uint32_t kMultiPart = 0x1000;
constexpr int kMaxParts = 64;

int32_t readLe32(const unsigned char* p) {
    uint32_t v = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
    int32_t s;
    std::memcpy(&s, &v, sizeof s);
    return s;
}

/// Printable names only in messages (the bytes are an attacker's).
std::string printable(const std::string& s) {
    for (unsigned char c : s)
        if (c < 0x20 || c > 0x7e) return "(unprintable)";
    return "'" + s + "'";
}

class HeaderWalk {
public:
    HeaderWalk(const unsigned char* data, size_t size, int maxSide, const char* name)
        : m_p(data), m_n(size), m_maxSide(maxSide), m_name(name) {}

    void run() {
        if (m_n < 8) fail("is too short to be an OpenEXR file");
        const uint32_t flags = uint32_t(readLe32(m_p + 4));
        m_maxNameLength = (flags & kLongNames) ? 255 : 31;
        m_at = 8;
        if (!(flags & kMultiPart)) {
            if (!header()) fail("has an empty header");
            return;
        }
        int parts = 0;
        while (header()) {
            if (++parts > kMaxParts) fail("has over " + std::to_string(kMaxParts) + " parts");
        }
        if (parts == 0) fail("has no parts");
    }

private:
    [[noreturn]] void fail(const std::string& why) const {
        throw InvalidArgument(std::string("'") + m_name + "' " + why + " (OpenEXR header, byte " + std::to_string(m_at) + ")");
    }

    std::string string() {
        const size_t start = m_at;
        while (m_at < m_n && m_p[m_at] != 0) {
            if (m_at - start >= m_maxNameLength) fail("has an attribute name or type over " + std::to_string(m_maxNameLength) + " characters");
            ++m_at;
        }
        if (m_at >= m_n) fail("ends inside its header");
        return std::string(reinterpret_cast<const char*>(m_p + start), m_at++ - start);
    }

    /// One header; false when it is empty (the end of a multi-part list).
    bool header() {
        bool any = false;
        for (;;) {
            if (m_at >= m_n) fail("ends inside its header");
            if (m_p[m_at] == 0) {
                ++m_at;
                return any;
            }
            const std::string name = string();
            const std::string type = string();
            if (m_n - m_at < 4) fail("ends inside its header");
            const int32_t size = readLe32(m_p + m_at);
            m_at += 4;
            if (size < 0 || size_t(size) > m_n - m_at) {
                fail("has attribute " + printable(name) + " claiming " + std::to_string(size) + " bytes where " +
                     std::to_string(m_n - m_at) + " remain");
            }
            if (type == "box2i" && size == 16 && (name == "dataWindow" || name == "displayWindow")) window(name);
            m_at += size_t(size);
            any = true;
        }
    }

    /// A data or display window: its sides must fit the largest image side we accept.
    void window(const std::string& name) const {
        const int64_t xMin = readLe32(m_p + m_at), yMin = readLe32(m_p + m_at + 4);
        const int64_t xMax = readLe32(m_p + m_at + 8), yMax = readLe32(m_p + m_at + 12);
        const int64_t w = xMax - xMin + 1, h = yMax - yMin + 1;
        if (w < 1 || h < 1) fail("has an empty " + name);
        if (w > m_maxSide || h > m_maxSide) {
            throw LimitExceeded(std::string("'") + m_name + "' is " + std::to_string(w) + "x" + std::to_string(h) + " (" + name +
                                "); each side must be in [1, " + std::to_string(m_maxSide) + "]");
        }
    }

    const unsigned char* m_p;
    size_t m_n;
    int m_maxSide;
    const char* m_name;
    size_t m_at = 0;
    size_t m_maxNameLength = 31;
};

}  // namespace

void checkExrStructure(const unsigned char* data, size_t size, int maxSide, const char* nameHint) {
    HeaderWalk(data, size, maxSide, nameHint).run();
}

}  // namespace volstyle::core

#include "protocol/mesh_upload_check.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include "core/base/errors.h"

namespace volstyle::protocol {
namespace {

using json = nlohmann::json;
constexpr double kMaxCount = 4294967295.0;  // glTF's integers are 32-bit where they count bytes or elements

uint32_t le32(const std::string& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;  // little-endian hosts only (x86-64, aarch64)
}

std::string_view typeName(const json& j) { return j.type_name(); }

/// A non-negative integer at `key` of `object` (`fallback` when absent), at most `max`.
double count(const json& object, const char* key, double fallback, double max, const std::string& where) {
    if (!object.contains(key)) return fallback;
    const json& v = object[key];
    if (!v.is_number_integer() && !v.is_number_unsigned())
        throw InvalidArgument("the glTF's " + where + "/" + key + " is a " + std::string(typeName(v)) + ", not an integer");
    const double x = v.is_number_unsigned() ? double(v.get<uint64_t>()) : double(v.get<int64_t>());
    if (x < 0 || x > max)
        throw InvalidArgument("the glTF's " + where + "/" + key + " is " + v.dump() + ", outside 0.." + std::to_string(uint64_t(max)));
    return x;
}

/// An index into an array of `size` elements at `key` (−1 when absent).
long indexAt(const json& object, const char* key, size_t size, const std::string& where, const char* into) {
    if (!object.contains(key)) return -1;
    const double i = count(object, key, -1, kMaxCount, where);
    if (i >= double(size))
        throw InvalidArgument("the glTF's " + where + "/" + key + " is " + std::to_string(uint64_t(i)) + " but it has " +
                              std::to_string(size) + " " + into);
    return long(i);
}

const json& arrayAt(const json& doc, const char* key) {
    static const json empty = json::array();
    if (!doc.contains(key)) return empty;
    if (!doc[key].is_array()) throw InvalidArgument(std::string("the glTF's /") + key + " is not an array");
    return doc[key];
}

/// The deepest nesting of arrays and objects in JSON text (strings skipped).
int jsonDepth(std::string_view text, int stopAt) {
    int depth = 0, deepest = 0;
    bool inString = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (inString) {
            if (c == '\\') ++i;
            else if (c == '"') inString = false;
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            deepest = std::max(deepest, ++depth);
            if (deepest > stopAt) return deepest;
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return deepest;
}

/// The GLB container: header and chunks add up to the bytes present; the JSON chunk's text and
/// the BIN chunk's length (0 without one).
std::string_view glbJson(const std::string& b, size_t& binBytes) {
    if (b.size() < 20 || b.compare(0, 4, "glTF") != 0) throw InvalidArgument("the GLB is shorter than its 20-byte header or lacks the 'glTF' magic");
    if (le32(b, 4) != 2) throw InvalidArgument("the GLB is version " + std::to_string(le32(b, 4)) + "; only glTF 2.0 is read");
    if (le32(b, 8) != b.size())
        throw InvalidArgument("the GLB's header declares " + std::to_string(le32(b, 8)) + " bytes but the upload holds " +
                              std::to_string(b.size()));
    const uint64_t jsonBytes = le32(b, 12);
    if (le32(b, 16) != 0x4E4F534Au) throw InvalidArgument("the GLB's first chunk is not its JSON chunk");
    if (20 + jsonBytes > b.size())
        throw InvalidArgument("the GLB's JSON chunk declares " + std::to_string(jsonBytes) + " bytes; " + std::to_string(b.size() - 20) +
                              " follow the header");
    binBytes = 0;
    for (uint64_t at = 20 + jsonBytes; at < b.size();) {
        if (at + 8 > b.size()) throw InvalidArgument("the GLB ends inside a chunk header");
        const uint64_t n = le32(b, size_t(at));
        if (at + 8 + n > b.size())
            throw InvalidArgument("a GLB chunk declares " + std::to_string(n) + " bytes; " + std::to_string(b.size() - at - 8) + " remain");
        if (le32(b, size_t(at + 4)) == 0x004E4942u && binBytes == 0) binBytes = size_t(n);
        at += 8 + n;
    }
    return std::string_view(b).substr(20, size_t(jsonBytes));
}

/// Extensions that may be required: assimp reads them or they change nothing an occluder uses.
bool honoured(const std::string& name) {
    return name.rfind("KHR_materials_", 0) == 0 || name == "KHR_texture_transform" || name == "KHR_lights_punctual";
}

void checkBuffers(const json& doc, bool glb, size_t binBytes, std::vector<double>& bufferBytes) {
    const json& buffers = arrayAt(doc, "buffers");
    for (size_t i = 0; i < buffers.size(); ++i) {
        const std::string where = "/buffers/" + std::to_string(i);
        const json& buf = buffers[i];
        if (!buf.is_object()) throw InvalidArgument("the glTF's " + where + " is not an object");
        const double bytes = count(buf, "byteLength", 0, kMaxCount, where);
        if (!buf.contains("uri")) {
            if (!glb || i != 0) throw InvalidArgument("the glTF's " + where + " has no uri (only a GLB's first buffer may live in its BIN chunk)");
            if (bytes > double(binBytes))
                throw InvalidArgument("the glTF's " + where + " declares " + std::to_string(uint64_t(bytes)) + " bytes; the GLB's BIN chunk holds " +
                                      std::to_string(binBytes));
        } else {
            const json& uri = buf["uri"];
            if (!uri.is_string()) throw InvalidArgument("the glTF's " + where + "/uri is not a string");
            const std::string& u = uri.get_ref<const std::string&>();
            const size_t comma = u.find(";base64,");
            if (u.rfind("data:", 0) != 0 || comma == std::string::npos)
                throw InvalidArgument("the glTF's " + where + " refers to the file '" + u.substr(0, 80) +
                                      "'; an upload brings no other files: embed its buffers as base64 data: URIs, or upload a .glb");
            const double holds = double(u.size() - comma - 8) * 3 / 4;
            if (bytes > holds + 2)
                throw InvalidArgument("the glTF's " + where + " declares " + std::to_string(uint64_t(bytes)) + " bytes; its data URI holds about " +
                                      std::to_string(uint64_t(holds)));
        }
        bufferBytes.push_back(bytes);
    }
}

/// Bytes one element of an accessor takes.
double elementBytes(const json& a, const std::string& where) {
    const double component = count(a, "componentType", 5126, 6000, where);
    const int c = int(component);
    const double size = c == 5120 || c == 5121 ? 1 : c == 5122 || c == 5123 ? 2 : c == 5125 || c == 5126 ? 4 : 0;
    if (size == 0) throw InvalidArgument("the glTF's " + where + "/componentType " + std::to_string(c) + " is not one glTF defines");
    const std::string type = a.contains("type") && a["type"].is_string() ? a["type"].get<std::string>() : "SCALAR";
    const double n = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" || type == "MAT2" ? 4 : type == "MAT3" ? 9 : type == "MAT4" ? 16 : 0;
    if (n == 0) throw InvalidArgument("the glTF's " + where + "/type is not one glTF defines");
    return size * n;
}

/// Every accessor's element count, checked against the buffer view it reads.
std::vector<double> checkAccessors(const json& doc, const std::vector<double>& bufferBytes) {
    const json& views = arrayAt(doc, "bufferViews");
    std::vector<double> viewBytes, viewStride;
    for (size_t i = 0; i < views.size(); ++i) {
        const std::string where = "/bufferViews/" + std::to_string(i);
        const json& v = views[i];
        if (!v.is_object()) throw InvalidArgument("the glTF's " + where + " is not an object");
        const long b = indexAt(v, "buffer", bufferBytes.size(), where, "buffers");
        if (b < 0) throw InvalidArgument("the glTF's " + where + " names no buffer");
        const double offset = count(v, "byteOffset", 0, kMaxCount, where), bytes = count(v, "byteLength", 0, kMaxCount, where);
        if (offset + bytes > bufferBytes[size_t(b)])
            throw InvalidArgument("the glTF's " + where + " reads bytes " + std::to_string(uint64_t(offset)) + ".." +
                                  std::to_string(uint64_t(offset + bytes)) + " of a buffer of " + std::to_string(uint64_t(bufferBytes[size_t(b)])));
        viewBytes.push_back(bytes);
        viewStride.push_back(count(v, "byteStride", 0, 252, where));
    }
    const json& accessors = arrayAt(doc, "accessors");
    std::vector<double> counts;
    for (size_t i = 0; i < accessors.size(); ++i) {
        const std::string where = "/accessors/" + std::to_string(i);
        const json& a = accessors[i];
        if (!a.is_object()) throw InvalidArgument("the glTF's " + where + " is not an object");
        const double n = count(a, "count", 0, kMaxCount, where), element = elementBytes(a, where);
        const long v = indexAt(a, "bufferView", viewBytes.size(), where, "bufferViews");
        if (v >= 0 && n > 0) {
            const double stride = std::max(viewStride[size_t(v)], element);
            const double need = count(a, "byteOffset", 0, kMaxCount, where) + (n - 1) * stride + element;
            if (need > viewBytes[size_t(v)])
                throw InvalidArgument("the glTF's " + where + " reads " + std::to_string(uint64_t(need)) + " bytes of a buffer view of " +
                                      std::to_string(uint64_t(viewBytes[size_t(v)])));
        }
        counts.push_back(n);
    }
    return counts;
}

struct MeshSize {
    double vertices = 0, triangles = 0;
};

std::vector<MeshSize> meshSizes(const json& doc, const std::vector<double>& accessorCounts) {
    const json& meshes = arrayAt(doc, "meshes");
    std::vector<MeshSize> out;
    for (size_t m = 0; m < meshes.size(); ++m) {
        const std::string where = "/meshes/" + std::to_string(m);
        MeshSize size;
        const json& prims = meshes[m].is_object() ? arrayAt(meshes[m], "primitives") : json::array();
        for (size_t p = 0; p < prims.size(); ++p) {
            const std::string pw = where + "/primitives/" + std::to_string(p);
            const json& prim = prims[p];
            if (!prim.is_object() || !prim.contains("attributes") || !prim["attributes"].is_object())
                throw InvalidArgument("the glTF's " + pw + " has no attributes object");
            const long pos = indexAt(prim["attributes"], "POSITION", accessorCounts.size(), pw + "/attributes", "accessors");
            const long idx = indexAt(prim, "indices", accessorCounts.size(), pw, "accessors");
            const double mode = count(prim, "mode", 4, 6, pw);
            const double vertices = pos < 0 ? 0 : accessorCounts[size_t(pos)];
            const double corners = idx < 0 ? vertices : accessorCounts[size_t(idx)];
            size.vertices += vertices;
            size.triangles += mode == 4 ? corners / 3 : mode >= 5 ? std::max(corners - 2, 0.0) : 0;
        }
        out.push_back(size);
    }
    return out;
}

/// The node graph: nesting, cycles, and what expanding every reference would make, memoised
/// (never expanded). An explicit stack: no recursion a hostile depth could overflow.
void checkNodes(const json& doc, const std::vector<MeshSize>& meshes, const core::MeshLimits& limits, const GltfLimits& gltf) {
    const json& nodes = arrayAt(doc, "nodes");
    if (nodes.size() > gltf.maxExpandedNodes)
        throw LimitExceeded("the glTF has " + std::to_string(nodes.size()) + " nodes, over the limit of " + std::to_string(gltf.maxExpandedNodes));
    const size_t n = nodes.size();
    std::vector<std::vector<size_t>> children(n);
    std::vector<long> mesh(n, -1);
    std::vector<bool> isChild(n, false);
    for (size_t i = 0; i < n; ++i) {
        const std::string where = "/nodes/" + std::to_string(i);
        if (!nodes[i].is_object()) throw InvalidArgument("the glTF's " + where + " is not an object");
        mesh[i] = indexAt(nodes[i], "mesh", meshes.size(), where, "meshes");
        const json& c = nodes[i].contains("children") ? nodes[i]["children"] : json::array();
        if (!c.is_array()) throw InvalidArgument("the glTF's " + where + "/children is not an array");
        for (size_t k = 0; k < c.size(); ++k) {
            if (!c[k].is_number_integer() || c[k].get<int64_t>() < 0 || uint64_t(c[k].get<int64_t>()) >= n)
                throw InvalidArgument("the glTF's " + where + "/children/" + std::to_string(k) + " is not a node index");
            children[i].push_back(size_t(c[k].get<int64_t>()));
            isChild[children[i].back()] = true;
        }
    }
    struct Expanded {
        double nodes = 0, vertices = 0, triangles = 0;
        int depth = 0;
    };
    std::vector<Expanded> memo(n);
    std::vector<char> state(n, 0);  // 0 unvisited, 1 on the stack, 2 done
    const double cap = 1e300;
    for (size_t root = 0; root < n; ++root) {
        if (state[root] == 2) continue;
        std::vector<std::pair<size_t, size_t>> stack{{root, 0}};
        state[root] = 1;
        while (!stack.empty()) {
            auto& [node, next] = stack.back();
            if (next < children[node].size()) {
                const size_t c = children[node][next++];
                if (state[c] == 1)
                    throw InvalidArgument("the glTF's node " + std::to_string(c) + " is its own ancestor (the node graph has a cycle)");
                if (state[c] == 0) {
                    if (int(stack.size()) >= gltf.maxNodeDepth)
                        throw LimitExceeded("the glTF's nodes nest over " + std::to_string(gltf.maxNodeDepth) + " levels deep (the limit)");
                    state[c] = 1;
                    stack.push_back({c, 0});
                }
                continue;
            }
            Expanded e{1, 0, 0, 1};
            if (mesh[node] >= 0) e.vertices = meshes[size_t(mesh[node])].vertices, e.triangles = meshes[size_t(mesh[node])].triangles;
            for (size_t c : children[node]) {
                e.nodes = std::min(cap, e.nodes + memo[c].nodes);
                e.vertices = std::min(cap, e.vertices + memo[c].vertices);
                e.triangles = std::min(cap, e.triangles + memo[c].triangles);
                e.depth = std::max(e.depth, memo[c].depth + 1);
            }
            if (e.depth > gltf.maxNodeDepth)
                throw LimitExceeded("the glTF's nodes nest " + std::to_string(e.depth) + " levels deep, over the limit of " +
                                    std::to_string(gltf.maxNodeDepth));
            memo[node] = e;
            state[node] = 2;
            stack.pop_back();
        }
    }
    Expanded total;
    for (size_t i = 0; i < n; ++i) {
        if (isChild[i]) continue;  // every tree counted from its root (scenes list roots only)
        total.nodes += memo[i].nodes;
        total.vertices += memo[i].vertices;
        total.triangles += memo[i].triangles;
    }
    const auto over = [](double x, double limit) { return x > limit; };
    if (over(total.nodes, double(gltf.maxExpandedNodes)))
        throw LimitExceeded("the glTF's nodes reference each other into " + (total.nodes >= 1e15 ? std::string("over 10^15") : std::to_string(uint64_t(total.nodes))) +
                            " node copies, over the limit of " + std::to_string(gltf.maxExpandedNodes));
    if (over(total.vertices, double(limits.maxVertices)))
        throw LimitExceeded("the glTF's mesh instances hold " + (total.vertices >= 1e15 ? std::string("over 10^15") : std::to_string(uint64_t(total.vertices))) +
                            " vertices, over the limit of " + std::to_string(limits.maxVertices));
    if (over(total.triangles, double(limits.maxTriangles)))
        throw LimitExceeded("the glTF's mesh instances hold " + (total.triangles >= 1e15 ? std::string("over 10^15") : std::to_string(uint64_t(total.triangles))) +
                            " triangles, over the limit of " + std::to_string(limits.maxTriangles));
}

}  // namespace

void checkMeshUpload(const std::string& bytes, const std::string& format, const core::MeshLimits& limits, const GltfLimits& gltf) {
    if (format != "gltf" && format != "glb") return;
    size_t binBytes = 0;
    const std::string_view text = format == "glb" ? glbJson(bytes, binBytes) : std::string_view(bytes);
    if (const int depth = jsonDepth(text, gltf.maxJsonDepth); depth > gltf.maxJsonDepth)
        throw InvalidArgument("the glTF's JSON nests over " + std::to_string(gltf.maxJsonDepth) + " levels deep");
    const json doc = json::parse(text.begin(), text.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) throw InvalidArgument("the glTF's JSON does not parse as an object");
    for (const json& e : arrayAt(doc, "extensionsRequired")) {
        const std::string name = e.is_string() ? e.get<std::string>() : e.dump();
        if (!honoured(name))
            throw InvalidArgument("the glTF requires the extension " + name.substr(0, 80) +
                                  ", which this server does not read (export without it, e.g. without Draco compression)");
    }
    std::vector<double> bufferBytes;
    checkBuffers(doc, format == "glb", binBytes, bufferBytes);
    const std::vector<double> counts = checkAccessors(doc, bufferBytes);
    checkNodes(doc, meshSizes(doc, counts), limits, gltf);
}

}  // namespace volstyle::protocol

#include "server/http/route_table.h"

#include <algorithm>
#include <set>

namespace volstyle::server {

void RouteTable::add(const std::string& method, const std::string& pattern) { m_routes.push_back({{method, pattern}, std::regex(pattern)}); }

std::vector<std::string> RouteTable::methodsAt(const std::string& path) const {
    std::set<std::string> methods;
    for (const auto& [route, re] : m_routes)
        if (std::regex_match(path, re)) methods.insert(route.method);
    if (methods.empty()) return {};
    if (methods.count("GET")) methods.insert("HEAD");
    methods.insert("OPTIONS");
    return {methods.begin(), methods.end()};
}

std::vector<RouteEntry> RouteTable::entries() const {
    std::vector<RouteEntry> out;
    for (const auto& [route, re] : m_routes) out.push_back(route);
    return out;
}

namespace {

/// A collection of the API, what one of its members is called and the shape of its ids.
struct Collection {
    const char* segment;
    const char* noun;
    std::regex id;
};

std::vector<std::string> segmentsOf(const std::string& path) {
    std::vector<std::string> out;
    size_t start = 0;
    while (start <= path.size()) {
        const size_t end = std::min(path.find('/', start), path.size());
        if (end > start) out.push_back(path.substr(start, end - start));
        start = end + 1;
    }
    return out;
}

}  // namespace

std::string describeMissing(const std::string& method, const std::string& path) {
    static const std::vector<Collection> kCollections = {
        {"sessions", "session", std::regex("[0-9a-f]+")}, {"views", "view", std::regex("v[0-9]+")},
        {"jobs", "job", std::regex("[0-9a-f]+")},         {"frames", "frame", std::regex("-?[0-9]+(\\.vdb)?")},
        {"occluders", "occluder mesh", std::regex("[A-Za-z0-9_.-]{1,64}")}};
    const std::vector<std::string> segments = segmentsOf(path);
    std::string where;
    for (size_t i = 0; i + 1 < segments.size(); ++i) {
        for (const Collection& c : kCollections) {
            if (segments[i] != c.segment) continue;
            const std::string& id = segments[i + 1];
            if (!std::regex_match(id, c.id)) {
                const std::string shown = id.size() > 64 ? id.substr(0, 64) + "…" : id;
                return std::string("no ") + c.noun + " '" + shown + "'" + where;
            }
            where = std::string(" in ") + c.noun + " '" + id + "'";
        }
    }
    return "no route " + method + " " + path + " (the API's routes: GET /api/v1/openapi.json)";
}

}  // namespace volstyle::server

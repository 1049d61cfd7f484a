#pragma once
/// \file route_table.h
/// Every route the server answers, by method and path pattern, as registered: the error handler
/// answers 405 with `Allow` from it where a path has routes under other methods (SPEC §10), and
/// the OpenAPI test compares it with the document.

#include <regex>
#include <string>
#include <vector>

namespace volstyle::server {

struct RouteEntry {
    std::string method;   ///< GET, POST, PUT, DELETE
    std::string pattern;  ///< the regular expression cpp-httplib matches the whole path against
};

class RouteTable {
public:
    void add(const std::string& method, const std::string& pattern);
    /// The methods some route answers at `path`, for `Allow`: sorted, HEAD where GET is, and
    /// OPTIONS; empty when no route has this path.
    std::vector<std::string> methodsAt(const std::string& path) const;
    std::vector<RouteEntry> entries() const;

private:
    std::vector<std::pair<RouteEntry, std::regex>> m_routes;
};

/// For a path no route has: what is missing, as a 404 message ("no session 'nope'", naming the
/// first id that cannot be one), or "no route METHOD PATH".
std::string describeMissing(const std::string& method, const std::string& path);

}  // namespace volstyle::server

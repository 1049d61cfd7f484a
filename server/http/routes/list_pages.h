#pragma once
/// \file list_pages.h
/// One page of a list (GET /sessions, GET /jobs; SPEC §10): the items after the cursor, in a
/// stable order, at most `limit`, and `Link: <…>; rel="next"` (with the same cursor in
/// `X-Next-Cursor`) while more remain. A cursor is the hex of the last item's sort key, so a page
/// stays right when items before it are deleted.

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "protocol/requests.h"
#include "protocol/validation.h"

namespace volstyle::server {

inline std::string hexOf(const std::string& text) {
    static const char* digits = "0123456789abcdef";
    std::string out;
    for (unsigned char c : text) out += digits[c >> 4], out += digits[c & 15];
    return out;
}

inline std::string textOfHex(const std::string& hex) {
    std::string out;
    for (size_t i = 0; i + 1 < hex.size(); i += 2) out += char(std::stoi(hex.substr(i, 2), nullptr, 16));
    return out;
}

/// `keyed`: each item's JSON under its sort key (any order). Answers the page as a JSON array.
inline void replyPage(httplib::Response& res, std::vector<std::pair<std::string, nlohmann::json>> keyed, const protocol::ListQuery& q,
                      const std::string& path, const std::string& filter = "") {
    std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const std::string after = textOfHex(q.cursor);
    auto first = q.cursor.empty() ? keyed.begin()
                                  : std::upper_bound(keyed.begin(), keyed.end(), after, [](const std::string& k, const auto& e) { return k < e.first; });
    nlohmann::json page = nlohmann::json::array();
    auto it = first;
    for (; it != keyed.end() && int(page.size()) < q.limit; ++it) page.push_back(std::move(it->second));
    if (it != keyed.end()) {
        const std::string next = hexOf(std::prev(it)->first);
        res.set_header("Link", "<" + path + "?limit=" + std::to_string(q.limit) + "&cursor=" + next + filter + ">; rel=\"next\"");
        res.set_header("X-Next-Cursor", next);
    }
    res.status = 200;
    res.set_content(protocol::toText(page), "application/json");
}

}  // namespace volstyle::server

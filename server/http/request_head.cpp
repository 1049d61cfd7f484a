#include "server/http/request_head.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <iterator>
#include <string_view>

namespace volstyle::server {
namespace {

bool isTokenChar(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("!#$%&'*+-.^_`|~", c) != nullptr;
}

/// `text` cut to 60 characters with control and non-ASCII bytes as '?', for messages.
std::string printable(std::string_view text) {
    std::string out;
    for (char c : text.substr(0, 60)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
    return text.size() > 60 ? out + "…" : out;
}

}  // namespace

std::string checkRequestHead(const std::string& head, const ConnectionLimits& limits, Refusal& why) {
    if (head.size() > limits.maxHeadBytes) {
        why = Refusal::HeadTooLarge;
        return "the request's head is over " + std::to_string(limits.maxHeadBytes) + " bytes (the limit)";
    }
    why = Refusal::MalformedRequest;
    const size_t lineEnd = head.find("\r\n");
    const std::string_view line = std::string_view(head).substr(0, lineEnd);
    const size_t sp1 = line.find(' '), sp2 = sp1 == std::string_view::npos ? sp1 : line.find(' ', sp1 + 1);
    if (sp2 == std::string_view::npos || line.find(' ', sp2 + 1) != std::string_view::npos)
        return "the request line '" + printable(line) + "' is not 'METHOD /path HTTP/1.1'";
    const std::string_view method = line.substr(0, sp1), target = line.substr(sp1 + 1, sp2 - sp1 - 1),
                           version = line.substr(sp2 + 1);
    static const char* const kMethods[] = {"GET", "HEAD", "POST", "PUT", "DELETE", "OPTIONS", "PATCH"};
    if (std::find(std::begin(kMethods), std::end(kMethods), method) == std::end(kMethods))
        return "the method '" + printable(method) + "' is not one this API serves (GET, HEAD, POST, PUT, DELETE, OPTIONS, PATCH)";
    if (version != "HTTP/1.1" && version != "HTTP/1.0") return "the protocol '" + printable(version) + "' is not HTTP/1.1 or HTTP/1.0";
    if (target.size() > limits.maxTargetBytes) {
        why = Refusal::TargetTooLong;
        return "the request target is " + std::to_string(target.size()) + " bytes, over the limit of " +
               std::to_string(limits.maxTargetBytes);
    }
    if (target.empty() || target[0] != '/') return "the request target '" + printable(target) + "' does not start with '/'";
    for (char c : target)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return "the request target holds a control character";
    std::string path(target.substr(0, target.find('?')));
    for (char& c : path) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (path.find("%00") != std::string::npos) return "the path holds an encoded NUL (%00)";
    if (path.find("%2f") != std::string::npos || path.find("%5c") != std::string::npos)
        return "the path holds an encoded '/' or '\\' (%2F, %5C): no id or file name holds one";
    int headers = 0;
    for (size_t at = lineEnd + 2; at < head.size();) {
        const size_t end = head.find("\r\n", at);
        if (end == std::string::npos || end == at) break;  // the blank line ends the head
        const std::string_view h = std::string_view(head).substr(at, end - at);
        const size_t colon = h.find(':');
        if (colon == std::string_view::npos || colon == 0 ||
            !std::all_of(h.begin(), h.begin() + long(colon), isTokenChar))
            return "the header line '" + printable(h) + "' is not 'Name: value'";
        if (++headers > limits.maxHeaderCount) {
            why = Refusal::HeadTooLarge;
            return "the request has over " + std::to_string(limits.maxHeaderCount) + " headers (the limit)";
        }
        at = end + 2;
    }
    return {};
}

}  // namespace volstyle::server

#pragma once
/// \file request_head.h
/// The check of a request's head before cpp-httplib parses it (issue #35): cpp-httplib 0.11.4
/// answers a malformed request line 400 but keeps the connection and reads the rest of the head as
/// new requests (two or three status lines for one request), accepts any number of headers, and
/// decodes %00 and %2F into the path it routes. Here the request line, the method, the protocol,
/// the path's encoded NUL and '/', and the header lines' count, size and shape are checked.

#include <string>

#include "server/http/connection_limits.h"

namespace volstyle::server {

/// Checks a request's head (request line and headers, up to and including the blank line) as
/// GuardedHttpServer does before parsing; empty when it may be parsed, else the refusal's detail
/// with `why` set. Pure, for tests.
std::string checkRequestHead(const std::string& head, const ConnectionLimits& limits, Refusal& why);

}  // namespace volstyle::server

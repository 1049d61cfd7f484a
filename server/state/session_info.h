#pragma once
/// \file session_info.h
/// A session's state as the API describes it (protocol/response_values.h): what the routes
/// encode with protocol/response_json.h.

#include <vector>

#include "protocol/response_values.h"
#include "server/state/session_store.h"

namespace volstyle::server {

protocol::SessionInfo sessionInfo(Session& s);  ///< takes the session's lock
protocol::SessionInfo sessionInfoLocked(const Session& s);  ///< the caller holds the session's lock
protocol::ViewInfo viewInfo(const SessionView& v);
std::vector<protocol::ViewInfo> viewInfos(Session& s);    ///< takes the session's lock
std::vector<protocol::FrameInfo> frameInfos(Session& s);  ///< takes the session's lock

}  // namespace volstyle::server

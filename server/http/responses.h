#pragma once
/// \file responses.h
/// The JSON answers for sessions and views (SPEC §3): {"id","created","scene","volume":{…},
/// "lighting","views","jobs"} and {"id","camera","has_target","has_weights","has_background"}.

#include <nlohmann/json.hpp>

#include "server/state/session_store.h"

namespace volstyle::server {

nlohmann::json sessionJson(Session& s);  ///< takes the session's lock
nlohmann::json viewJson(const SessionView& v);
nlohmann::json viewsJson(const Session& s);  ///< call with the session's lock held

}  // namespace volstyle::server

#pragma once
/// \file job_json.h
/// Jobs at the door (SPEC §3 jobs): GET /jobs/{jid}, and the data of each event of
/// GET /jobs/{jid}/events, from the values of job_values.h.

#include <nlohmann/json.hpp>

#include "protocol/job_values.h"

namespace volstyle::protocol {

nlohmann::json jobProgressToJson(const JobProgress& p);
nlohmann::json jobResultToJson(const JobResult& r);
/// {"code", "message", "details", "request_id": ""} (a job's error belongs to no request).
nlohmann::json jobErrorToJson(const JobError& e);
JobError jobErrorFromJson(const nlohmann::json& j);
nlohmann::json jobToJson(const JobInfo& job);
nlohmann::json jobEventDataToJson(const JobEventData& e);

}  // namespace volstyle::protocol

#include "server/store/job_record.h"

#include "protocol/job_json.h"
#include "protocol/validation.h"

namespace volstyle::server::store {

using json = nlohmann::json;

std::string encodeJobRecord(const Job& job) {
    std::lock_guard lock(job.mutex);
    const json j = {{"format", 1},      {"id", job.id},           {"session", job.session}, {"state", protocol::jobStateName(job.state)},
                    {"progress", protocol::jobProgressToJson(job.progress)}, {"result", protocol::jobResultToJson(job.result)},
                    {"error", job.error ? protocol::jobErrorToJson(*job.error) : json(nullptr)}};
    return protocol::toText(j, 2);
}

bool readJobRecord(const std::string& text, Job& job) {
    const json j = json::parse(text);
    if (j.value("format", 1) != 1) throw std::runtime_error("the record's format " + j.at("format").dump() + " is newer than this server's (1)");
    std::lock_guard lock(job.mutex);
    if (job.id.empty()) job.id = j.at("id");  // read without the lock elsewhere: set once
    if (job.session.empty()) job.session = j.at("session");
    const std::string state = j.at("state");
    job.state = protocol::jobStateFromName(state).value_or(protocol::JobState::Running);
    // A finished job's progress and result are replayed as they were answered (see RecordedJobBody).
    if (const json& p = j.at("progress"); !p.empty()) job.progress = protocol::RecordedJobBody{p.dump()};
    if (const json& r = j.at("result"); !r.is_null()) job.result = protocol::RecordedJobBody{r.dump()};
    if (const json& e = j.at("error"); !e.is_null()) job.error = protocol::jobErrorFromJson(e);
    return job.isFinished();
}

std::shared_ptr<Job> decodeJobRecord(const std::string& text, bool& interrupted) {
    auto job = std::make_shared<Job>();
    interrupted = !readJobRecord(text, *job);
    if (interrupted)
        job->fail(protocol::JobState::Failed, protocol::ErrorCode::Interrupted,
                  "the server stopped while this job was " + std::string(protocol::jobStateName(job->state)) +
                      "; the volume keeps its last committed version");
    job->emitFinal();
    return job;
}

std::string encodeJobEvent(const protocol::JobEventData& e) { return protocol::toText(protocol::jobEventDataToJson(e)); }

std::optional<protocol::JobEventData> decodeJobEvent(const std::string& name, const std::string& data) {
    for (const auto& [event, eventName] : protocol::kJobEvents)
        if (name == eventName && !protocol::isFinal(event))
            return protocol::JobEventData{event, protocol::JobProgress{protocol::RecordedJobBody{data}}};
    return std::nullopt;
}

}  // namespace volstyle::server::store

#include "protocol/job_json.h"

#include "protocol/error_body.h"
#include "protocol/render_json.h"
#include "protocol/solve_json.h"

namespace volstyle::protocol {
namespace {

using json = nlohmann::json;

template <class... F>
struct Visitor : F... {
    using F::operator()...;
};
template <class... F>
Visitor(F...) -> Visitor<F...>;

json recorded(const RecordedJobBody& r) { return json::parse(r.json); }

json toJson(const SolveJobProgress& p) {
    json j = solveProgressToJson(p.solve);
    if (!p.block.empty()) j["block"] = p.block;
    if (p.round > 0) j["round"] = p.round;
    return j;
}
json toJson(const AnimateJobProgress& p) {
    return {{"sweep", p.sweep}, {"sweeps", p.sweeps}, {"key_frame", p.keyFrame}, {"step", p.step}, {"steps", p.steps}};
}
json toJson(const FramesRenderJobProgress& p) {
    return {{"frame", p.frame}, {"done", p.done}, {"frames", p.frames}, {"url", p.url}};
}
json toJson(const SequenceJobProgress& p) {
    return {{"frame", p.frame}, {"frames", p.frames}, {"time", p.time}, {"url", p.url}, {"render_ms", p.renderMs}};
}

json toJson(const SolveJobResult& r) { return {{"version", r.version}, {"report", solveReportToJson(r.report)}}; }
json toJson(const LightsJobResult& r) {
    json j;
    if (r.rounds) {
        j["rounds"] = *r.rounds;
        j["rms_history"] = r.rmsHistory;
        j["total_ms"] = r.totalMs;
    }
    if (r.report) {
        j["report"] = solveReportToJson(*r.report);
        j["light_volumes"] = {{"ms", r.lightVolumeMs}, {"bytes", r.lightVolumeBytes}};
    }
    j["version"] = r.version;
    j["lighting"] = lightingToJson(r.lighting, r.sessionMap.get());
    j["environment_url"] = r.environmentUrl;
    return j;
}
json toJson(const AnimateJobResult& r) {
    return {{"key_frames", r.keyFrames}, {"frames", r.frames}, {"change_per_sweep", r.changePerSweep}};
}
json toJson(const FramesRenderJobResult& r) { return {{"frames", r.frames}, {"frame_urls", r.frameUrls}}; }
json toJson(const SequenceJobResult& r) {
    json j = {{"frames", r.frames}, {"fps", r.fps}, {"start", r.start}, {"end", r.end}, {"frame_urls", r.frameUrls},
              {"render_ms", r.renderMs}};
    if (r.videoUrl) j["video_url"] = *r.videoUrl;
    return j;
}

json toJson(const PreviewEvent& e) {
    json urls = json::object();
    for (const auto& [view, url] : e.urls) urls[view] = url;
    return {{"iteration", e.iteration}, {"urls", urls}};
}

}  // namespace

json jobProgressToJson(const JobProgress& p) {
    return std::visit(Visitor{[](std::monostate) { return json::object(); },
                                 [](const RecordedJobBody& r) { return recorded(r); },
                                 [](const auto& v) { return toJson(v); }},
                      p);
}

json jobResultToJson(const JobResult& r) {
    return std::visit(Visitor{[](std::monostate) { return json(nullptr); },
                                 [](const RecordedJobBody& b) { return recorded(b); },
                                 [](const auto& v) { return toJson(v); }},
                      r);
}

json jobErrorToJson(const JobError& e) { return errorBody(e.code, e.message, e.details, "")["error"]; }

JobError jobErrorFromJson(const json& j) {
    JobError e{errorCodeFromName(j.at("code").get<std::string>()), j.at("message").get<std::string>(), {}};
    for (const auto& d : j.value("details", json::array())) e.details.push_back({d.at("path"), d.at("message")});
    return e;
}

json jobToJson(const JobInfo& job) {
    return {{"id", job.id},
            {"session", job.session},
            {"state", jobStateName(job.state)},
            {"progress", jobProgressToJson(job.progress)},
            {"result", jobResultToJson(job.result)},
            {"error", job.error ? jobErrorToJson(*job.error) : json(nullptr)}};
}

json jobEventDataToJson(const JobEventData& e) {
    return std::visit(Visitor{[](const JobProgress& p) { return jobProgressToJson(p); },
                                 [](const PreviewEvent& p) { return toJson(p); },
                                 [](const JobInfo& j) { return jobToJson(j); }},
                      e.data);
}

}  // namespace volstyle::protocol

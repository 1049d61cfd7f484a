// Jobs: POST /sessions/{sid}/solve, GET/DELETE /jobs/{jid}, GET …/events (SSE),
// GET …/preview/{vid}.png; a sequence's GET …/frames/{i}.png and …/video.mp4.
#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>

#include "protocol/job_json.h"
#include "server/http/routes/list_pages.h"
#include "server/http/routes/route_context.h"
#include "server/runtime/video_encoder.h"

namespace volstyle::server {
namespace {

/// How long an event stream waits for news before checking whether its client is still there.
constexpr auto kEventPoll = std::chrono::milliseconds(500);

/// Ends a chunked answer. cpp-httplib writes the last chunk from a function-local static string
/// built on the first end; its initialisation guard is inside the uninstrumented library, so
/// ThreadSanitizer saw two streams ending at once as a race on that string. The first end runs
/// under std::call_once, whose completion every later end synchronises with (only the first end
/// can wait, and only for that one write).
void endChunkedAnswer(httplib::DataSink& sink) {
    static std::once_flag first;
    bool ended = false;
    std::call_once(first, [&] {
        sink.done();
        ended = true;
    });
    if (!ended) sink.done();
}

/// Streams a job's events from the first: every one written so far, then each as it comes; the
/// stream ends after the final event (the job's state flips before that event is queued, so the
/// events decide, not the state).
/// While nothing happens, a comment line every `keepAliveSeconds`.
void streamEvents(httplib::Response& res, std::shared_ptr<Job> job, JobService& jobs, StreamLimiter& streams, const std::string& client,
                  double keepAliveSeconds) {
    const auto keepAlive = std::chrono::duration<double>(keepAliveSeconds);
    streams.acquire(client);  // released when the response is destroyed, however the stream ends
    res.set_header("Cache-Control", "no-cache");
    res.set_chunked_content_provider("text/event-stream", [job, &jobs, keepAlive, sent = size_t(0), last = std::chrono::steady_clock::now()](
                                                              size_t, httplib::DataSink& sink) mutable {
        std::unique_lock lock(job->mutex);
        if (!job->changed.wait_for(lock, kEventPoll, [&] { return job->events.size() > sent; }) && job->remote) {
            // Another replica runs it: its events come as notifications, and one lost (the
            // listener reconnecting) must not leave the stream waiting for an end it missed.
            lock.unlock();
            try {
                jobs.refresh(*job);
            } catch (const std::exception&) {
                // The store is unreachable now: the stream waits, and asks again.
            }
            lock.lock();
        }
        bool final = false;
        if (sent == job->events.size() && std::chrono::steady_clock::now() - last >= keepAlive) {
            // A phase without events (a large solve's set-up): a comment line keeps proxies and
            // clients' read timeouts from closing a stream that is only quiet.
            lock.unlock();
            if (!sink.write(": keep-alive\n\n", 14)) return false;
            last = std::chrono::steady_clock::now();
            return true;
        }
        if (sent < job->events.size()) last = std::chrono::steady_clock::now();
        while (sent < job->events.size()) {
            const protocol::JobEventData& e = job->events[sent++];
            final = protocol::isFinal(e.event);
            std::string message = std::string("event: ") + protocol::jobEventName(e.event) + "\ndata: " +
                                  protocol::toText(protocol::jobEventDataToJson(e)) + "\n\n";
            lock.unlock();
            if (!sink.write(message.data(), message.size())) return false;  // the client left
            lock.lock();
        }
        if (final) {
            lock.unlock();
            endChunkedAnswer(sink);
        }
        return true;
    }, [&streams, client](bool) { streams.release(client); });
}

/// A job's file to download (frames and videos are small enough to send whole).
void replyFile(const httplib::Request& req, httplib::Response& res, const std::filesystem::path& path, const char* mime) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    replyDownload(req, res, std::move(bytes), mime, path.filename().string());
}

}  // namespace

void addJobRoutes(RouteContext& c) {
    c.postCreating(kSessionPath + "/solve", [&c](const httplib::Request& req, httplib::Response& res) {
        auto s = c.services.sessions.find(req.matches[1]);
        const nlohmann::json body = c.body(req);
        const Vec3d background = c.services.sessions.lighting(*s).background.color;  // offered when L_m is left out
        const protocol::SolveRequest request = protocol::SolveRequest::fromJson(body, c.limits, &background);
        reply(res, 202, {{"job", c.services.jobs.startSolve(s, request.options, JobOrigin{"solve", protocol::toText(body), nullptr})->id}});
    });
    // Run again on this replica when the one solving it died (the job queue).
    c.services.jobs.addResumer("solve", [&c](const JobOrigin& o, const std::shared_ptr<Session>& s) {
        const Vec3d background = c.services.sessions.lighting(*s).background.color;
        c.services.jobs.startSolve(s, protocol::SolveRequest::fromJson(nlohmann::json::parse(o.request), c.limits, &background).options, o);
    });
    c.get(kApi + "/jobs", [&c](const httplib::Request& req, httplib::Response& res) {
        const protocol::ListQuery q = protocol::ListQuery::fromQuery(req.params, true);
        if (!q.session.empty()) (void)c.services.sessions.find(q.session);  // 404 names an unknown session
        std::vector<std::pair<std::string, nlohmann::json>> keyed;
        for (const auto& job : c.services.jobs.all()) {
            const protocol::JobInfo info = job->info();
            if (!q.session.empty() && info.session != q.session) continue;
            keyed.emplace_back(fmt::format("{:016x}", job->sequence), protocol::jobToJson(info));  // oldest first
        }
        replyPage(res, std::move(keyed), q, kApi + "/jobs", q.session.empty() ? "" : "&session=" + q.session);
    });
    c.get(kJobPath, [&c](const httplib::Request& req, httplib::Response& res) {
        reply(res, 200, protocol::jobToJson(c.services.jobs.job(req.matches[1])->info()));
    });
    c.del(kJobPath, [&c](const httplib::Request& req, httplib::Response& res) {
        auto job = c.services.jobs.job(req.matches[1]);
        c.services.jobs.cancel(*job);
        reply(res, 202, protocol::jobToJson(job->info()));
    });
    c.get(kJobPath + "/events", [&c](const httplib::Request& req, httplib::Response& res) {
        streamEvents(res, c.services.jobs.job(req.matches[1]), c.services.jobs, c.streams, req.remote_addr, c.eventKeepAliveSeconds);
    });
    // A sequence job's files (issue #15): its frames and its video.
    c.get(kJobPath + R"(/frames/([0-9]{1,6})\.png)", [&c](const httplib::Request& req, httplib::Response& res) {
        replyFile(req, res, c.services.jobs.jobFile(req.matches[1], sequenceFrameName(std::stoul(req.matches[2]))), "image/png");
    });
    c.get(kJobPath + R"(/video\.mp4)", [&c](const httplib::Request& req, httplib::Response& res) {
        replyFile(req, res, c.services.jobs.jobFile(req.matches[1], "video.mp4"), "video/mp4");
    });
    c.get(kJobPath + R"(/preview/(v[0-9]+)\.png)", [&c](const httplib::Request& req, httplib::Response& res) {
        replyImage(res, c.services.volumes.renderPreview(req.matches[1], req.matches[2]), protocol::ImageFormat::Png);
    });
}

}  // namespace volstyle::server

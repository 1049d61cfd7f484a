// ServiceContext's jobs: queue, run and finish one, write its record (the data folder, and with
// a PostgreSQL store the job queue's row), forget old ones, and — with the queue — the copies of
// jobs other replicas run (their state read from the queue, their events from its notifications).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <thread>

#include "protocol/error_body.h"
#include "server/service/service_context.h"
#include "server/store/job_record.h"

namespace volstyle::server {
namespace {

bool isRemote(const Job& j) {
    std::lock_guard lock(j.mutex);
    return j.remote;
}

}  // namespace

void ServiceContext::saved(Job& j) {
    std::lock_guard lock(jobRecords);
    if (j.forgotten || isRemote(j)) return;
    if (persist) persist->saveJob(j);
    if (!queue) return;
    std::string state;
    {
        std::lock_guard jl(j.mutex);
        state = protocol::jobStateName(j.state);
    }
    if (!queue->write(j.id, state, store::encodeJobRecord(j))) loseJob(j, "another replica took it over (its lease lapsed here)");
}

void ServiceContext::loseJob(Job& j, const std::string& why) {
    {
        // A remote copy from now on: it writes, relays and prunes nothing of the row.
        std::lock_guard lock(j.mutex);
        if (j.remote) return;
        j.remote = true;
        j.relay = nullptr;
    }
    j.cancel = true;
    spdlog::warn("job {}: {}; stopping this copy", j.id, why);
}

void ServiceContext::pruneJobs() {
    std::error_code ec;
    for (const auto& j : jobs.prune(limits.finishedJobsKept)) {
        const bool remote = isRemote(*j);
        {
            std::lock_guard lock(jobRecords);
            j->forgotten = true;
            try {
                if (persist && !remote) persist->removeJob(j->id);
                else if (!persist) std::filesystem::remove_all(jobFilesDir(j->id), ec);
                if (queue && !remote) queue->remove(j->id);
            } catch (const std::exception& e) {
                spdlog::warn("job {}: its record or files stay in the store: {}", j->id, e.what());
            }
        }
        if (auto s = sessions.find(j->session)) {
            std::lock_guard lock(s->mutex);
            std::erase(s->jobs, j->id);
        }
        std::shared_ptr<core::GpuVolume> preview;
        {
            std::lock_guard lock(j->mutex);
            preview = std::move(j->preview);
        }
        release(std::move(preview));
    }
}

std::shared_ptr<Job> ServiceContext::job(const std::string& id) {
    auto j = jobs.find(id);
    if (queue && SessionStore::isStoreId(id) && (!j || isRemote(*j))) j = remoteJob(id, std::move(j));
    if (!j) throw ApiError(ErrorCode::NotFound, "no job '" + id + "'");
    return j;
}

std::shared_ptr<Job> ServiceContext::remoteJob(const std::string& id, std::shared_ptr<Job> held) {
    const std::optional<std::string> record = queue->record(id);
    if (!record) return nullptr;  // none, or pruned by the replica that ran it
    if (held) {
        refreshRemote(*held, *record);
        return held;
    }
    std::lock_guard lock(remoteCopies);  // one copy per job: a stream must watch the copy lookups refresh
    if (auto again = jobs.find(id)) {
        refreshRemote(*again, *record);
        return again;
    }
    auto j = std::make_shared<Job>();
    j->remote = true;
    const bool finished = store::readJobRecord(*record, *j);
    // A stream opened here starts where the job is: its latest progress, then what comes.
    if (!std::holds_alternative<std::monostate>(j->progress)) j->events.push_back({protocol::JobEvent::Progress, j->progress});
    if (finished) j->emitFinal();
    auto kept = jobs.insertIfAbsent(j);  // a claim may have made it local meanwhile
    pruneJobs();                         // a replica that only reads keeps finishedJobsKept copies too
    return kept;
}

void ServiceContext::refreshRemote(Job& j) {
    if (!queue || !isRemote(j)) return;
    if (const auto record = queue->record(j.id)) return refreshRemote(j, *record);
    {
        std::lock_guard lock(j.mutex);
        if (j.isFinished()) return;
    }
    // Its row is gone (pruned by the replica that ran it): the copy ends, and its streams with it.
    j.fail(JobState::Failed, protocol::ErrorCode::NotFound, "the job is no longer in the store (the replica that ran it forgot it)");
    j.emitFinal();
}

void ServiceContext::refreshRemote(Job& j, const std::string& record) {
    bool wasFinished = false;
    {
        std::lock_guard lock(j.mutex);
        if (!j.remote) return;  // claimed here meanwhile: the row is this replica's to write
        wasFinished = j.isFinished();
    }
    if (store::readJobRecord(record, j) && !wasFinished) j.emitFinal();
}

void ServiceContext::onQueueNotice(const std::string& id, const std::string& what, const std::string& data) {
    auto j = jobs.find(id);
    if (!j) return;
    const bool remote = isRemote(*j);
    if (what == "cancel") {
        if (!remote) j->cancel = true;  // DELETE /jobs/{jid} was asked of another replica
        return;
    }
    if (!remote) return;
    if (what == "state") return refreshRemote(*j);
    if (auto event = store::decodeJobEvent(what, data)) {
        {
            std::lock_guard lock(j->mutex);
            if (j->isFinished()) return;  // a late event: the copy has its end already
            if (event->event == protocol::JobEvent::Progress) j->progress = std::get<protocol::JobProgress>(event->data);
        }
        j->emit(std::move(*event));
    }
}

void ServiceContext::checkLeases(const std::vector<std::shared_ptr<Job>>& running, const std::vector<HeldLease>& held) {
    for (const auto& j : running) {
        auto it = std::find_if(held.begin(), held.end(), [&](const HeldLease& h) { return h.id == j->id; });
        if (it == held.end()) {
            {
                std::lock_guard lock(j->mutex);
                if (j->isFinished()) continue;  // it finished meanwhile: its row holds no lease
            }
            loseJob(*j, "its lease went to another replica");
        } else if (it->cancel) {
            j->cancel = true;
        }
    }
}

void ServiceContext::cancelJob(Job& j) {
    if (isRemote(j) && queue) {
        if (!queue->requestCancel(j.id)) throw ApiError(ErrorCode::NotFound, "no job '" + j.id + "'");
        return refreshRemote(j);
    }
    j.cancel = true;
}

void ServiceContext::relayEvents(Job& j) {
    if (!queue) return;
    j.setRelay([this, id = j.id](const protocol::JobEventData& e) {
        try {
            queue->publish(id, protocol::jobEventName(e.event), store::encodeJobEvent(e));
        } catch (const std::exception& ex) {
            spdlog::debug("job {}: an event was not sent to other replicas: {}", id, ex.what());
        }
    });
}

std::shared_ptr<Job> ServiceContext::queueJob(Session& s, const JobOrigin& origin) {
    if (origin.adopted) return origin.adopted;
    checkJobQueue(s);
    pruneJobs();
    auto job = jobs.add(s.id);
    try {
        if (queue) {
            relayEvents(*job);
            queue->add(job->id, s.id, origin.kind, origin.request, "queued", store::encodeJobRecord(*job));
        }
        if (persist) persist->saveJob(*job);
        std::lock_guard lock(s.mutex);
        s.jobs.push_back(job->id);
        saved(s);
    } catch (...) {
        // Not acknowledged: nothing of it stays (a queued job left here would be leased forever).
        jobs.remove(job->id);
        try {
            if (queue) queue->remove(job->id);
        } catch (const std::exception&) {
            // Its row lapses and is claimed, then fails: its session's record does not name it.
        }
        throw;
    }
    spdlog::info("job {} queued (session {})", job->id, s.id);
    return job;
}

std::shared_ptr<Job> ServiceContext::adoptJob(const ClaimedJob& c) {
    auto job = jobs.adopt(c.id, c.session);
    relayEvents(*job);
    try {
        saved(*job);  // queued again, under this replica's lease
    } catch (...) {
        loseJob(*job, "its claim could not be written");  // not renewed here: claimed again once it lapses
        throw;
    }
    spdlog::warn("job {} claimed from {} (attempt {}): its lease lapsed there", c.id, c.previousOwner, c.attempt);
    return job;
}

void ServiceContext::checkJobQueue(const Session& s) const {
    if (jobs.pending(s.id) >= limits.maxQueuedJobs)
        throw ApiError(ErrorCode::TooManyJobs, "session '" + s.id + "' already has " + std::to_string(limits.maxQueuedJobs) +
                                                   " queued jobs (the limit); wait or cancel one");
}

void ServiceContext::runJob(Job& job, const std::function<void()>& work) {
    if (job.cancel) {
        job.fail(JobState::Cancelled, protocol::ErrorCode::Cancelled, "cancelled before it started");
        return;
    }
    job.setState(JobState::Running);
    saved(job);
    spdlog::info("job {} running", job.id);
    try {
        work();
    } catch (...) {
        const protocol::ErrorReport e = protocol::describeException(std::current_exception());
        job.fail(e.code == protocol::ErrorCode::Cancelled ? JobState::Cancelled : JobState::Failed, e.code, e.message, e.details);
    }
}

void ServiceContext::finishJob(Job& job) {
    JobState state;
    {
        std::lock_guard lock(job.mutex);
        state = job.state;
    }
    spdlog::info("job {} {}", job.id, protocol::jobStateName(state));
    // A store that blinks must not make another replica run a finished job again: the end is
    // tried three times (0.5 and 1 s apart) before it is left to the lease.
    for (int attempt = 1;; ++attempt) {
        try {
            if (queue && persist && !isRemote(job)) persist->saveJobFiles(job.id);  // before the record says done
            saved(job);
            break;
        } catch (const std::exception& e) {
            if (!queue || attempt == 3) {
                spdlog::error("job {}: cannot record its end: {}", job.id, e.what());
                break;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(500 * attempt));
        }
    }
    job.emitFinal();
}

}  // namespace volstyle::server

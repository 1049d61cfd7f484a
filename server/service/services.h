#pragma once
/// \file services.h
/// The session services on one shared context (issue #36): what the HTTP routes call. Each is a
/// small class taking and returning core and protocol values (no JSON); the context holds what
/// they share (service_context.h).

#include <memory>
#include <string>

#include "server/service/job_queue_runner.h"
#include "server/service/job_service.h"
#include "server/service/sessions_service.h"
#include "server/service/stylizer_service.h"
#include "server/service/viewport_service.h"
#include "server/service/volume_service.h"

namespace volstyle::server {

struct Services {
    /// Restores sessions and jobs from `dataDir` (empty: in memory only); GL work goes to `gl`
    /// (none: its own GL thread).
    Services(ServiceLimits limits, const std::string& dataDir, std::unique_ptr<GlExecutor> gl = nullptr)
        : context(std::move(limits), dataDir, std::move(gl)) {}
    /// The job queue's threads, then the GL thread stop before the services go: the work queued
    /// for them calls into the services.
    ~Services() {
        queueRunner.reset();
        context.shutdown();
    }
    /// Stops the job queue's threads (before the routes, whose resumers they call, go).
    void stopJobQueue() { queueRunner.reset(); }
    /// With a PostgreSQL store: this replica's part in the job queue (job_queue_runner.h), from
    /// now on. Call once the routes are set (their resumers with them).
    void startJobQueue() {
        if (context.queue && !queueRunner) queueRunner = std::make_unique<JobQueueRunner>(context, [this](const ClaimedJob& c) { jobs.resume(c); });
    }
    Services(const Services&) = delete;
    Services& operator=(const Services&) = delete;

    ServiceContext context;
    SessionsService sessions{context};
    VolumeService volumes{context};
    ViewportService viewport{context, volumes};
    StylizerService stylizer{context};
    JobService jobs{context};
    std::unique_ptr<JobQueueRunner> queueRunner;
};

}  // namespace volstyle::server

#pragma once
/// \file job_values.h
/// What a job reports, as values (issue #36: "job results are typed"). Each kind of job — a
/// volume solve, a light solve, key-frame animation, a frames render, a stylizer sequence — has
/// its progress and its result; a solve also streams preview events. The services fill these in,
/// the HTTP routes encode them with job_json.h (SPEC §3 jobs), and the job record stores that
/// encoding.

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "core/image/image.h"
#include "core/scene/lighting.h"
#include "core/scene/solve_options.h"
#include "protocol/error_code.h"
#include "protocol/vocabulary.h"

namespace volstyle::protocol {

/// An iteration of a volume or light solve. A light solve names its block ("lights", or in a
/// combined solve "lights"/"volume") and, when combined, its round (1-based; 0 = none).
struct SolveJobProgress {
    core::SolveProgress solve;
    std::string block;
    int round = 0;
};
/// A step of key-frame animation: sweep `sweep` of `sweeps`, solving key frame `keyFrame`.
struct AnimateJobProgress {
    int sweep = 0, sweeps = 0, keyFrame = 0, step = 0, steps = 0;
};
/// A frame of POST …/frames/render: frame number `frame`, `done` of `frames` written.
struct FramesRenderJobProgress {
    int frame = 0;
    size_t done = 0, frames = 0;
    std::string url;
};
/// A frame of a stylizer sequence: `frame` (1-based) of `frames`, at time `time`.
struct SequenceJobProgress {
    size_t frame = 0, frames = 0;
    double time = 0, renderMs = 0;
    std::string url;
};

/// The encoded body of a job read back from its record: a finished job's answer is replayed as
/// it was given, never read into (the store keeps the door's encoding, not each kind's fields).
struct RecordedJobBody {
    std::string json;
};

using JobProgress = std::variant<std::monostate, SolveJobProgress, AnimateJobProgress, FramesRenderJobProgress,
                                 SequenceJobProgress, RecordedJobBody>;

struct SolveJobResult {
    int version = 0;
    core::SolveReport report;
};
/// A light solve; alone (`report`, `lightVolume*`) or with the volume in rounds (`rounds`, …).
struct LightsJobResult {
    int version = 0;
    std::optional<core::SolveReport> report;
    double lightVolumeMs = 0;
    size_t lightVolumeBytes = 0;
    std::optional<int> rounds;
    std::vector<double> rmsHistory;
    double totalMs = 0;
    core::Lighting lighting;  ///< the session's lighting after the solve
    std::shared_ptr<const core::Image> sessionMap;  ///< the session's environment map, named "session"
    std::string environmentUrl;
};
struct AnimateJobResult {
    std::vector<int> keyFrames, frames;
    std::vector<double> changePerSweep;
};
struct FramesRenderJobResult {
    std::vector<int> frames;
    std::vector<std::string> frameUrls;
};
struct SequenceJobResult {
    size_t frames = 0;
    double fps = 0, start = 0, end = 0, renderMs = 0;
    std::vector<std::string> frameUrls;
    std::optional<std::string> videoUrl;
};

using JobResult = std::variant<std::monostate, SolveJobResult, LightsJobResult, AnimateJobResult, FramesRenderJobResult,
                               SequenceJobResult, RecordedJobBody>;

/// Why a job failed or was cancelled (the SPEC error body without a request id).
struct JobError {
    ErrorCode code = ErrorCode::InternalError;
    std::string message;
    std::vector<FieldError> details;
};

/// A solve's latest iterate is ready to preview: one URL per view.
struct PreviewEvent {
    int iteration = 0;
    std::vector<std::pair<std::string, std::string>> urls;  ///< view id, preview URL
};

/// GET /jobs/{jid}, and the data of the final event.
struct JobInfo {
    std::string id, session;
    JobState state = JobState::Queued;
    JobProgress progress;
    JobResult result;
    std::optional<JobError> error;
};

/// One event of a job's stream: progress, a preview, or the final event (whose data is the
/// job's snapshot when it ended).
struct JobEventData {
    JobEvent event = JobEvent::Progress;
    std::variant<JobProgress, PreviewEvent, JobInfo> data;
};

}  // namespace volstyle::protocol

#pragma once
/// \file vocabulary.h
/// The API's closed sets of names besides error codes (error_code.h) and stop reasons
/// (core/solve/solve_options.h): job states and the events of a job's stream. Enums with
/// constexpr name tables; the schema and docs/API.md list the same names (a unit test checks).

#include <optional>
#include <string_view>

#include "core/base/name_table.h"

namespace volstyle::protocol {

enum class JobState { Queued, Running, Done, Failed, Cancelled };
inline constexpr Named<JobState> kJobStates[] = {
    {JobState::Queued, "queued"}, {JobState::Running, "running"}, {JobState::Done, "done"},
    {JobState::Failed, "failed"}, {JobState::Cancelled, "cancelled"},
};
static_assert(coversInOrder(kJobStates), "a name for every state");

constexpr const char* jobStateName(JobState s) { return nameOf(kJobStates, s); }
constexpr std::optional<JobState> jobStateFromName(std::string_view name) { return valueOf(kJobStates, name); }
constexpr bool isFinished(JobState s) { return s == JobState::Done || s == JobState::Failed || s == JobState::Cancelled; }

/// Events of GET /jobs/{jid}/events: progress and preview while running, then exactly one final
/// event named after the final state (done, failed or cancelled).
enum class JobEvent { Progress, Preview, Done, Failed, Cancelled };
inline constexpr Named<JobEvent> kJobEvents[] = {
    {JobEvent::Progress, "progress"}, {JobEvent::Preview, "preview"}, {JobEvent::Done, "done"},
    {JobEvent::Failed, "failed"}, {JobEvent::Cancelled, "cancelled"},
};
static_assert(coversInOrder(kJobEvents), "a name for every event");

constexpr const char* jobEventName(JobEvent e) { return nameOf(kJobEvents, e); }
constexpr bool isFinal(JobEvent e) { return e == JobEvent::Done || e == JobEvent::Failed || e == JobEvent::Cancelled; }
/// The final event of a finished state.
constexpr JobEvent finalEvent(JobState s) {
    return s == JobState::Done ? JobEvent::Done : s == JobState::Failed ? JobEvent::Failed : JobEvent::Cancelled;
}

}  // namespace volstyle::protocol

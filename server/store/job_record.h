#pragma once
/// \file job_record.h
/// DIR/jobs/<jid>.json: a job's own record on disk, apart from the API's answer (format 1: id,
/// session, state, progress, result, error). Unfinished jobs read back as failed/interrupted.

#include <memory>
#include <optional>
#include <string>

#include "server/state/job_store.h"

namespace volstyle::server::store {

std::string encodeJobRecord(const Job& job);

/// The job a record holds (its final event added); `interrupted` says it was queued or running
/// when the server stopped and is now failed/interrupted (write it back). Throws when damaged.
/// Reads a record's state, progress, result and error into `job` (under its lock), as stored;
/// whether it is finished. Throws when damaged.
bool readJobRecord(const std::string& text, Job& job);

std::shared_ptr<Job> decodeJobRecord(const std::string& text, bool& interrupted);

/// A job's event as the queue sends it to other replicas (its data as the event stream gives it).
std::string encodeJobEvent(const protocol::JobEventData& e);
/// An event another replica sent: its data replayed as sent; nullopt for a name that is not a
/// progress or preview event (a final state comes with the job's record instead).
std::optional<protocol::JobEventData> decodeJobEvent(const std::string& name, const std::string& data);

}  // namespace volstyle::server::store

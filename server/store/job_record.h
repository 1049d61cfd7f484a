#pragma once
/// \file job_record.h
/// DIR/jobs/<jid>.json: a job's own record on disk, apart from the API's answer (format 1: id,
/// session, state, progress, result, error). Unfinished jobs read back as failed/interrupted.

#include <memory>
#include <string>

#include "server/state/job_store.h"

namespace volstyle::server::store {

std::string encodeJobRecord(const Job& job);

/// The job a record holds (its final event added); `interrupted` says it was queued or running
/// when the server stopped and is now failed/interrupted (write it back). Throws when damaged.
std::shared_ptr<Job> decodeJobRecord(const std::string& text, bool& interrupted);

}  // namespace volstyle::server::store

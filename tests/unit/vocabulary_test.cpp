// The API's closed vocabularies (issue #8): error codes, job states, job events and solver stop
// reasons are enums with constexpr tables, and the schema and docs/API.md list exactly those names.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <set>
#include <sstream>

#include "core/base/errors.h"
#include "core/scene/solve_options.h"
#include "protocol/error_body.h"
#include "protocol/error_code.h"
#include "protocol/validation.h"
#include "protocol/vocabulary.h"

using namespace volstyle;
using json = nlohmann::json;

namespace {

json schema() { return json::parse(protocol::kSchemaV1); }

std::set<std::string> enumOf(const json& j) { return j.get<std::set<std::string>>(); }

std::string apiDoc() {
    std::ifstream f(VOLSTYLE_SOURCE_DIR "/docs/API.md");
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

}  // namespace

TEST(Vocabulary, ErrorCodesMatchTheSchemaAndTheDocs) {
    std::set<std::string> names;
    for (const auto& e : protocol::kErrorCodes) {
        names.insert(e.name);
        EXPECT_EQ(protocol::errorCodeFromName(e.name), e.code) << e.name;
        EXPECT_GE(e.httpStatus, 400) << e.name;
    }
    EXPECT_EQ(names, enumOf(schema()["definitions"]["error"]["properties"]["error"]["properties"]["code"]["enum"]));
    const std::string doc = apiDoc();
    for (const auto& n : names) EXPECT_NE(doc.find("`" + n + "`"), std::string::npos) << n << " is not in docs/API.md";
}

TEST(Vocabulary, StatusesAreTheSpecs) {
    using protocol::ErrorCode, protocol::httpStatus;
    EXPECT_EQ(httpStatus(ErrorCode::InvalidArgument), 400);
    EXPECT_EQ(httpStatus(ErrorCode::UnknownField), 400);
    EXPECT_EQ(httpStatus(ErrorCode::Unauthorized), 401);
    EXPECT_EQ(httpStatus(ErrorCode::NotFound), 404);
    EXPECT_EQ(httpStatus(ErrorCode::TooLarge), 413);
    EXPECT_EQ(httpStatus(ErrorCode::UnsupportedMedia), 422);
    EXPECT_EQ(httpStatus(ErrorCode::TooManySessions), 422);
    EXPECT_EQ(httpStatus(ErrorCode::OutOfMemory), 507);
    EXPECT_EQ(httpStatus(ErrorCode::InternalError), 500);
}

TEST(Vocabulary, EveryCoreErrorHasAnApiCode) {
    // core's exceptions name their code(); each must be a row of the table (not a fallback).
    const std::vector<std::pair<std::exception_ptr, protocol::ErrorCode>> cases = {
        {std::make_exception_ptr(InvalidArgument("x")), protocol::ErrorCode::InvalidArgument},
        {std::make_exception_ptr(NotFound("x")), protocol::ErrorCode::NotFound},
        {std::make_exception_ptr(IoError("x")), protocol::ErrorCode::IoError},
        {std::make_exception_ptr(GpuError("x")), protocol::ErrorCode::GpuError},
        {std::make_exception_ptr(ShaderCompileError("x")), protocol::ErrorCode::ShaderCompileError},
        {std::make_exception_ptr(OutOfMemory("x")), protocol::ErrorCode::OutOfMemory},
        {std::make_exception_ptr(Cancelled("x")), protocol::ErrorCode::Cancelled},
        {std::make_exception_ptr(InternalError("x")), protocol::ErrorCode::InternalError},
        {std::make_exception_ptr(LimitExceeded("x")), protocol::ErrorCode::TooLarge},
        {std::make_exception_ptr(protocol::ValidationError(std::vector<protocol::FieldError>{{"/a", "unknown field; allowed: b"}})), protocol::ErrorCode::UnknownField},
        {std::make_exception_ptr(protocol::ValidationError(std::vector<protocol::FieldError>{{"/a", "must be a number"}})), protocol::ErrorCode::InvalidArgument},
        {std::make_exception_ptr(protocol::ApiError(protocol::ErrorCode::TooManyJobs, "x")), protocol::ErrorCode::TooManyJobs},
        {std::make_exception_ptr(std::runtime_error("x")), protocol::ErrorCode::InternalError},
    };
    for (const auto& [e, code] : cases) EXPECT_EQ(protocol::describeException(e).code, code) << protocol::errorName(code);
    EXPECT_EQ(protocol::errorCodeFromName("no_such_code"), protocol::ErrorCode::InternalError);
}

TEST(Vocabulary, JobStatesAndEventsMatchTheSchemaAndTheDocs) {
    std::set<std::string> states, events;
    for (const auto& s : protocol::kJobStates) {
        states.insert(s.name);
        EXPECT_EQ(protocol::jobStateFromName(s.name), s.value);
    }
    for (const auto& e : protocol::kJobEvents) events.insert(e.name);
    const json defs = schema()["definitions"];
    EXPECT_EQ(states, enumOf(defs["job"]["properties"]["state"]["enum"]));
    EXPECT_EQ(events, enumOf(defs["job_event"]["enum"]));
    for (protocol::JobState s : {protocol::JobState::Done, protocol::JobState::Failed, protocol::JobState::Cancelled}) {
        EXPECT_TRUE(protocol::isFinished(s));
        EXPECT_STREQ(protocol::jobEventName(protocol::finalEvent(s)), protocol::jobStateName(s)) << "final event = final state";
    }
    EXPECT_FALSE(protocol::isFinished(protocol::JobState::Running));
    const std::string doc = apiDoc();
    for (const auto& n : states) EXPECT_NE(doc.find("`" + n + "`"), std::string::npos) << n << " is not in docs/API.md";
    for (const auto& n : events) EXPECT_NE(doc.find("`" + n + "`"), std::string::npos) << n << " is not in docs/API.md";
}

TEST(Vocabulary, StopReasonsMatchTheSchemaAndTheDocs) {
    std::set<std::string> reasons;
    for (const auto& r : core::kStopReasons)
        if (r.value != core::StopReason::None) reasons.insert(r.name);
    EXPECT_EQ(reasons, enumOf(schema()["definitions"]["solve_report"]["properties"]["stop_reason"]["enum"]));
    const std::string doc = apiDoc();
    for (const auto& n : reasons) EXPECT_NE(doc.find("`" + n + "`"), std::string::npos) << n << " is not in docs/API.md";
}

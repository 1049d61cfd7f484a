#pragma once
/// \file errors.h
/// The closed set of exceptions core throws (OpenVDB-style taxonomy), and always-on checks that
/// print both operand values (pbrt's CHECK_*), throwing InternalError instead of aborting: a
/// server must survive a broken invariant in one request.

#include <sstream>
#include <stdexcept>
#include <string>

namespace volstyle {

/// Base of every error volstyle throws. `code()` is the snake_case name the API reports.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
    virtual const char* code() const noexcept = 0;
};

#define VOLSTYLE_DECLARE_ERROR(Name, codeName)                                  \
    class Name : public Error {                                                 \
    public:                                                                     \
        using Error::Error;                                                     \
        const char* code() const noexcept override { return codeName; }         \
    }

VOLSTYLE_DECLARE_ERROR(InvalidArgument, "invalid_argument");  ///< bad input from the user
VOLSTYLE_DECLARE_ERROR(NotFound, "not_found");                ///< a named thing does not exist
VOLSTYLE_DECLARE_ERROR(IoError, "io_error");                  ///< a file could not be read/written
VOLSTYLE_DECLARE_ERROR(GpuError, "gpu_error");                ///< GL context or driver failure
VOLSTYLE_DECLARE_ERROR(ShaderCompileError, "shader_compile_error");
VOLSTYLE_DECLARE_ERROR(OutOfMemory, "out_of_memory");
VOLSTYLE_DECLARE_ERROR(Cancelled, "cancelled");
VOLSTYLE_DECLARE_ERROR(OverBudget, "over_budget");  ///< work stopped at its time budget (work_budget.h)
VOLSTYLE_DECLARE_ERROR(InternalError, "internal_error");  ///< a broken invariant (a bug)

#undef VOLSTYLE_DECLARE_ERROR

/// Input over a configured limit (voxels, image sides, bytes): bad input, so an InvalidArgument
/// to callers that only know that, but typed so a server answers 413/422 without reading messages.
class LimitExceeded : public InvalidArgument {
public:
    using InvalidArgument::InvalidArgument;
    const char* code() const noexcept override { return "too_large"; }
};

namespace detail {
template <typename A, typename B>
[[noreturn]] void throwCheckFailure(const char* expr, const A& a, const B& b, const char* file,
                                    int line) {
    std::ostringstream s;
    s << file << ":" << line << ": check failed: " << expr << " (" << a << " vs " << b << ")";
    throw InternalError(s.str());
}
}  // namespace detail

}  // namespace volstyle

/// Always-on invariant check: `VOLSTYLE_CHECK(a, <, b)`; prints both values on failure.
#define VOLSTYLE_CHECK(a, op, b)                                                           \
    do {                                                                                   \
        const auto& volstyle_a_ = (a);                                                     \
        const auto& volstyle_b_ = (b);                                                     \
        if (!(volstyle_a_ op volstyle_b_))                                                 \
            ::volstyle::detail::throwCheckFailure(#a " " #op " " #b, volstyle_a_, volstyle_b_, \
                                                  __FILE__, __LINE__);                     \
    } while (0)

#ifndef NDEBUG
#define VOLSTYLE_DCHECK(a, op, b) VOLSTYLE_CHECK(a, op, b)
#else
#define VOLSTYLE_DCHECK(a, op, b) \
    do {                          \
    } while (0)
#endif

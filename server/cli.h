#pragma once
/// \file cli.h
/// The `volstyle` subcommands (SPEC §4). Each returns the process exit status: 0 success,
/// 2 bad input (one line on stderr), 1 anything else.

#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "core/render/params.h"
#include "protocol/validation.h"

namespace volstyle::server {

/// `--name value`, `--name=value`, `-o value` and bare flags; positional arguments in order.
struct Arguments {
    std::map<std::string, std::string> options;
    std::vector<std::string> positional;

    bool has(const std::string& name) const { return options.count(name) > 0; }
    std::string get(const std::string& name, const std::string& fallback = "") const;
    double number(const std::string& name, double fallback) const;
};

/// A finite number, or InvalidArgument naming `--flag`.
double parseNumber(const std::string& flag, const std::string& text);

/// Parses argv (after the subcommand); `flags` are options that take no value. Unknown options
/// throw InvalidArgument naming them and listing `known`.
Arguments parseArguments(const std::vector<std::string>& args, const std::vector<std::string>& known,
                         const std::vector<std::string>& flags);

/// Reads and parses a JSON file; InvalidArgument names the file.
nlohmann::json readJsonFile(const std::string& path);

/// Parses a file with `parse`, turning validation errors into one line that names the file.
template <typename F>
auto fromFile(const std::string& path, F&& parse) {
    try {
        return parse(readJsonFile(path));
    } catch (const protocol::ValidationError& e) {
        throw InvalidArgument("'" + path + "': " + e.what());
    }
}

/// A lighting object from a file (`jsonPath`): environment map paths are relative to it.
core::Lighting lightingFromJsonFile(const nlohmann::json& j, const std::string& jsonPath, const std::string& pointer = "");

int runRender(const std::vector<std::string>& args);
int runSolve(const std::vector<std::string>& args);
int runServe(const std::vector<std::string>& args);
int runInfo(const std::vector<std::string>& args);

}  // namespace volstyle::server

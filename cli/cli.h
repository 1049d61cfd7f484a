#pragma once
/// \file cli.h
/// The `volstyle` subcommands (SPEC §4). Each returns the process exit status: 0 success,
/// 2 bad input (one line on stderr), 1 anything else.

#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/scene/solve_options.h"
#include "core/volume/volume.h"
#include "protocol/validation.h"

namespace volstyle::cli {

/// `--name value`, `--name=value`, `-o value` and bare flags; positional arguments in order.
struct Arguments {
    std::map<std::string, std::string> options;
    std::vector<std::string> positional;

    bool has(const std::string& name) const { return options.count(name) > 0; }
    std::string get(const std::string& name, const std::string& fallback = "") const;
    double number(const std::string& name, double fallback) const;
};

/// One option of a subcommand, for parsing and for its --help.
struct OptionSpec {
    std::string name;   ///< without the dashes; "output" is also -o
    std::string value;  ///< its placeholder ("FILE.vdb"); empty: a flag that takes no value
    std::string help;   ///< what it does, ending with its default or "(required)"
};

/// A subcommand: what `volstyle help NAME` and `volstyle NAME --help` print, and what it accepts.
struct CommandSpec {
    std::string name;
    std::string brief;     ///< a line for `volstyle help`
    std::string synopsis;  ///< the usage line after "volstyle NAME"
    std::string summary;   ///< one paragraph: what it does
    std::vector<OptionSpec> options;
    std::string examples;  ///< lines of shell, each run by the docs test
};

/// The --help text: usage, summary, every option with its description and default, examples.
std::string usageText(const CommandSpec& spec);

/// Prints usageText(spec) to stdout if --help was given (the command then exits 0).
bool printHelpIfAsked(const Arguments& args, const CommandSpec& spec);

/// Parses argv against `spec` (--help is always accepted).
Arguments parseArguments(const std::vector<std::string>& args, const CommandSpec& spec);

/// The page's folder when `serve` has no --web-dir: $VOLSTYLE_WEB_DIR, the installed
/// share/volstyle/web next to the binary (../share) or at the install prefix, then this build's
/// source tree — the first holding index.html, whatever the working directory. Empty if none.
std::string defaultWebDir();

/// The subcommands' specs (help texts and options), for `volstyle help`.
const CommandSpec& renderCommand();
const CommandSpec& solveCommand();
const CommandSpec& serveCommand();
const CommandSpec& infoCommand();
const CommandSpec& convertCommand();
const CommandSpec& stylizeCommand();
const CommandSpec& animateCommand();

/// A finite number, or InvalidArgument naming `--flag`.
double parseNumber(const std::string& flag, const std::string& text);
/// `s` cut at `sep`, empty parts dropped.
std::vector<std::string> split(const std::string& s, char sep);
/// `count` comma-separated numbers of `--flag` (InvalidArgument naming it otherwise).
std::vector<double> numbers(const std::string& flag, const std::string& value, size_t count);

/// --glass N[,R[,NOISE]]: bakes a glass sphere's refractive index into `volume` (issue #16); a
/// no-op without the flag. Throws InvalidArgument naming the bad value.
void applyGlassOption(const Arguments& args, core::Volume& volume);
/// The help line of --glass (render and solve share it; constants, so other files' static
/// command tables can use them at start-up).
inline constexpr const char* kGlassValue = "N[,R[,NOISE]]";
inline constexpr const char* kGlassHelp =
    "bake a glass sphere of index N into the volume (radius R world units, default 0.55; noise amplitude NOISE, default 0.03): "
    "rays bend through it; default: the volume's own refractive_index, if any";

/// Parses argv (after the subcommand); `flags` are options that take no value. Unknown options
/// throw InvalidArgument naming them and listing `known`.
Arguments parseArguments(const std::vector<std::string>& args, const std::vector<std::string>& known,
                         const std::vector<std::string>& flags);

/// An output path whose folder exists (IoError naming the folder otherwise: a typo in -o should not
/// make folders silently).
void requireParentFolder(const std::string& outputPath);

/// The -o of a command writing one image: required, .png or .exr, its folder existing.
std::string imageOutputPath(const Arguments& args);

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

/// The views of VIEWS.json: {"views": [{"name"?, "camera", "target", "weights"?, "background"?}],
/// "lighting"?}; "background" is the view's plate (SPEC §1), an image of the camera's size. With
/// `frames`, each view also names its "frame" (an animation's), returned in order.
/// `clipAware`: targets from 8/16-bit files get weight 0 where the picture was clipped.
std::vector<core::SolveView> readViews(const std::string& path, core::Lighting& lighting, std::vector<int>* frames = nullptr,
                                       bool clipAware = true);

int runRender(const std::vector<std::string>& args);
int runAnimate(const std::vector<std::string>& args);
int runSolve(const std::vector<std::string>& args);
int runServe(const std::vector<std::string>& args);
int runInfo(const std::vector<std::string>& args);
int runConvert(const std::vector<std::string>& args);
int runStylize(const std::vector<std::string>& args);
/// The server's child readers (cli/reader_commands.cpp).
int runReadVdb(const std::vector<std::string>& args);
int runReadMesh(const std::vector<std::string>& args);

}  // namespace volstyle::cli

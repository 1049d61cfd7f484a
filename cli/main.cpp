// The `volstyle` binary: one executable, subcommands (SPEC §4).

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "cli/cli.h"
#include "protocol/build_version.h"

namespace {

using volstyle::cli::CommandSpec;

const std::vector<const CommandSpec*>& commands() {
    static const std::vector<const CommandSpec*> all{
        &volstyle::cli::serveCommand(), &volstyle::cli::renderCommand(), &volstyle::cli::solveCommand(),
        &volstyle::cli::stylizeCommand(), &volstyle::cli::animateCommand(), &volstyle::cli::infoCommand(),
        &volstyle::cli::convertCommand()};
    return all;
}

std::string usage() {
    std::string s = std::string("volstyle ") + volstyle::protocol::versionString() +
                    " — restyle smoke, clouds and fog by painting what they should look like\n"
                    "usage: volstyle COMMAND [options]    (volstyle help COMMAND for its options)\n\ncommands:\n";
    for (const CommandSpec* c : commands()) {
        s += "  " + c->name + std::string(10 - c->name.size(), ' ') + c->brief + "\n";
    }
    s += "  help      this text, or a command's: volstyle help render\n"
         "\nenvironment: VOLSTYLE_EGL=device|surfaceless, VOLSTYLE_LOG_LEVEL=debug|info|warn,\n"
         "             VOLSTYLE_TOKEN (serve's --token), VOLSTYLE_WEB_DIR (serve's page folder),\n"
         "             VOLSTYLE_SHADER_DIR=core/shaders (load shaders from disk)\n";
    return s;
}

void setUpLogging() {
    auto logger = spdlog::stderr_color_mt("volstyle");
    spdlog::set_default_logger(logger);
    const char* level = std::getenv("VOLSTYLE_LOG_LEVEL");
    spdlog::set_level(level ? spdlog::level::from_str(level) : spdlog::level::warn);
}

}  // namespace

int main(int argc, char** argv) {
    setUpLogging();
    if (argc < 2) {
        std::cerr << usage();
        return 2;
    }
    const std::string command = argv[1];
    if (command == "--help" || command == "-h" || (command == "help" && argc == 2)) {
        std::cout << usage();
        return 0;
    }
    if (command == "--version" || command == "version") {
        std::cout << "volstyle " << volstyle::protocol::versionString() << "\n";
        return 0;
    }
    if (command == "help") {
        for (const CommandSpec* c : commands())
            if (c->name == argv[2]) {
                std::cout << volstyle::cli::usageText(*c);
                return 0;
            }
        std::cerr << "volstyle help: no command '" << argv[2] << "'\n" << usage();
        return 2;
    }
    const std::vector<std::string> args(argv + 2, argv + argc);
    try {
        if (command == "render") return volstyle::cli::runRender(args);
        if (command == "stylize") return volstyle::cli::runStylize(args);
        if (command == "animate") return volstyle::cli::runAnimate(args);
        if (command == "info") return volstyle::cli::runInfo(args);
        if (command == "convert") return volstyle::cli::runConvert(args);
        if (command == "solve") return volstyle::cli::runSolve(args);
        if (command == "serve") return volstyle::cli::runServe(args);
        if (command == "read-vdb") return volstyle::cli::runReadVdb(args);  // the server's child reader
        if (command == "read-mesh") return volstyle::cli::runReadMesh(args);  // the server's child mesh reader
        std::cerr << "volstyle: unknown command '" << command << "'\n" << usage();
        return 2;
    } catch (const volstyle::InvalidArgument& e) {
        std::cerr << "volstyle " << command << ": " << e.what() << "\n";
        return 2;
    } catch (const volstyle::IoError& e) {
        std::cerr << "volstyle " << command << ": " << e.what() << "\n";
        return 2;
    } catch (const volstyle::NotFound& e) {
        std::cerr << "volstyle " << command << ": " << e.what() << "\n";
        return 2;
    } catch (const volstyle::Cancelled& e) {
        std::cerr << "volstyle " << command << ": cancelled: " << e.what() << "\n";
        return 130;
    } catch (const volstyle::Error& e) {
        std::cerr << "volstyle " << command << ": " << e.code() << ": " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "volstyle " << command << ": internal error: " << e.what() << "\n";
        return 1;
    }
}

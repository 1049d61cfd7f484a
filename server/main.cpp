// The `volstyle` binary: one executable, subcommands (SPEC §4).

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "server/cli.h"
#include "server/vdb_reader.h"

namespace {

const char* kUsage =
    "volstyle — restyle volumes by painting them\n"
    "usage: volstyle <command> [options]\n"
    "  serve    the HTTP/JSON server           (volstyle serve --help)\n"
    "  render   render a scene to PNG/EXR      (volstyle render --help)\n"
    "  solve    restyle a volume from painted views (volstyle solve --help)\n"
    "  info     describe an OpenVDB file       (volstyle info FILE.vdb)\n"
    "Environment: VOLSTYLE_EGL=device|surfaceless, VOLSTYLE_LOG_LEVEL=debug|info|warn,\n"
    "             VOLSTYLE_SHADER_DIR=core/shaders (load shaders from disk).\n";

void setUpLogging() {
    auto logger = spdlog::stderr_color_mt("volstyle");
    spdlog::set_default_logger(logger);
    const char* level = std::getenv("VOLSTYLE_LOG_LEVEL");
    spdlog::set_level(level ? spdlog::level::from_str(level) : spdlog::level::warn);
}

}  // namespace

int main(int argc, char** argv) {
    setUpLogging();
    if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
        std::cout << kUsage;
        return argc < 2 ? 2 : 0;
    }
    const std::string command = argv[1];
    const std::vector<std::string> args(argv + 2, argv + argc);
    try {
        if (command == "render") return volstyle::server::runRender(args);
        if (command == "info") return volstyle::server::runInfo(args);
        if (command == "solve") return volstyle::server::runSolve(args);
        if (command == "serve") return volstyle::server::runServe(args);
        if (command == "read-vdb") return volstyle::server::runReadVdb(args);  // the server's child reader
        std::cerr << "volstyle: unknown command '" << command << "'\n" << kUsage;
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

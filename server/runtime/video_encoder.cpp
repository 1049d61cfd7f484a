#include "server/runtime/video_encoder.h"

#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/base/errors.h"

extern char** environ;

namespace volstyle::server {

namespace fs = std::filesystem;

std::string findFfmpeg() {
    const char* path = std::getenv("PATH");
    std::stringstream dirs(path ? path : "/usr/bin:/bin");
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        const fs::path candidate = fs::path(dir.empty() ? "." : dir) / "ffmpeg";
        if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
    return {};
}

std::string sequenceFrameName(size_t index) { return fmt::format("frame_{:05d}.png", index); }

void encodeVideo(const fs::path& framesDir, size_t frames, double fps, const fs::path& output) {
    const std::string ffmpeg = findFfmpeg();
    if (ffmpeg.empty()) throw IoError("no ffmpeg on PATH to encode the video (Debian: apt install ffmpeg); the PNG frames are written");
    const fs::path log = output.string() + ".log";
    std::vector<std::string> args = {ffmpeg, "-nostdin", "-y", "-v", "error", "-framerate", fmt::format("{:g}", fps),
                                     "-i", (framesDir / "frame_%05d.png").string(),
                                     "-frames:v", std::to_string(frames), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                                     "-movflags", "+faststart", output.string()};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) throw IoError("could not start ffmpeg: " + std::string(std::strerror(spawned)));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    std::ifstream in(log);
    std::string complaint((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::error_code ec;
    fs::remove(log, ec);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        if (complaint.size() > 400) complaint = "…" + complaint.substr(complaint.size() - 400);
        throw IoError("ffmpeg could not encode '" + output.string() + "': " + (complaint.empty() ? "it failed" : complaint));
    }
}

}  // namespace volstyle::server

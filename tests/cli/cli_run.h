#pragma once
// Running the real `volstyle` binary from the CLI tests.
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace volstyle::test {

struct Result {
    int status = -1;
    std::string out;  // stdout + stderr
};

inline Result run(const std::string& args) {
    std::string cmd = std::string(VOLSTYLE_BINARY) + " " + args + " 2>&1";
    Result r;
    FILE* pipe = popen(cmd.c_str(), "r");
    std::array<char, 4096> buf;
    while (size_t n = fread(buf.data(), 1, buf.size(), pipe)) r.out.append(buf.data(), n);
    int st = pclose(pipe);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

inline size_t lines(const std::string& s) { return size_t(std::count(s.begin(), s.end(), '\n')); }

inline void writeText(const std::filesystem::path& p, const std::string& text) { std::ofstream(p) << text; }

}  // namespace volstyle::test

#pragma once
/// \file video_encoder.h
/// Stylizer sequences as video files (issue #15): Debian's ffmpeg encodes the PNG frames a
/// sequence wrote to H.264 in MP4, run as a separate process (no shell, arguments as given).

#include <filesystem>
#include <string>

namespace volstyle::server {

/// The ffmpeg on PATH, or empty when there is none.
std::string findFfmpeg();

/// Encodes `frames` frames `framesDir`/frame_%05d.png from 0 at `fps` into `output` (.mp4, H.264,
/// yuv420p, sides padded to even; older frames beyond them in the folder are left out). Throws
/// IoError naming ffmpeg's complaint, or that there is no ffmpeg.
void encodeVideo(const std::filesystem::path& framesDir, size_t frames, double fps, const std::filesystem::path& output);

/// The file name of frame `index` of a sequence: frame_00012.png.
std::string sequenceFrameName(size_t index);
/// The URL of a job's file (GET /api/v1/jobs/{id}/{file}: frames/3.png, video.mp4).
inline std::string jobFileUrl(const std::string& job, const std::string& file) { return "/api/v1/jobs/" + job + "/" + file; }

}  // namespace volstyle::server

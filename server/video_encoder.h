#pragma once
/// \file video_encoder.h
/// Stylizer sequences as video files (issue #15): Debian's ffmpeg encodes the PNG frames a
/// sequence wrote to H.264 in MP4, run as a separate process (no shell, arguments as given).

#include <filesystem>
#include <string>

namespace volstyle::server {

/// The ffmpeg on PATH, or empty when there is none.
std::string findFfmpeg();

/// Encodes `framesDir`/frame_%05d.png at `fps` into `output` (.mp4, H.264, yuv420p, sides
/// padded to even). Throws IoError naming ffmpeg's complaint; NotSupported-like IoError when
/// ffmpeg is missing.
void encodeVideo(const std::filesystem::path& framesDir, double fps, const std::filesystem::path& output);

/// The file name of frame `index` of a sequence: frame_00012.png.
std::string sequenceFrameName(size_t index);

}  // namespace volstyle::server

#include "server/store/session_record.h"

#include <spdlog/spdlog.h>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/scene/environment_lobes.h"
#include "core/volume/vdb_io.h"
#include "protocol/render_json.h"
#include "protocol/response_json.h"
#include "server/state/session_info.h"

namespace volstyle::server::store {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr int kFormat = 1;

/// A view in the record: its camera (as the API writes cameras), frame and which images it has.
json viewRecord(const SessionView& v) {
    json j = {{"id", v.id}, {"camera", protocol::cameraToJson(v.camera)}, {"has_target", v.target.has_value()},
              {"has_weights", v.weights.has_value()}, {"has_background", bool(v.background)}};
    if (v.frame) j["frame"] = *v.frame;
    if (v.clippedPixels) j["clipped_pixels"] = v.clippedPixels;
    return j;
}

/// Restores the environment map (environment.image) and the lighting that may name it; a damaged
/// map is quarantined and the lighting falls back to the background colour and the lobes'
/// radiances as they were last written.
void restoreLighting(DataDir& dir, Session& s, const fs::path& folder, const json& lighting) {
    const std::string file = "environment.image";
    if (fs::exists(folder / file)) {
        try {
            const std::string bytes = readFile(folder / file);
            auto map = std::make_shared<core::Image>(core::loadImageFromMemory(bytes.data(), bytes.size(), "the environment map").image);
            if (std::string why = core::latLongMapProblem(*map); !why.empty()) throw IoError(why);
            s.light.environmentMap = std::move(map);
        } catch (const std::exception& e) {
            dir.quarantineFile(s.id, file, e.what());
            s.damaged.push_back({file, e.what()});
        }
    }
    protocol::LightingRequest request = protocol::lightingFromJson(lighting);
    if (!s.light.environmentMap) {  // damaged: the background's colour, and the lobes' radiances as they were
        request.backgroundUsesSessionMap = request.environmentUsesSessionMap = false;
    }
    s.light.lighting = request.resolve(s.light.environmentMap);
}

/// Restores the versions the record lists; the current one is read (or the newest readable one,
/// if it is damaged). Throws if no version is readable.
void restoreVersions(DataDir& dir, Session& s, const json& j) {
    const json bytes = j.value("version_bytes", json::object());
    for (int n : j.at("versions")) s.volume.versions.add(n);
    for (const auto& d : s.damaged)  // damage found before a restart stays listed
        for (int n : s.volume.versions.numbers())
            if (d.file == versionFile(n)) s.volume.versions.markDamaged(n, d.reason);
    const auto damage = [&](int n, const std::string& reason) {
        dir.quarantineFile(s.id, versionFile(n), reason);
        s.volume.versions.markDamaged(n, reason);
        s.damaged.push_back({versionFile(n), reason});
    };
    // Every version's file must exist with the size it was written with (a stat, not a read).
    for (int n : s.volume.versions.numbers()) {
        if (s.volume.versions.damage(n)) continue;
        std::error_code ec;
        const std::uintmax_t size = fs::file_size(dir.sessionDir(s.id) / versionFile(n), ec);
        const std::uintmax_t expected = bytes.contains(std::to_string(n)) ? bytes[std::to_string(n)].get<std::uintmax_t>() : size;
        if (ec) damage(n, "the file is missing");
        else if (size != expected) damage(n, "the file is " + std::to_string(size) + " bytes; it was written with " + std::to_string(expected));
        else s.volume.versions.markStored(n, size);
    }
    // The current version is read now; if it is damaged, the newest readable one becomes current.
    const int recorded = j.at("version");
    for (auto it = s.volume.versions.numbers().rbegin(); it != s.volume.versions.numbers().rend(); ++it) {
        const int n = *it;
        if (n > recorded || s.volume.versions.damage(n)) continue;
        try {
            s.volume.current = loadVersionFile(dir, s.id, n, *s.volume.versions.storedBytes(n));
            s.volume.version = n;
            // Undo and redo (since 2026-12-05; older records: none, the version shows itself).
            s.volume.shows = n == recorded ? j.value("shows", n) : n;
            s.volume.undo = j.value("undo", std::vector<int>{});
            s.volume.redo = j.value("redo", std::vector<int>{});
            if (n != recorded) spdlog::warn("restore: session {} falls back from version {} to {}", s.id, recorded, n);
            return;
        } catch (const std::exception& e) {
            damage(n, e.what());
        }
    }
    throw IoError("no version of the volume is readable");
}

/// The views, each with the images the record says it has (a damaged one is dropped alone).
void restoreViews(DataDir& dir, Session& s, const fs::path& folder, const json& views) {
    for (const auto& v : views) {
        SessionView view{v.at("id"), protocol::cameraFromJson(v.at("camera")), std::nullopt, std::nullopt};
        if (v.contains("frame")) view.frame = v.at("frame").get<int>();
        view.clippedPixels = v.value("clipped_pixels", size_t(0));
        for (const char* kind : {"target", "weights", "background"}) {
            if (!v.value(std::string("has_") + kind, false)) continue;  // "has_background": since 2026-12
            const std::string file = "views/" + view.id + "/" + kind + ".exr";
            try {
                core::Image image = core::loadImage((folder / file).string()).image;
                const std::string k = kind;
                if (k == "background") view.background = std::make_shared<const core::Image>(std::move(image));
                else (k == "target" ? view.target : view.weights) = std::move(image);
            } catch (const std::exception& e) {
                dir.quarantineFile(s.id, file, e.what());  // the view stays, without this image
                s.damaged.push_back({file, e.what()});
            }
        }
        s.views.list.push_back(std::move(view));
    }
}

/// The animation's frames (since issue #16): a damaged one is quarantined and dropped.
void restoreFrames(DataDir& dir, Session& s, const fs::path& folder, const json& frames) {
    for (const auto& f : frames) {
        const int n = f.at("frame").get<int>();
        const std::string file = "frames/" + std::to_string(n) + ".vdb";
        try {
            s.frames[n] = {core::loadVdb((folder / file).string()), f.value("solved", false)};
        } catch (const std::exception& e) {
            dir.quarantineFile(s.id, file, e.what());
            s.damaged.push_back({file, e.what()});
        }
    }
}

}  // namespace

std::string versionFile(int version) { return "versions/" + std::to_string(version) + ".vdb"; }

std::string encodeSessionRecord(const Session& s) {
    json bytes = json::object(), damaged = json::array(), views = json::array(), frames = json::array();
    for (int n : s.volume.versions.numbers())
        if (auto b = s.volume.versions.storedBytes(n)) bytes[std::to_string(n)] = *b;
    for (const auto& d : s.damaged) damaged.push_back({{"file", d.file}, {"reason", d.reason}});
    for (const auto& v : s.views.list) views.push_back(viewRecord(v));
    for (const auto& [n, f] : s.frames) frames.push_back({{"frame", n}, {"solved", f.solved}});
    const json j = {{"format", kFormat},
                    {"id", s.id},
                    {"created", s.created},
                    {"scene", s.scene},
                    {"version", s.volume.version},
                    {"shows", s.volume.shows},
                    {"undo", s.volume.undo},
                    {"redo", s.volume.redo},
                    {"versions", s.volume.versions.numbers()},
                    {"version_bytes", bytes},
                    {"damaged", damaged},
                    {"lighting", protocol::lightingToJson(s.light.lighting, s.light.environmentMap.get())},
                    {"views", views},
                    {"next_view", s.views.next},
                    {"jobs", s.jobs},
                    {"frames", frames}};
    return protocol::toText(j, 2);
}

std::shared_ptr<Session> restoreSessionRecord(DataDir& dir, const fs::path& folder, size_t& recordedDamage) {
    json j;
    try {
        j = json::parse(readFile(folder / "session.json"));
    } catch (const std::exception& e) {
        throw IoError(std::string("session.json is unreadable: ") + e.what());
    }
    if (j.value("format", kFormat) > kFormat)
        throw IoError("session.json is format " + j.at("format").dump() + ", newer than this server's (" + std::to_string(kFormat) + ")");
    auto s = std::make_shared<Session>();
    s->id = j.at("id");
    s->created = j.at("created");
    s->scene = j.at("scene");
    s->views.next = j.at("next_view");
    s->jobs = j.at("jobs").get<std::vector<std::string>>();
    for (const auto& d : j.value("damaged", json::array())) s->damaged.push_back({d.at("file"), d.at("reason")});
    recordedDamage = s->damaged.size();
    restoreLighting(dir, *s, folder, j.at("lighting"));
    restoreVersions(dir, *s, j);
    restoreViews(dir, *s, folder, j.at("views"));
    restoreFrames(dir, *s, folder, j.value("frames", json::array()));
    return s;
}

core::Volume loadVersionFile(const DataDir& dir, const std::string& session, int version, std::uintmax_t expectedBytes) {
    const fs::path path = dir.sessionDir(session) / versionFile(version);
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) throw IoError("version " + std::to_string(version) + "'s file is missing");
    if (expectedBytes && size != expectedBytes)
        throw IoError("version " + std::to_string(version) + "'s file is " + std::to_string(size) + " bytes; it was written with " +
                      std::to_string(expectedBytes));
    return core::loadVdb(path.string());
}

std::string encodeSessionSummary(const Session& s) { return protocol::sessionToJson(sessionInfoLocked(s)).dump(); }

}  // namespace volstyle::server::store

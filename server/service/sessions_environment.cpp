// The session's environment map (SPEC §8, docs/LIGHTING.md): a lat-long image uploaded with
// PUT …/environment that the lighting names "session" — as the background, as the map the
// environment light's lobes are fitted to, or both.
#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/scene/environment_lobes.h"
#include "server/service/services.h"

namespace volstyle::server {
namespace {

const std::string kEnvironmentFile = "environment.image";

bool namesMap(const core::Lighting& l, const core::Image* map) {
    return map && (l.background.environment.get() == map || l.environment.map.get() == map);
}

}  // namespace

std::optional<EnvironmentMapInfo> environmentMapInfo(const Session& s) {
    if (!s.light.environmentMap) return std::nullopt;
    return EnvironmentMapInfo{s.light.environmentMap->width, s.light.environmentMap->height, namesMap(s.light.lighting, s.light.environmentMap.get())};
}

EnvironmentMapInfo SessionsService::setEnvironmentMap(Session& s, const std::string& bytes) {
    m_ctx.checkUploadSize(bytes, "the environment map");
    std::optional<ServiceContext::DecodeSlot> slot;
    core::Image image;
    try {
        image = core::loadImageFromMemory(bytes.data(), bytes.size(), "the environment map", m_ctx.limits.maxImageSide,
                                          [&](int width, int height) {
                                              if (std::abs(width - 2 * height) > 1)  // before decoding the pixels
                                                  throw ApiError(ErrorCode::InvalidArgument,
                                                                 "a latitude-longitude map is twice as wide as high; this one is " +
                                                                     std::to_string(width) + "x" + std::to_string(height));
                                              slot.emplace(m_ctx.decodeSlots);
                                          }).image;
    } catch (const Error& e) {
        throw ApiError(ErrorCode::UnsupportedMedia, e.what());  // undecodable, or over the side limit
    }
    if (std::string why = core::latLongMapProblem(image); !why.empty()) throw ApiError(ErrorCode::InvalidArgument, "the environment map: " + why);
    for (size_t i = 0; i < image.pixelCount(); ++i) image.rgba[4 * i + 3] = 1;  // radiance: alpha means nothing
    auto map = std::make_shared<const core::Image>(std::move(image));
    slot.reset();
    std::lock_guard lock(s.mutex);
    if (s.removed) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' was deleted");
    m_ctx.memory.check(s, map->rgba.size() * sizeof(float), s.light.environmentMap ? s.light.environmentMap->rgba.size() * sizeof(float) : 0, "the environment map");
    if (m_ctx.persist) m_ctx.persist->saveSessionFile(s.id, kEnvironmentFile, bytes);
    // The lighting that names the old map names the new one.
    core::Lighting& l = s.light.lighting;
    if (s.light.environmentMap && l.background.environment == s.light.environmentMap) l.background.environment = map;
    if (s.light.environmentMap && l.environment.map == s.light.environmentMap) l.environment.map = map;
    s.light.environmentMap = map;
    m_ctx.saved(s);
    m_ctx.shownChanged(s);
    return *environmentMapInfo(s);
}

std::shared_ptr<const core::Image> SessionsService::environmentMap(Session& s) const {
    std::lock_guard lock(s.mutex);
    if (!s.light.environmentMap) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no environment map uploaded");
    return s.light.environmentMap;
}

void SessionsService::removeEnvironmentMap(Session& s) {
    std::lock_guard lock(s.mutex);
    if (!s.light.environmentMap) throw ApiError(ErrorCode::NotFound, "session '" + s.id + "' has no environment map uploaded");
    if (namesMap(s.light.lighting, s.light.environmentMap.get()))
        throw ApiError(ErrorCode::Busy, "the lighting names the environment map (\"session\"); PUT a lighting without it first");
    if (m_ctx.persist) m_ctx.persist->removeSessionFile(s.id, kEnvironmentFile);
    s.light.environmentMap.reset();
    m_ctx.saved(s);
}

}  // namespace volstyle::server

#pragma once
/// \file sessions_service.h
/// Sessions, their views, lighting and environment map (SPEC §3): create, find, delete; every
/// change on disk before it returns.

#include "server/service/service_context.h"

namespace volstyle::server {

class SessionsService {
public:
    explicit SessionsService(ServiceContext& ctx) : m_ctx(ctx) {}

    std::shared_ptr<Session> create(const protocol::CreateSessionRequest& request);
    std::shared_ptr<Session> find(const std::string& id) const { return m_ctx.find(id); }  ///< ApiError not_found
    std::vector<std::shared_ptr<Session>> all() const { return m_ctx.sessions.all(); }
    /// A session as GET /sessions lists it: its state here, or (another replica's, from the store)
    /// the JSON its last save wrote beside its record.
    struct Listed {
        std::string id;
        std::optional<protocol::SessionInfo> info;
        std::string storedJson;
    };
    /// Every session: those held here and, with a store, every replica's (issue #41): one query
    /// for the summaries, no session loaded (but a record an older volstyle saved, once).
    std::vector<Listed> list() const;

private:
    Listed summaryOfUnsummed(const std::string& id) const;

public:
    void remove(const std::string& id);
    const core::gl::Capabilities& capabilities() const { return m_ctx.gl->capabilities(); }
    /// What the data directory's quarantine holds (empty without one).
    std::vector<QuarantineEntry> quarantine() const;
    /// GET /ready's checks: "" where it holds, else why not.
    struct Readiness {
        std::string store;  ///< "folder" or "memory"
        std::string storeProblem, glProblem;
    };
    Readiness readiness() const;

    core::Lighting lighting(Session& s) const { return m_ctx.lighting(s); }
    /// Sets the lighting, "session" resolved to the session's map (ValidationError naming the
    /// field without one); the lighting as set.
    core::Lighting setLighting(Session& s, const protocol::LightingRequest& request);
    /// The session's environment map for answers that name it "session" (null without one).
    std::shared_ptr<const core::Image> environmentMapIfAny(Session& s) const;

    // The session's environment map (session_environment.cpp; docs/LIGHTING.md).
    /// Decodes and stores a lat-long map (2:1, finite, >= 0; 422 otherwise, 413 over the limits);
    /// a lighting that names it now uses this one.
    EnvironmentMapInfo setEnvironmentMap(Session& s, const std::string& bytes);
    std::shared_ptr<const core::Image> environmentMap(Session& s) const;  ///< not_found without one
    void removeEnvironmentMap(Session& s);  ///< busy (409) while the lighting names it

    // Views.
    SessionView addView(Session& s, const core::Camera& camera, std::optional<int> frame = std::nullopt);
    SessionView view(Session& s, const std::string& viewId) const { return m_ctx.view(s, viewId); }  ///< a copy; not_found
    void removeView(Session& s, const std::string& viewId);
    /// Decodes an uploaded image (413 over the upload limit, 422 undecodable or over the side
    /// limit) and stores it as the view's target or weights. `clipAware`: a target from an 8/16-bit
    /// file gets weight 0 where the picture was clipped (core/image/clipped_pixels.h).
    SessionView setViewImage(Session& s, const std::string& viewId, ViewImage kind, const std::string& bytes, bool clipAware = true);
    /// Forgets the view's image of `kind` (not_found without one).
    SessionView removeViewImage(Session& s, const std::string& viewId, ViewImage kind);

private:
    ServiceContext& m_ctx;
};

}  // namespace volstyle::server

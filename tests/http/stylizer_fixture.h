#pragma once
// The stylizer API tests' fixture: a session's stylizer resource, its scene and frames (small:
// the fixture's image limit is 64 a side).
#include "api_fixture.h"

namespace volstyle::test {

class StylizerApi : public Api {
protected:
    void SetUp() override {
        Api::SetUp();
        if (!m_server) return;
        base = "/api/v1/sessions/" + createSession() + "/stylizer";
    }
    json scene() {
        auto r = client().Get(base.c_str());
        EXPECT_EQ(r->status, 200) << r->body;
        return json::parse(r->body);
    }
    /// The built-in forest at 64×36 (the fixture's image limit is 64).
    json smallForest() {
        json s = scene();
        s["camera"]["width"] = 64;
        s["camera"]["height"] = 36;
        s["light"]["shadow_map_size"] = 512;
        return s;
    }
    httplib::Result putScene(const json& s) { return client().Put(base.c_str(), s.dump(), "application/json"); }
    core::Image frame(const json& request = {{"format", "exr"}}) {
        auto r = client().Post((base + "/frame").c_str(), request.dump(), "application/json");
        EXPECT_EQ(r->status, 200) << r->body;
        return core::loadImageFromMemory(r->body.data(), r->body.size(), "frame").image;
    }
    std::string base;
};

}  // namespace volstyle::test

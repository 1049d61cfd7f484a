// The REST conventions of SPEC §10 (issue #37): 405 with Allow, 404 naming what is missing,
// Location on 201, ETag / If-None-Match / Content-Disposition on downloads, lists with limit and
// a cursor, and Idempotency-Key on the POSTs that create sessions and jobs.
#include <cctype>
#include <functional>
#include <map>
#include <regex>
#include <set>

#include "api_fixture.h"

namespace volstyle::test {
namespace {

/// A small camera looking at the scene.
const json kCamera = {{"eye", {0, 0, 3}}, {"target", {0, 0, 0}}, {"width", 8}, {"height", 8}};

class Rest : public Api {
protected:
    /// Gives session `sid` a view with a flat target; the body of a short solve of it.
    std::string viewWithATarget(const std::string& sid) {
        auto v = client().Post(("/api/v1/sessions/" + sid + "/views").c_str(), json{{"camera", kCamera}}.dump(),
                               "application/json");
        EXPECT_EQ(v->status, 201) << v->body;
        const std::string vid = json::parse(v->body)["id"];
        core::Image target(8, 8);
        for (float& x : target.rgba) x = 0.25f;
        core::SaveOptions exact;
        exact.halfFloat = false;
        auto t = client().Put(("/api/v1/sessions/" + sid + "/views/" + vid + "/target").c_str(), core::encodeImage(target, "exr", exact),
                              "application/octet-stream");
        EXPECT_EQ(t->status, 200) << t->body;
        return json{{"views", {vid}}, {"max_iterations", 2}}.dump();
    }
};

/// The methods of an Allow header.
std::set<std::string> allowOf(const httplib::Result& r) {
    std::set<std::string> out;
    std::string allow = r->get_header_value("Allow");
    for (size_t start = 0; start < allow.size();) {
        size_t end = allow.find(',', start);
        if (end == std::string::npos) end = allow.size();
        std::string m = allow.substr(start, end - start);
        m.erase(0, m.find_first_not_of(' '));
        out.insert(m);
        start = end + 1;
    }
    return out;
}

TEST_F(Rest, AWrongMethodIs405WithTheMethodsThePathHas) {
    const std::string sid = createSession();
    auto r = client().Patch(("/api/v1/sessions/" + sid).c_str(), "{}", "application/json");
    expectError(r, 405, "method_not_allowed");
    EXPECT_EQ(allowOf(r), (std::set<std::string>{"DELETE", "GET", "HEAD", "OPTIONS"}));
    r = client().Put("/api/v1/sessions", "{}", "application/json");
    expectError(r, 405, "method_not_allowed");
    EXPECT_EQ(allowOf(r), (std::set<std::string>{"GET", "HEAD", "OPTIONS", "POST"}));
    r = client().Options(("/api/v1/sessions/" + sid + "/volume.vdb").c_str());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 204);
    EXPECT_EQ(allowOf(r), (std::set<std::string>{"GET", "HEAD", "OPTIONS"}));
}

TEST_F(Rest, A404NamesWhatIsMissing) {
    json e = expectError(client().Get("/api/v1/sessions/nope"), 404, "not_found");
    EXPECT_EQ(e["error"]["message"], "no session 'nope'");
    e = expectError(client().Get("/api/v1/sessions/0123abcd"), 404, "not_found");
    EXPECT_NE(e["error"]["message"].get<std::string>().find("0123abcd"), std::string::npos) << e;
    const std::string sid = createSession();
    e = expectError(client().Get(("/api/v1/sessions/" + sid + "/views/x1").c_str()), 404, "not_found");
    EXPECT_EQ(e["error"]["message"], "no view 'x1' in session '" + sid + "'");
    e = expectError(client().Get("/api/v1/jobs/zz"), 404, "not_found");
    EXPECT_EQ(e["error"]["message"], "no job 'zz'");
    e = expectError(client().Get("/api/v1/bogus"), 404, "not_found");
    EXPECT_NE(e["error"]["message"].get<std::string>().find("no route GET /api/v1/bogus"), std::string::npos) << e;
}

TEST_F(Rest, ACreatedResourceIsNamedInLocation) {
    auto r = client().Post("/api/v1/sessions", json{{"scene", "builtin:sphere"}, {"resolution", 16}}.dump(), "application/json");
    ASSERT_EQ(r->status, 201);
    const std::string sid = json::parse(r->body)["id"];
    EXPECT_EQ(r->get_header_value("Location"), "/api/v1/sessions/" + sid);
    EXPECT_EQ(client().Get(r->get_header_value("Location").c_str())->status, 200);
    r = client().Post(("/api/v1/sessions/" + sid + "/views").c_str(), json{{"camera", kCamera}}.dump(), "application/json");
    ASSERT_EQ(r->status, 201) << r->body;
    EXPECT_EQ(r->get_header_value("Location"), "/api/v1/sessions/" + sid + "/views/" + json::parse(r->body)["id"].get<std::string>());
}

TEST_F(Rest, DownloadsHaveAnETagThatAnswers304) {
    const std::string sid = createSession();
    const std::string path = "/api/v1/sessions/" + sid + "/volume.vdb";
    auto r = client().Get(path.c_str());
    ASSERT_EQ(r->status, 200);
    const std::string etag = r->get_header_value("ETag");
    EXPECT_EQ(etag, "\"" + sid + "-v1\"") << "a version's tag: its bytes differ on every write (OpenVDB's UUID)";
    EXPECT_EQ(r->get_header_value("Content-Disposition"), "attachment; filename=\"volstyle-" + sid.substr(0, 8) + ".vdb\"");
    auto again = client().Get(path.c_str(), {{"If-None-Match", etag}});
    ASSERT_TRUE(again);
    EXPECT_EQ(again->status, 304);
    EXPECT_TRUE(again->body.empty());
    again = client().Get(path.c_str(), {{"If-None-Match", "\"0000000000000000\", W/" + etag}});
    EXPECT_EQ(again->status, 304) << "a weak tag in a list matches too";
    again = client().Get(path.c_str(), {{"If-None-Match", "\"0000000000000000\""}});
    EXPECT_EQ(again->status, 200);
    EXPECT_EQ(again->body.size(), r->body.size());
    // A new version is another file: another tag.
    ASSERT_EQ(client().Post(("/api/v1/sessions/" + sid + "/perturb").c_str(), R"({"amplitude": 1.5, "frequency": 6, "seed": 3})", "application/json")->status,
              200);
    auto changed = client().Get(path.c_str(), {{"If-None-Match", etag}});
    EXPECT_EQ(changed->status, 200);
    EXPECT_NE(changed->get_header_value("ETag"), etag);
}

TEST_F(Rest, ListsPageWithALimitAndACursor) {
    std::vector<std::string> ids;
    for (int i = 0; i < 5; ++i) ids.push_back(createSession(8));
    std::vector<std::string> seen;
    std::string next = "/api/v1/sessions?limit=2";
    int pages = 0;
    while (!next.empty()) {
        auto r = client().Get(next.c_str());
        ASSERT_EQ(r->status, 200) << r->body;
        const json page = json::parse(r->body);
        EXPECT_LE(page.size(), 2u);
        for (const auto& s : page) seen.push_back(s["id"]);
        const std::string link = r->get_header_value("Link");
        next = link.empty() ? "" : link.substr(1, link.find('>') - 1);
        if (!link.empty()) {
            EXPECT_NE(link.find("rel=\"next\""), std::string::npos) << link;
        }
        ASSERT_LT(++pages, 10);
    }
    EXPECT_EQ(pages, 3);
    EXPECT_EQ(std::set<std::string>(seen.begin(), seen.end()), std::set<std::string>(ids.begin(), ids.end()));
    EXPECT_EQ(seen.size(), ids.size()) << "no session twice";
    // A page after a deleted item still continues after it.
    auto first = client().Get("/api/v1/sessions?limit=2");
    const std::string cursor = first->get_header_value("X-Next-Cursor");
    ASSERT_FALSE(cursor.empty());
    ASSERT_EQ(client().Delete(("/api/v1/sessions/" + json::parse(first->body)[1]["id"].get<std::string>()).c_str())->status, 204);
    auto rest = client().Get(("/api/v1/sessions?cursor=" + cursor).c_str());
    EXPECT_EQ(json::parse(rest->body).size(), 3u);
    // Bad values are refused by name, never ignored.
    json e = expectError(client().Get("/api/v1/sessions?limit=0"), 400, "invalid_argument");
    EXPECT_EQ(e["error"]["details"][0]["path"], "?limit");
    expectError(client().Get("/api/v1/sessions?limit=5000"), 400, "invalid_argument");
    expectError(client().Get("/api/v1/sessions?cursor=zz"), 400, "invalid_argument");
    expectError(client().Get("/api/v1/sessions?session=x"), 400, "invalid_argument");
}

TEST_F(Rest, JobsAreListedAndFilteredBySession) {
    const std::string a = createSession(8), b = createSession(8);
    std::set<std::string> jobs;
    for (const std::string& sid : {a, b, a}) {
        auto r = client().Post(("/api/v1/sessions/" + sid + "/solve").c_str(), viewWithATarget(sid), "application/json");
        ASSERT_EQ(r->status, 202) << r->body;
        jobs.insert(json::parse(r->body)["job"].get<std::string>());
    }
    auto all = client().Get("/api/v1/jobs");
    ASSERT_EQ(all->status, 200) << all->body;
    std::set<std::string> listed;
    for (const auto& j : json::parse(all->body)) listed.insert(j["id"].get<std::string>());
    EXPECT_EQ(listed, jobs);
    const json mine = json::parse(client().Get(("/api/v1/jobs?session=" + a).c_str())->body);
    EXPECT_EQ(mine.size(), 2u);
    for (const auto& j : mine) EXPECT_EQ(j["session"], a);
    auto page = client().Get(("/api/v1/jobs?limit=1&session=" + a).c_str());
    EXPECT_EQ(json::parse(page->body).size(), 1u);
    EXPECT_NE(page->get_header_value("Link").find("&session=" + a), std::string::npos) << "the next page keeps the filter";
    expectError(client().Get("/api/v1/jobs?session=nope"), 404, "not_found");
}

TEST_F(Rest, AnIdempotencyKeyMakesARetryTheSameRequest) {
    const std::string body = json{{"scene", "builtin:sphere"}, {"resolution", 8}}.dump();
    const httplib::Headers key{{"Idempotency-Key", "0b6d3f5e-retry-1"}};
    auto first = client().Post("/api/v1/sessions", key, body, "application/json");
    ASSERT_EQ(first->status, 201) << first->body;
    auto retry = client().Post("/api/v1/sessions", key, body, "application/json");
    ASSERT_EQ(retry->status, 201) << retry->body;
    EXPECT_EQ(json::parse(retry->body)["id"], json::parse(first->body)["id"]) << "the same session, not a second one";
    EXPECT_EQ(retry->get_header_value("Idempotent-Replayed"), "true");
    EXPECT_EQ(retry->get_header_value("Location"), first->get_header_value("Location"));
    EXPECT_EQ(json::parse(client().Get("/api/v1/sessions")->body).size(), 1u);
    // The same key with another body is refused; another key is another session.
    expectError(client().Post("/api/v1/sessions", key, json{{"scene", "builtin:cloud"}, {"resolution", 8}}.dump(), "application/json"), 422,
                "idempotency_conflict");
    auto other = client().Post("/api/v1/sessions", {{"Idempotency-Key", "another"}}, body, "application/json");
    ASSERT_EQ(other->status, 201);
    EXPECT_NE(json::parse(other->body)["id"], json::parse(first->body)["id"]);
    expectError(client().Post("/api/v1/sessions", {{"Idempotency-Key", "has space"}}, body, "application/json"), 400, "invalid_argument");
    // A solve: two POSTs with one key are one job.
    const std::string sid = json::parse(first->body)["id"];
    const std::string solve = viewWithATarget(sid);
    const httplib::Headers solveKey{{"Idempotency-Key", "solve-once"}};
    auto job1 = client().Post(("/api/v1/sessions/" + sid + "/solve").c_str(), solveKey, solve, "application/json");
    auto job2 = client().Post(("/api/v1/sessions/" + sid + "/solve").c_str(), solveKey, solve, "application/json");
    ASSERT_EQ(job1->status, 202) << job1->body;
    ASSERT_EQ(job2->status, 202) << job2->body;
    EXPECT_EQ(json::parse(job1->body)["job"], json::parse(job2->body)["job"]);
    EXPECT_EQ(json::parse(client().Get(("/api/v1/jobs?session=" + sid).c_str())->body).size(), 1u);
}

/// An OpenAPI path as a concrete one: each {parameter} replaced by a value of its shape.
std::string samplePath(std::string path) {
    static const std::map<std::string, std::string> kSamples = {{"sid", "0123abcd"}, {"vid", "v1"},   {"jid", "4567cdef"}, {"n", "3"},
                                                                {"i", "0"},         {"rev", "7"},    {"name", "floor"},   {"format", "png"}};
    for (const auto& [name, value] : kSamples)
        for (size_t at; (at = path.find("{" + name + "}")) != std::string::npos;) path.replace(at, name.size() + 2, value);
    return "/api/v1" + path;
}

TEST_F(Rest, TheOpenApiDocumentListsTheServersRoutes) {
    // Issue #37: every route the server registers is in the document and every operation of the
    // document is a route, by method and path.
    auto r = client().Get("/api/v1/openapi.json");
    ASSERT_EQ(r->status, 200);
    const json doc = json::parse(r->body);
    EXPECT_EQ(doc["openapi"], "3.1.0");
    std::vector<std::regex> routes;
    std::vector<std::string> methods;
    std::vector<bool> documented;
    for (const server::RouteEntry& e : m_server->routes()) {
        routes.emplace_back(e.pattern);
        methods.push_back(e.method);
        documented.push_back(false);
    }
    ASSERT_GT(routes.size(), 50u);
    int operations = 0;
    for (const auto& [path, item] : doc["paths"].items())
        for (const auto& [method, operation] : item.items()) {
            ++operations;
            std::string upper = method;
            for (char& ch : upper) ch = char(std::toupper(ch));
            const std::string sample = samplePath(path);
            bool found = false;
            for (size_t k = 0; k < routes.size(); ++k)
                if (methods[k] == upper && std::regex_match(sample, routes[k])) found = true, documented[k] = true;
            EXPECT_TRUE(found) << upper << " " << path << " is in the document but the server has no such route";
            for (const auto& [status, answer] : operation["responses"].items()) EXPECT_TRUE(answer.is_object()) << path << " " << status;
        }
    for (size_t k = 0; k < routes.size(); ++k)
        EXPECT_TRUE(documented[k]) << methods[k] << " " << m_server->routes()[k].pattern << " is a route the document does not list";
    EXPECT_EQ(size_t(operations), routes.size());
    // The bodies' schemas are the JSON Schema's definitions, and every reference resolves.
    const json& schemas = doc["components"]["schemas"];
    EXPECT_TRUE(schemas.contains("session") && schemas.contains("solve_options") && schemas.contains("error"));
    std::function<void(const json&)> checkRefs = [&](const json& j) {
        if (j.is_object()) {
            for (const auto& [key, value] : j.items()) {
                if (key == "$ref") {
                    const std::string ref = value;
                    ASSERT_EQ(ref.rfind("#/", 0), 0u) << ref;
                    EXPECT_NO_THROW((void)doc.at(json::json_pointer(ref.substr(1)))) << ref << " does not resolve";
                } else {
                    checkRefs(value);
                }
            }
        } else if (j.is_array()) {
            for (const auto& v : j) checkRefs(v);
        }
    };
    checkRefs(doc);
}

}  // namespace
}  // namespace volstyle::test

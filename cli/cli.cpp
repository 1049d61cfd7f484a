#include "cli/cli.h"

#include <algorithm>
#include <cstdlib>
#include <cmath>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/base/errors.h"
#include "core/image/image_io.h"
#include "core/volume/builtin_scenes.h"
#include "protocol/render_json.h"

namespace volstyle::cli {

std::string Arguments::get(const std::string& name, const std::string& fallback) const {
    auto it = options.find(name);
    return it == options.end() ? fallback : it->second;
}

double parseNumber(const std::string& flag, const std::string& text) {
    size_t used = 0;
    double v = 0;
    try {
        v = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != text.size() || !std::isfinite(v))
        throw InvalidArgument("--" + flag + " must be a number, got '" + text + "'");
    return v;
}

double Arguments::number(const std::string& name, double fallback) const {
    return has(name) ? parseNumber(name, get(name)) : fallback;
}

Arguments parseArguments(const std::vector<std::string>& args, const std::vector<std::string>& known,
                         const std::vector<std::string>& flags) {
    auto isIn = [](const std::vector<std::string>& v, const std::string& s) {
        return std::find(v.begin(), v.end(), s) != v.end();
    };
    Arguments out;
    for (size_t i = 0; i < args.size(); ++i) {
        std::string a = args[i];
        if (a.size() < 2 || a[0] != '-') {
            out.positional.push_back(a);
            continue;
        }
        std::string name = a == "-o" ? "output" : a.substr(a.rfind("--", 0) == 0 ? 2 : 1);
        std::string value;
        bool hasValue = false;
        if (auto eq = name.find('='); eq != std::string::npos) {
            value = name.substr(eq + 1);
            name = name.substr(0, eq);
            hasValue = true;
        }
        if (!isIn(known, name) && !isIn(flags, name)) {
            std::string list;
            for (const auto& k : known) list += " --" + k;
            for (const auto& f : flags) list += " --" + f;
            throw InvalidArgument("unknown option '" + a + "'; options:" + list);
        }
        if (isIn(flags, name)) {
            out.options[name] = "1";
            continue;
        }
        if (!hasValue) {
            if (i + 1 >= args.size()) throw InvalidArgument("option '" + a + "' needs a value");
            value = args[++i];
        }
        out.options[name] = value;
    }
    return out;
}

void requireParentFolder(const std::string& outputPath) {
    const std::filesystem::path folder = std::filesystem::path(outputPath).parent_path();
    std::error_code ec;
    if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
        throw IoError("no such folder '" + folder.string() + "' for '" + outputPath + "' (create it first)");
}

std::string imageOutputPath(const Arguments& args) {
    if (!args.has("output")) throw InvalidArgument("-o OUT.png|OUT.exr is required");
    const std::string output = args.get("output");
    const std::string ext = std::filesystem::path(output).extension().string();
    if (ext != ".png" && ext != ".exr") throw InvalidArgument("-o must end in .png or .exr, got '" + output + "'");
    requireParentFolder(output);  // before the work, not after it
    return output;
}

std::string usageText(const CommandSpec& spec) {
    std::ostringstream s;
    s << "usage: volstyle " << spec.name << " " << spec.synopsis << "\n\n" << spec.summary << "\n";
    if (!spec.options.empty()) {
        s << "\noptions:\n";
        size_t width = 0;
        auto head = [](const OptionSpec& o) {
            std::string h = (o.name == "output" ? "-o, --output" : "--" + o.name);
            return o.value.empty() ? h : h + " " + o.value;
        };
        for (const auto& o : spec.options) width = std::max(width, head(o).size());
        for (const auto& o : spec.options) {
            const std::string h = head(o);
            s << "  " << h << std::string(width - h.size() + 2, ' ') << o.help << "\n";
        }
        s << "  --help" << std::string(width > 4 ? width - 4 : 2, ' ') << "this text\n";
    }
    if (!spec.examples.empty()) s << "\nexamples:\n" << spec.examples;
    return s.str();
}

bool printHelpIfAsked(const Arguments& args, const CommandSpec& spec) {
    if (!args.has("help")) return false;
    std::cout << usageText(spec);
    return true;
}

Arguments parseArguments(const std::vector<std::string>& args, const CommandSpec& spec) {
    std::vector<std::string> known, flags{"help"};
    for (const auto& o : spec.options) (o.value.empty() ? flags : known).push_back(o.name);
    return parseArguments(args, known, flags);
}

std::string defaultWebDir() {
    namespace fs = std::filesystem;
    std::vector<fs::path> candidates;
    if (const char* env = std::getenv("VOLSTYLE_WEB_DIR")) candidates.emplace_back(env);
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) candidates.push_back(exe.parent_path().parent_path() / "share" / "volstyle" / "web");
    candidates.emplace_back(fs::path(VOLSTYLE_INSTALL_DATADIR) / "web");
    candidates.emplace_back(VOLSTYLE_SOURCE_WEB_DIR);
    for (const auto& dir : candidates)
        if (fs::is_regular_file(dir / "index.html", ec)) return fs::absolute(dir, ec).lexically_normal().string();
    return "";
}

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, sep);)
        if (!item.empty()) out.push_back(item);
    return out;
}

std::vector<double> numbers(const std::string& flag, const std::string& value, size_t count) {
    std::vector<double> out;
    for (const auto& part : split(value, ',')) out.push_back(parseNumber(flag, part));
    if (out.size() != count)
        throw InvalidArgument("--" + flag + " takes " + std::to_string(count) + " comma-separated numbers, got '" + value + "'");
    return out;
}

void applyGlassOption(const Arguments& args, core::Volume& volume) {
    if (!args.has("glass")) return;
    const auto parts = split(args.get("glass"), ',');
    if (parts.empty() || parts.size() > 3) throw InvalidArgument("--glass takes N, N,R or N,R,NOISE, got '" + args.get("glass") + "'");
    core::GlassSphere g;
    g.index = parseNumber("glass", parts[0]);
    if (parts.size() > 1) g.radius = parseNumber("glass", parts[1]);
    if (parts.size() > 2) g.noise = parseNumber("glass", parts[2]);
    g.noise = std::min(g.noise, std::max(g.index - 1, 0.0));  // the default noise on a weak glass: n stays >= 1
    for (const auto& [field, message] : g.check()) throw InvalidArgument("--glass: " + field + " " + message);
    core::addGlassSphere(volume, g);
}

nlohmann::json readJsonFile(const std::string& path) {
    std::ifstream f(path);
    if (!f) {
        std::error_code ec;
        if (!std::filesystem::exists(path, ec)) throw IoError("no such file '" + path + "'");
        throw IoError("cannot read '" + path + "' (permission denied?)");
    }
    std::stringstream s;
    s << f.rdbuf();
    try {
        return protocol::parseJson(s.str(), "'" + path + "'");
    } catch (const protocol::ValidationError& e) {
        throw InvalidArgument(e.what());
    }
}

core::Lighting lightingFromJsonFile(const nlohmann::json& j, const std::string& jsonPath, const std::string& pointer) {
    auto request = protocol::lightingFromJson(j, pointer, /*allowFilePaths=*/true);
    // A lat-long map next to the JSON file, refused (naming the field) unless 2:1, finite, >= 0.
    auto loadMap = [&](const std::string& file, const std::string& field) {
        const auto path = std::filesystem::path(jsonPath).parent_path() / file;
        auto map = std::make_shared<core::Image>(core::loadImage(path.string()).image);
        if (std::string why = core::latLongMapProblem(*map); !why.empty())
            throw InvalidArgument(pointer + field + ": '" + path.string() + "': " + why);
        return map;
    };
    if (request.environmentPath) request.lighting.background.environment = loadMap(*request.environmentPath, "/background/environment");
    if (request.environmentLightPath) {  // the map the lobes are fitted to (environment.map)
        request.lighting.environment.map = loadMap(*request.environmentLightPath, "/environment/map");
        request.lighting.environment.radiance.clear();  // projected from the map
    }
    return request.lighting;
}

}  // namespace volstyle::cli

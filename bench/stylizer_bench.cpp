// bench/stylizer: the light-shaft stylizer at 1920×1080 on the built-in forest (issue #11), the
// counterpart of the GI paper's Tables 1–2:
//   Table 1 — per shadow-map size (512/1024/2048): ms of the shadow maps (+ holes on the
//             canopies), the min-max mipmap, the G-buffer, the per-pixel pass (V̄, scattering,
//             surfaces) with and without a transfer function, for the accelerated V̄ and the
//             naive one (1024 lookups), and the accelerated V̄'s difference from the naive one;
//             the four passes render in turn each round, and speed-ups are taken within rounds.
//   Time against error — the naive V̄ at 64–4096 steps against the accelerated one (exact
//             against the map) on the 2048² map.
//   Table 2 — the closing of a 2048² map per kernel radius (box and disc).
// --live: the live stream's read-back alone (issue #40) at 960×540 and 1920×1080: the frame as
// floats then converted and encoded on the CPU, against display bytes packed on the GPU into a
// read-back slot (core::gl::ReadbackRing) and encoded from there.
// Usage: stylizer_bench [--quick] [--accelerated-only] [--reps N] [--table1-only SM] [--live]. Prints tables,
// then one JSON line per row (--accelerated-only: Table 1's accelerated columns alone, for
// profiling; --table1-only: Table 1 for one map size and nothing else, for repeated runs).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <iostream>
#include <random>
#include <sstream>

#include "bench_util.h"
#include "core/base/stopwatch.h"
#include "core/gl/readback_ring.h"
#include "core/gpu/gpu_device.h"
#include "core/image/jpeg_encoder.h"
#include "core/stylize/morphology.h"
#include "core/stylize/stylizer.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

struct Times {
    double shadow = 0, mipmap = 0, gbuffer = 0, shade = 0, total = 0;
    double mipmapGpu = 0, shadeGpu = 0;  // GPU time alone (timer queries)
};

Times timesOf(const StylizedFrame& f) {
    return {f.shadowMs, f.mipmapMs, f.gbufferMs, f.shadeMs, f.totalMs, f.mipmapGpuMs, f.shadeGpuMs};
}

Times medianOf(const std::vector<Times>& rounds) {
    const auto med = [&](double Times::*field) {
        std::vector<double> v;
        for (const Times& t : rounds) v.push_back(t.*field);
        return bench::median(v);
    };
    return {med(&Times::shadow), med(&Times::mipmap),    med(&Times::gbuffer), med(&Times::shade),
            med(&Times::total),  med(&Times::mipmapGpu), med(&Times::shadeGpu)};
}

struct Config {
    const StylizerScene* scene;
    StylizeSettings settings;
};

/// Every config rendered once per round, `reps` rounds after one that compiles the kernels; the
/// result holds each config's times per round. This VM's speed drifts by ±10% within a minute:
/// a round puts the same drift on all its configs, so ratios taken within a round hold where
/// ratios of separately taken medians did not. `last` gets each config's last frame.
std::vector<std::vector<Times>> interleavedRounds(Stylizer& stylizer, const std::vector<Config>& configs, int reps,
                                                  std::vector<StylizedFrame>* last) {
    std::vector<std::vector<Times>> rounds(configs.size());
    std::vector<StylizedFrame> frames(configs.size());
    for (int r = 0; r <= reps; ++r)
        for (size_t c = 0; c < configs.size(); ++c) {
            frames[c] = stylizer.render(*configs[c].scene, configs[c].settings);
            if (r > 0) rounds[c].push_back(timesOf(frames[c]));
        }
    if (last) *last = std::move(frames);
    return rounds;
}

/// Medians over `reps` renders (after one to compile the kernels).
Times timeRenders(Stylizer& stylizer, const StylizerScene& scene, const StylizeSettings& settings, int reps, StylizedFrame* last) {
    std::vector<StylizedFrame> frames;
    const Times t = medianOf(interleavedRounds(stylizer, {{&scene, settings}}, reps, last ? &frames : nullptr)[0]);
    if (last) *last = std::move(frames[0]);
    return t;
}

/// The median over rounds of a ratio taken within each round.
double medianRatio(const std::vector<std::vector<Times>>& rounds, const std::function<double(size_t round)>& ratio) {
    std::vector<double> v;
    for (size_t r = 0; r < rounds[0].size(); ++r) v.push_back(ratio(r));
    return bench::median(v);
}

struct Difference {
    double max = 0, p999 = 0, mean = 0;
};

Difference visibilityDifference(const Image& a, const Image& b) {
    std::vector<double> d;
    for (size_t i = 0; i < a.pixelCount(); ++i) d.push_back(std::abs(a.rgba[4 * i] - b.rgba[4 * i]));
    std::sort(d.begin(), d.end());
    double sum = 0;
    for (double v : d) sum += v;
    return {d.back(), d[d.size() * 999 / 1000], sum / double(d.size())};
}

/// A number for the JSON lines: null where it is not finite (a ratio over a timer that read 0;
/// JSON has no inf or nan).
std::string jsonNumber(double v) { return std::isfinite(v) ? std::to_string(v) : "null"; }

std::shared_ptr<const Image> warmTransferFunction() {
    auto img = std::make_shared<Image>(64, 64);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            float* p = img->pixel(x, y);
            p[0] = 1.0f, p[1] = 0.6f + 0.4f * float(x) / 63, p[2] = 0.3f + 0.7f * float(y) / 63, p[3] = 1;
        }
    return img;
}

}  // namespace

/// The live stream's read-back (see the file's comment): median of 5 frames each way.
void liveReadback(Stylizer& stylizer) {
    StylizerScene scene = builtinForest();
    StylizeSettings lean;
    readBackOnly(lean, StylizerOutput::Frame);
    gl::ReadbackRing ring(2);
    std::cout << "Live read-back: forest, frame only; ms, median of 5 (read-back is the frame's, encode is the JPEG q90's)\n"
              << "  size        floats: read-back  convert+encode  | display bytes: pack+fence  encode\n";
    for (auto [w, h] : {std::pair{960, 540}, std::pair{1920, 1080}}) {
        scene.camera.width = w, scene.camera.height = h;
        std::vector<double> fr, fe, dr, de;
        for (int i = 0; i < 6; ++i) {
            const StylizedFrame a = stylizer.render(scene, lean);
            auto t = Clock::now();
            (void)encodeJpeg(a.frame, 90);
            const double aEncode = msSince(t);
            const DisplayReadback display{&ring, 0};
            const StylizedFrame b = stylizer.render(scene, lean, nullptr, &display);
            t = Clock::now();
            (void)encodeJpegRgbx(b.displayBytes, w, h, 90);
            const double bEncode = msSince(t);
            ring.release(b.displaySlot);
            if (i == 0) continue;  // compiles the variants
            fr.push_back(a.readbackMs), fe.push_back(aEncode), dr.push_back(b.readbackMs), de.push_back(bEncode);
        }
        auto median = [](std::vector<double> v) { std::sort(v.begin(), v.end()); return v[v.size() / 2]; };
        std::printf("  %4dx%-4d   %17.1f  %14.1f  | %25.1f  %6.1f\n", w, h, median(fr), median(fe), median(dr), median(de));
    }
}

int main(int argc, char** argv) {
    bool quick = false, acceleratedOnly = false, live = false;
    int reps = 2, onlySize = 0;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--quick")) quick = true;
        else if (!std::strcmp(argv[i], "--accelerated-only")) acceleratedOnly = true;
        else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--table1-only") && i + 1 < argc) onlySize = std::clamp(std::atoi(argv[++i]), 512, 4096);
        else if (!std::strcmp(argv[i], "--live")) live = true;
        else {
            std::cerr << "usage: stylizer_bench [--quick] [--accelerated-only] [--reps N] [--table1-only SM] [--live]\n";
            return 2;
        }
    }
    spdlog::set_level(spdlog::level::warn);
    auto device = GpuDevice::create();
    Stylizer stylizer(*device);
    if (live) {
        std::cout << "device: " << device->capabilities().renderer << "\n";
        liveReadback(stylizer);
        return 0;
    }
    StylizerScene scene = builtinForest();
    scene.camera.width = quick ? 960 : 1920;
    scene.camera.height = quick ? 540 : 1080;
    for (Occluder& o : scene.occluders)
        if (o.name != "ground") o.manipulation.holeProbability = 0.3;
    std::vector<std::string> json;
    const bool gpuTimers = !device->capabilities().isSoftware;  // llvmpipe's timer queries read ~0
    std::cout << "device: " << device->capabilities().renderer << "\n";
    std::cout << "Table 1: forest " << scene.camera.width << "x" << scene.camera.height
              << ", holes on the canopies; ms, median of " << reps
              << " rounds (each renders the four passes in turn; speed-ups are medians of per-round ratios)\n";
    std::cout << "  SM    shadow+holes  mipmap  G-buffer  pass(acc)  pass(acc,TF)  pass(naive 1024)  pass(V̄ 1 lookup)  total(acc)  speed-up pass  V̄(naive) V̄(acc) speed-up V̄  V̄ max / p99.9 / mean diff\n";
    const std::vector<int> sizes = onlySize ? std::vector<int>{onlySize} : quick ? std::vector<int>{512, 1024} : std::vector<int>{512, 1024, 2048};
    for (int sm : sizes) {
        scene.light.shadowMapSize = sm;
        StylizeSettings acc, naive;
        naive.method = VisibilityMethod::Naive;
        naive.steps = 1024;
        if (acceleratedOnly) {  // for profiling the accelerated pass: no naive, no other tables
            const Times ta = timeRenders(stylizer, scene, acc, reps, nullptr);
            std::printf("  %-5d %12.1f %7.1f %9.1f %10.1f\n", sm, ta.shadow, ta.mipmap, ta.gbuffer, ta.shade);
            continue;
        }
        StylizerScene withTf = scene;
        withTf.transferFunction = TransferFunction{warmTransferFunction(), TransferFunction::Mode::Multiply, 0, 40};
        // The pass with a one-lookup V̄: everything but V̄ (G-buffer reads, surfaces, scattering,
        // writes). V̄'s own cost is a pass's time over it (the paper's "Scattering Vis." column).
        StylizeSettings base = naive;
        base.steps = 1;
        std::vector<StylizedFrame> frames;
        const auto rounds = interleavedRounds(stylizer, {{&scene, acc}, {&withTf, acc}, {&scene, naive}, {&scene, base}}, reps, &frames);
        const StylizedFrame &a = frames[0], &b = frames[2];
        const Times ta = medianOf(rounds[0]), tf = medianOf(rounds[1]), tn = medianOf(rounds[2]), t1 = medianOf(rounds[3]);
        const double vNaive = tn.shade - t1.shade, vAcc = ta.mipmap + ta.shade - t1.shade;
        const double vSpeedup = medianRatio(rounds, [&](size_t r) {
            return (rounds[2][r].shade - rounds[3][r].shade) / (rounds[0][r].mipmap + rounds[0][r].shade - rounds[3][r].shade);
        });
        const double passSpeedup = medianRatio(rounds, [&](size_t r) { return rounds[2][r].shade / (rounds[0][r].mipmap + rounds[0][r].shade); });
        // The same from the GPU's own clock (timer queries): on a GPU the wall clock of a 1 ms
        // pass is mostly the driver's latency.
        const double gNaive = tn.shadeGpu - t1.shadeGpu, gAcc = ta.mipmapGpu + ta.shadeGpu - t1.shadeGpu;
        const Difference d = visibilityDifference(a.averageVisibility, b.averageVisibility);
        char line[640];
        std::snprintf(line, sizeof line, "  %-5d %12.1f %7.1f %9.1f %10.1f %13.1f %17.1f %18.1f %11.1f %12.1fx %9.1f %7.1f %9.1fx  %.4f / %.4f / %.5f\n", sm,
                      ta.shadow, ta.mipmap, ta.gbuffer, ta.shade, tf.shade, tn.shade, t1.shade, ta.total, passSpeedup, vNaive,
                      vAcc, vSpeedup, d.max, d.p999, d.mean);
        std::cout << line;
        if (gpuTimers)
            std::printf("        GPU time: mipmap %.3f, pass acc %.3f, naive 1024 %.3f, V̄ 1 lookup %.3f; V̄ naive %.3f, acc %.3f: %.1fx\n", ta.mipmapGpu,
                        ta.shadeGpu, tn.shadeGpu, t1.shadeGpu, gNaive, gAcc, gNaive / gAcc);
        std::ostringstream js;
        js << "{\"table\":1,\"sm\":" << sm << ",\"shadow_ms\":" << ta.shadow << ",\"mipmap_ms\":" << ta.mipmap << ",\"gbuffer_ms\":" << ta.gbuffer
           << ",\"pass_accelerated_ms\":" << ta.shade << ",\"pass_accelerated_tf_ms\":" << tf.shade << ",\"pass_naive1024_ms\":" << tn.shade << ",\"pass_vbar_1_lookup_ms\":" << t1.shade << ",\"vbar_speedup\":" << jsonNumber(vSpeedup) << ",\"gpu_mipmap_ms\":" << ta.mipmapGpu << ",\"gpu_pass_accelerated_ms\":" << ta.shadeGpu
           << ",\"gpu_pass_naive1024_ms\":" << tn.shadeGpu << ",\"gpu_pass_vbar_1_lookup_ms\":" << t1.shadeGpu << ",\"gpu_vbar_speedup\":" << jsonNumber(gNaive / gAcc)
           << ",\"vbar_max_diff\":" << d.max << ",\"vbar_p999_diff\":" << d.p999 << ",\"vbar_mean_diff\":" << d.mean << "}";
        json.push_back(js.str());
    }

    if (acceleratedOnly || onlySize) {
        for (const std::string& line : json) std::cout << line << "\n";
        return 0;
    }
    scene.light.shadowMapSize = quick ? 1024 : 2048;
    std::cout << "\nTime against error: naive V̄ vs the accelerated (exact against the " << scene.light.shadowMapSize << "² map)\n";
    std::cout << "  method          pass ms   V̄ max diff   p99.9     mean\n";
    StylizedFrame exact;
    const Times te = timeRenders(stylizer, scene, {}, reps, &exact);
    const auto gpuMs = [&](double ms) { return gpuTimers ? "   (GPU " + std::to_string(ms).substr(0, 6) + " ms)" : std::string(); };
    std::printf("  accelerated  %10.1f   (reference)%s\n", te.mipmap + te.shade, gpuMs(te.mipmapGpu + te.shadeGpu).c_str());
    for (int steps : quick ? std::vector<int>{64, 256, 1024} : std::vector<int>{64, 256, 1024, 4096}) {
        StylizeSettings naive;
        naive.method = VisibilityMethod::Naive;
        naive.steps = steps;
        StylizedFrame f;
        const Times t = timeRenders(stylizer, scene, naive, 1, &f);
        const Difference d = visibilityDifference(f.averageVisibility, exact.averageVisibility);
        std::printf("  naive %5d  %10.1f   %.5f     %.5f  %.6f%s\n", steps, t.shade, d.max, d.p999, d.mean, gpuMs(t.shadeGpu).c_str());
        std::ostringstream js;
        js << "{\"table\":\"time_error\",\"sm\":" << scene.light.shadowMapSize << ",\"steps\":" << steps << ",\"pass_ms\":" << t.shade
           << ",\"vbar_max_diff\":" << d.max << ",\"vbar_p999_diff\":" << d.p999 << ",\"vbar_mean_diff\":" << d.mean << "}";
        json.push_back(js.str());
    }

    const int n = quick ? 1024 : 2048;
    std::cout << "\nTable 2: closing a " << n << "² shadow map (dilation + erosion), ms (median of " << reps << ")\n";
    std::cout << "  radius     box    disc\n";
    std::mt19937 rng(5);
    std::vector<float> map(size_t(n) * n);
    for (float& v : map) v = rng() % 3 == 0 ? 1.0f : 0.3f + 0.5f * float(rng() % 1000) / 1000.0f;
    auto timeClosing = [&](int radius, MorphShape shape) {
        std::vector<double> ms;
        (void)closingOnGpu(*device, map, n, radius, shape);  // compiles, and is the upload + read-back floor at r = 0
        for (int r = 0; r < reps; ++r) {
            const auto t0 = Clock::now();
            (void)closingOnGpu(*device, map, n, radius, shape);
            ms.push_back(msSince(t0));
        }
        return bench::median(ms);
    };
    const double floorMs = timeClosing(0, MorphShape::Box);
    std::printf("  (upload + read-back, subtracted: %.1f ms)\n", floorMs);
    for (int radius : {1, 2, 4, 8, 16, 32}) {
        const double box = timeClosing(radius, MorphShape::Box) - floorMs, disc = timeClosing(radius, MorphShape::Disc) - floorMs;
        std::printf("  %6d %7.1f %7.1f\n", radius, box, disc);
        std::ostringstream js;
        js << "{\"table\":2,\"n\":" << n << ",\"radius\":" << radius << ",\"box_ms\":" << box << ",\"disc_ms\":" << disc << "}";
        json.push_back(js.str());
    }
    std::cout << "\n";
    for (const std::string& j : json) std::cout << j << "\n";
    return 0;
}

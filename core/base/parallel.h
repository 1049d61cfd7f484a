#pragma once
/// \file parallel.h
/// Work split over the machine's cores by plain threads, not TBB: their joins are the
/// happens-before edges ThreadSanitizer sees (it cannot see inside the uninstrumented TBB
/// scheduler, and reported every read after a parallel_for as a race).

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace volstyle::core {

/// Runs work(chunk, lo, hi) for the chunks [lo, hi) of [0, count), `chunk` items each (the last
/// fewer), taken in turn by one thread per core: items of unequal cost (rows of a matrix, slices
/// of a scene) keep every core busy. `chunk`'s index is lo / chunk, so per-chunk results can be
/// combined in a fixed order whichever thread ran them. `work` must not throw.
template <typename Work>
void forEachChunk(size_t count, size_t chunk, const Work& work) {
    chunk = std::max<size_t>(chunk, 1);
    const size_t chunks = (count + chunk - 1) / chunk;
    const size_t workers = std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()), chunks);
    std::atomic<size_t> next{0};
    auto run = [&] {
        for (size_t c; (c = next.fetch_add(1)) < chunks;) work(c, c * chunk, std::min(count, (c + 1) * chunk));
    };
    std::vector<std::thread> helpers;
    try {
        for (size_t w = 1; w < workers; ++w) helpers.emplace_back(run);
    } catch (...) {  // a thread that could not start: the ones that did finish the work
    }
    run();
    for (auto& t : helpers) t.join();
}

}  // namespace volstyle::core

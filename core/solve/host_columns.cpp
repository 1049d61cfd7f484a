#include "core/solve/host_columns.h"

#include <algorithm>
#include <memory>

#include "core/base/errors.h"
#include "core/gl/mapped_buffer.h"

namespace volstyle::core {

uint64_t exclusiveScan(std::vector<uint32_t>& counts) {
    uint64_t total = 0;
    for (auto& c : counts) {
        const uint64_t n = c;
        c = uint32_t(std::min<uint64_t>(total, 0xffffffffu));
        total += n;
    }
    counts.push_back(uint32_t(std::min<uint64_t>(total, 0xffffffffu)));
    return total;
}

void transposeOnHost(SparseRows& r, const std::vector<uint32_t>& rowStart) {
    VOLSTYLE_CHECK(r.hostMapped, ==, true);
    const size_t ch = size_t(r.channels), E = r.entries;
    // In place: a copy out and back of the 10 M entries of a 480² view cost ~200 ms of the
    // transpose's ~300 on llvmpipe (bench/solver_race (b)).
    const gl::MappedBuffer rowIndexMap(r.rowIndex, 4 * E, GL_MAP_READ_BIT), rowWeightMap(r.rowWeight, 4 * E * ch, GL_MAP_READ_BIT);
    const uint32_t* rowIndex = rowIndexMap.as<const uint32_t>();
    const float* rowWeight = rowWeightMap.as<const float>();
    std::vector<uint32_t> colStart(r.columns, 0);
    for (size_t k = 0; k < E; ++k) ++colStart[rowIndex[k]];
    exclusiveScan(colStart);
    std::vector<uint32_t> cursor(colStart.begin(), colStart.end() - 1);
    {
        // Every slot is written once (all E entries are placed): no clearing first.
        const gl::MappedBuffer colIndexMap(r.colIndex, 4 * E, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
        const gl::MappedBuffer colWeightMap(r.colWeight, 4 * E * ch, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
        uint32_t* colIndex = colIndexMap.as<uint32_t>();
        float* colWeight = colWeightMap.as<float>();
        for (size_t p = 0; p < r.rows; ++p)
            for (size_t k = rowStart[p]; k < rowStart[p + 1]; ++k) {
                const uint32_t j = cursor[rowIndex[k]]++;
                colIndex[j] = uint32_t(p);
                std::copy_n(&rowWeight[k * ch], ch, &colWeight[size_t(j) * ch]);
            }
    }
    gl::writeBuffer(r.colStart, 0, 4 * colStart.size(), colStart.data());
}

void mergeColumnsOnHost(SparseRows& merged, const std::vector<uint32_t>& colStart, const std::vector<const SparseRows*>& views,
                        const std::vector<size_t>& offsets) {
    VOLSTYLE_CHECK(merged.hostMapped, ==, true);
    VOLSTYLE_CHECK(views.size(), ==, offsets.size());
    const size_t ch = size_t(merged.channels), E = merged.entries, C = merged.columns;
    struct Source {
        const uint32_t *start, *index;
        const float* weight;
        uint32_t offset;
    };
    std::vector<std::unique_ptr<gl::MappedBuffer>> maps;
    std::vector<Source> sources;
    for (size_t v = 0; v < views.size(); ++v) {
        const SparseRows& r = *views[v];
        VOLSTYLE_CHECK(r.hostMapped, ==, true);
        if (r.entries == 0) continue;
        maps.push_back(std::make_unique<gl::MappedBuffer>(r.colStart, 4 * (C + 1), GL_MAP_READ_BIT));
        const auto* start = maps.back()->as<const uint32_t>();
        maps.push_back(std::make_unique<gl::MappedBuffer>(r.colIndex, 4 * r.entries, GL_MAP_READ_BIT));
        const auto* index = maps.back()->as<const uint32_t>();
        maps.push_back(std::make_unique<gl::MappedBuffer>(r.colWeight, 4 * r.entries * ch, GL_MAP_READ_BIT));
        sources.push_back({start, index, maps.back()->as<const float>(), uint32_t(offsets[v])});
    }
    const gl::MappedBuffer indexMap(merged.colIndex, 4 * E, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
    const gl::MappedBuffer weightMap(merged.colWeight, 4 * E * ch, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
    uint32_t* index = indexMap.as<uint32_t>();
    float* weight = weightMap.as<float>();
    for (size_t e = 0; e < C; ++e) {
        size_t j = colStart[e];
        for (const Source& s : sources) {
            const uint32_t begin = s.start[e], end = s.start[e + 1];
            for (uint32_t k = begin; k < end; ++k) index[j + (k - begin)] = s.index[k] + s.offset;
            std::copy(s.weight + size_t(begin) * ch, s.weight + size_t(end) * ch, weight + j * ch);
            j += end - begin;
        }
    }
}

std::shared_ptr<const SparseRows> restrictRowsOnHost(std::shared_ptr<const SparseRows> all, const std::vector<uint8_t>& keep) {
    VOLSTYLE_CHECK(all->hostMapped, ==, true);
    VOLSTYLE_CHECK(keep.size(), ==, all->rows);
    const size_t ch = size_t(all->channels), P = all->rows;
    std::vector<uint32_t> start(P + 1);
    {
        const gl::MappedBuffer startMap(all->rowStart, 4 * (P + 1), GL_MAP_READ_BIT);
        std::copy_n(startMap.as<const uint32_t>(), P + 1, start.data());
    }
    std::vector<uint32_t> counts(P);
    bool dropsEntries = false;
    for (size_t p = 0; p < P; ++p) {
        counts[p] = keep[p] ? start[p + 1] - start[p] : 0;
        dropsEntries |= !keep[p] && start[p + 1] > start[p];
    }
    if (!dropsEntries) return all;
    const uint64_t entries = exclusiveScan(counts);
    auto r = std::make_shared<SparseRows>();
    r->rows = P, r->columns = all->columns, r->entries = entries, r->channels = all->channels, r->hostMapped = true;
    r->buildMs = all->buildMs;  // what a miss costs: writing them again
    r->rowStart = gl::createBuffer(4 * counts.size(), counts.data(), kHostMappedStorage, "rows-start");
    r->colStart = gl::createBuffer(4 * (r->columns + 1), nullptr, kHostMappedStorage, "columns-start");
    r->rowIndex = gl::createBuffer(std::max<size_t>(4 * entries, 4), nullptr, kHostMappedStorage, "rows-index");
    r->rowWeight = gl::createBuffer(std::max<size_t>(4 * entries * ch, 4), nullptr, kHostMappedStorage, "rows-weight");
    r->colIndex = gl::createBuffer(std::max<size_t>(4 * entries, 4), nullptr, kHostMappedStorage, "columns-index");
    r->colWeight = gl::createBuffer(std::max<size_t>(4 * entries * ch, 4), nullptr, kHostMappedStorage, "columns-weight");
    if (entries > 0) {
        const gl::MappedBuffer fromIndex(all->rowIndex, 4 * all->entries, GL_MAP_READ_BIT);
        const gl::MappedBuffer fromWeight(all->rowWeight, 4 * all->entries * ch, GL_MAP_READ_BIT);
        const gl::MappedBuffer toIndex(r->rowIndex, 4 * entries, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
        const gl::MappedBuffer toWeight(r->rowWeight, 4 * entries * ch, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
        for (size_t p = 0; p < P; ++p) {
            if (!keep[p]) continue;
            const size_t n = start[p + 1] - start[p];
            std::copy_n(fromIndex.as<const uint32_t>() + start[p], n, toIndex.as<uint32_t>() + counts[p]);
            std::copy_n(fromWeight.as<const float>() + size_t(start[p]) * ch, n * ch, toWeight.as<float>() + size_t(counts[p]) * ch);
        }
    }
    transposeOnHost(*r, counts);
    return r;
}

}  // namespace volstyle::core

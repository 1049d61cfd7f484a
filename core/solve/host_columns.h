#pragma once
/// \file host_columns.h
/// The columns of W made on the host, on a CPU rasterizer (issue #40). There, the fill pass's
/// per-entry column atomics and scattered stores cost more than the march itself, and a
/// GPU-side merge of the views' columns is a scattered copy too. The host reads and writes the
/// buffers in place (mapped: on a CPU rasterizer they are the process's memory), so neither
/// step copies the entries through a staging buffer. GPUs build columns on the device instead
/// (project.comp's fill, sparse_merge.comp). GL thread only.

#include <epoxy/gl.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "core/solve/sparse_rows.h"

namespace volstyle::core {

/// Storage flags of a SparseRows' buffers the host reads or writes in place (SparseRows::hostMapped).
constexpr GLbitfield kHostMappedStorage = GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT | GL_MAP_WRITE_BIT;

/// Counts in place → exclusive prefix sums with the total appended; the total (a start past
/// 2³² − 1 saturates there: callers refuse such sizes).
uint64_t exclusiveScan(std::vector<uint32_t>& counts);

/// `r`'s columns from its rows (`rowStart`: its rows' starts, with the total appended): each
/// column's entries counted (its start written to r.colStart), then placed by a counting sort by
/// element, each column's entries in row order. `r` must be hostMapped. A slot a ray left
/// unfilled (element 0, weight 0) becomes a weight-0 entry of column 0.
void transposeOnHost(SparseRows& r, const std::vector<uint32_t>& rowStart);

/// `merged`'s columns from the views' (each hostMapped): for each element, every view's entries of
/// its column in view order, their pixels shifted by the view's first pixel (`offsets`).
/// `colStart` is the merged columns' starts; merged.colIndex and colWeight must be hostMapped.
void mergeColumnsOnHost(SparseRows& merged, const std::vector<uint32_t>& colStart, const std::vector<const SparseRows*>& views,
                        const std::vector<size_t>& offsets);

/// The rows of `all` (one view's, written for every pixel; hostMapped) of the pixels `keep` marks,
/// and their columns: what the fill pass writes when masked to those pixels, entry for entry (a
/// ray's entries do not depend on which other rays are written). `all` itself where every pixel
/// left out has no entry (its rays meet no medium): nothing to copy. Work ahead writes rows for
/// every pixel before the paint says which have weight (solve_prefetch.h).
std::shared_ptr<const SparseRows> restrictRowsOnHost(std::shared_ptr<const SparseRows> all, const std::vector<uint8_t>& keep);

}  // namespace volstyle::core

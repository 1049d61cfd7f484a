#include "core/volume/brick_layout.h"

#include <algorithm>

namespace volstyle::core {

BrickLayout::BrickLayout(Int3 dims, Int3 offset) : m_dims(dims), m_offset(offset) {
    m_brickDims = {(dims.x + offset.x + kBrickSide - 1) / kBrickSide, (dims.y + offset.y + kBrickSide - 1) / kBrickSide,
                   (dims.z + offset.z + kBrickSide - 1) / kBrickSide};
    m_slotOfBrick.assign(size_t(m_brickDims.volume()), 0u);
    m_brickOfSlot.push_back({-1, -1, -1});  // slot 0: the background brick
    m_shared.push_back(0);
}

BrickLayout BrickLayout::full(Int3 dims, Int3 offset) {
    BrickLayout l(dims, offset);
    l.m_brickOfSlot.reserve(size_t(l.m_brickDims.volume()) + 1);
    for (int z = 0; z < l.m_brickDims.z; ++z)
        for (int y = 0; y < l.m_brickDims.y; ++y)
            for (int x = 0; x < l.m_brickDims.x; ++x) l.activate({x, y, z});
    return l;
}

uint32_t BrickLayout::activate(Int3 b) {
    uint32_t& slot = m_slotOfBrick[brickIndex(b)];
    if (slot == 0 || m_shared[slot]) {
        if (slot == 0) ++m_activeBricks;
        else --m_sharingBricks;
        slot = uint32_t(m_brickOfSlot.size());
        m_brickOfSlot.push_back(b);
        m_shared.push_back(0);
    }
    return slot;
}

uint32_t BrickLayout::addSharedSlot(Int3 representative) {
    m_brickOfSlot.push_back(representative);
    m_shared.push_back(1);
    return uint32_t(m_brickOfSlot.size() - 1);
}

void BrickLayout::share(Int3 b, uint32_t slot) {
    uint32_t& s = m_slotOfBrick[brickIndex(b)];
    if (s == 0) ++m_activeBricks;
    if (s != 0 && m_shared[s]) --m_sharingBricks;
    if (m_shared[slot]) ++m_sharingBricks;
    s = slot;
}

std::pair<Int3, Int3> BrickLayout::activeVoxelBox() const {
    Int3 lo{m_dims.x, m_dims.y, m_dims.z}, hi{-1, -1, -1};
    forEachActiveBrick([&](Int3 b, uint32_t) {
        const Int3 f = firstVoxel(b);
        lo = {std::min(lo.x, std::max(f.x, 0)), std::min(lo.y, std::max(f.y, 0)), std::min(lo.z, std::max(f.z, 0))};
        hi = {std::max(hi.x, std::min(f.x + kBrickSide - 1, m_dims.x - 1)), std::max(hi.y, std::min(f.y + kBrickSide - 1, m_dims.y - 1)),
              std::max(hi.z, std::min(f.z + kBrickSide - 1, m_dims.z - 1))};
    });
    return {lo, hi};
}

}  // namespace volstyle::core

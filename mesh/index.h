// The one "no index" value of the code base: a 32-bit vertex, tetrahedron, slot, face or merge index
// that names nothing (a boundary face's missing neighbour, an empty hash cell, a merge tree's root, a
// free slot). Local names for it (kNoNeighbor, kRoot, ...) are aliases of this constant.
#pragma once

#include <cstdint>

namespace gtn {

inline constexpr uint32_t kNoIndex = 0xFFFFFFFFu;

}  // namespace gtn

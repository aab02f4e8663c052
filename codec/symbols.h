// The symbols that name a triangle's or a tetrahedron's new vertex in the level codec (spec sections
// 10.3 and 10.4): new (not yet decoded), 1 + its place among the candidates, or escape.
#pragma once

#include <cstdint>

#include "mesh/index.h"

namespace gtn::level {

inline constexpr uint32_t kSymNew = 0;
inline constexpr uint32_t kSymEscape = 15;
inline constexpr int kMaxCandidates = 14;  // symbols 1..14

// The symbol of vertex `slot` (kNoIndex: not decoded yet) among the candidates cands[0..nc).
inline uint32_t candidateSymbol(uint32_t slot, const uint32_t* cands, int nc) {
  if (slot == kNoIndex) return kSymNew;
  uint32_t sym = kSymEscape;
  for (int i = 0; i < nc; ++i)
    if (cands[i] == slot) sym = static_cast<uint32_t>(i + 1);
  return sym;
}

}  // namespace gtn::level

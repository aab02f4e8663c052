#include "mesh/hex_split.h"

namespace gtn {

void splitHexSix(const uint32_t h[8], std::vector<Tet>& out) {
  static const int kSix[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  for (const auto& t : kSix) out.push_back({h[t[0]], h[t[1]], h[t[2]], h[t[3]]});
}

void splitHexFive(const uint32_t h[8], bool odd_parity, std::vector<Tet>& out) {
  // Even cells use the face diagonals 0-2, 0-5, 0-7, 2-5, 2-7, 5-7; odd cells the other ones, so that
  // neighbouring cells of opposite parity agree on their shared face.
  // Every tetrahedron positively oriented in a right-handed cell (VTK's corner order), so that only a
  // left-handed grid reports flips; each listed as the orientation pass would have flipped it (its
  // last two corners exchanged), so the tetrahedra are the same either way.
  static const int kEven[5][4] = {{0, 2, 7, 5}, {1, 0, 5, 2}, {3, 0, 2, 7}, {4, 0, 7, 5}, {6, 2, 5, 7}};
  static const int kOdd[5][4] = {{1, 3, 4, 6}, {0, 1, 3, 4}, {2, 1, 6, 3}, {5, 1, 4, 6}, {7, 3, 6, 4}};
  const auto& table = odd_parity ? kOdd : kEven;
  for (const auto& t : table) out.push_back({h[t[0]], h[t[1]], h[t[2]], h[t[3]]});
}

}  // namespace gtn

// The line `gtn convert` ends with (unless -q): what was read and written, their sizes and ratio, bits
// per tetrahedron of the output, the time taken.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace gtn::cli {

// Prints on standard error, e.g. "gtn: spx.vtk (506752 bytes) -> spx.gtn (68965 bytes): 13.61% of the
// input, 42.65 bits/tet (12936 tetrahedra), 1.00 s". A TetGen mesh counts its .node,
// .ele and .face files; sizes that cannot be known (standard input, a .p3d meta-file) are left out.
void printConvertSummary(const std::vector<std::string>& inputs, const std::string& output, size_t tets,
                         double seconds);

}  // namespace gtn::cli

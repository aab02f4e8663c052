// `gtn info --plot FILE.png`: level 0's merge error against the simplification ratio, stored levels
// marked, drawn by gnuplot (Debian's gnuplot-nox, which the set-up installs) from a script and data
// written to a temporary folder; the PNG is then written atomically to FILE.png.
#pragma once

#include <string>

#include "format/gtn_reader.h"
#include "mesh/status.h"

namespace gtn::cli {

inline constexpr int kPlotWidth = 800, kPlotHeight = 500;

// Fails with kUsage when the file stores no merge tree or no error quantiles, kIo when gnuplot
// cannot be run or fails.
Status plotMergeTree(GtnReader& reader, const std::string& png_path);

}  // namespace gtn::cli

#include "cli/merge_tree_plot.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "format/file_io.h"
#include "validate/info.h"

namespace gtn::cli {

namespace {
// A gnuplot string literal: single quotes, a quote doubled.
std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
  return q + "'";
}

// A word for the shell: single quotes, a quote as '\''.
std::string shellQuoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Removes the temporary folder and what is in it when the plot is done.
struct TempDir {
  std::string path;
  ~TempDir() {
    std::error_code ec;
    if (!path.empty()) std::filesystem::remove_all(path, ec);
  }
};

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}
}  // namespace

Status plotMergeTree(GtnReader& r, const std::string& png_path) {
  const std::string& input = r.file().path;
  GTN_ASSIGN_OR_RETURN(std::optional<MergeTreeReport> report, mergeTreeReport(r));
  if (!report) return usageError(input + ": --plot: the file stores no merge tree (written with --no-merge-tree)");
  if (report->error_curve.empty())
    return usageError(input +
                      ": --plot: the merge tree stores no error quantiles (no merges, or written without them)");

  std::error_code ec;  // TMPDIR naming no folder: an error, not an exception that aborts the program
  const std::filesystem::path temp = std::filesystem::temp_directory_path(ec);
  if (ec) return ioError(png_path + ": --plot: no folder for temporary files (" + ec.message() + "; TMPDIR names it)");
  std::string tmpl = (temp / "gtn-plot-XXXXXX").string();
  if (!mkdtemp(tmpl.data()))
    return ioError(png_path + ": --plot: cannot create a temporary folder in " + temp.string());
  TempDir dir{tmpl};
  const std::string curve = dir.path + "/curve.dat", levels = dir.path + "/levels.dat";
  const std::string script = dir.path + "/plot.gp", image = dir.path + "/plot.png", log = dir.path + "/gnuplot.log";
  double min_positive = 0, max_error = 0;
  {
    std::ofstream c(curve), l(levels), g(script);
    c.precision(17);
    l.precision(17);
    for (const MergeErrorPoint& p : report->error_curve) {
      c << p.ratio << ' ' << p.error << ' ' << p.largest_error << '\n';
      if (p.error > 0 && (min_positive == 0 || p.error < min_positive)) min_positive = p.error;
      max_error = std::max(max_error, p.error);
    }
    for (const MergeTreeLevelRow& row : report->levels)
      if (row.largest_error) l << row.ratio << ' ' << *row.largest_error << ' ' << row.level << '\n';
    // Errors span orders of magnitude: a log scale when they do (zero errors are then not drawn).
    const bool log_scale = min_positive > 0 && max_error / min_positive > 100;
    g << "set terminal pngcairo size " << kPlotWidth << ',' << kPlotHeight << " noenhanced font 'sans,10'\n"
      << "set output " << quoted(image) << "\n"
      << "set title " << quoted(input + ": merge error against simplification ratio") << "\n"
      << "set xlabel 'simplification ratio (vertices merged away / vertices of level 0)'\n"
      << "set ylabel 'merge error'\n"
      << "set xrange [0:1]\n"
      << "set grid\n"
      << "set key top left\n"
      << (log_scale ? "set logscale y\nset format y '%.0e'\n" : "");
    for (const MergeTreeLevelRow& row : report->levels) {
      if (row.level == 0) continue;
      g << "set arrow from " << row.ratio << ", graph 0 to " << row.ratio << ", graph 1 nohead dt 2 lc rgb '#888888'\n"
        << "set label " << quoted("level " + std::to_string(row.level)) << " at " << row.ratio
        << ", graph 0.03 rotate by 90 offset -0.6,0 textcolor rgb '#555555'\n";
    }
    g << "plot " << quoted(curve)
      << " using 1:3 with steps lw 2 lc rgb '#1f77b4' title 'largest merge error up to the ratio', " << quoted(curve)
      << " using 1:2 with points pt 7 ps 0.5 lc rgb '#9ecae1' "
      << "title 'error quantiles of each stored level''s merge tree'";
    bool any_level = false;
    for (const MergeTreeLevelRow& row : report->levels) any_level |= row.largest_error.has_value();
    if (any_level)
      g << ", " << quoted(levels) << " using 1:2 with points pt 5 ps 1.2 lc rgb '#d62728' "
        << "title 'stored levels: largest error'";
    g << "\n";
    if (!c || !l || !g) return ioError(png_path + ": --plot: cannot write the plot's data in " + dir.path);
  }
  const std::string command = "gnuplot " + shellQuoted(script) + " >" + shellQuoted(log) + " 2>&1";
  const int rc = std::system(command.c_str());
  if (rc == -1 || !WIFEXITED(rc) || WEXITSTATUS(rc) != 0) {
    std::string why = readText(log);
    if (WIFEXITED(rc) && WEXITSTATUS(rc) == 127) why = "gnuplot is not installed (Debian package gnuplot-nox)";
    return ioError(png_path + ": --plot: gnuplot failed" + (why.empty() ? std::string() : ": " + why));
  }
  GTN_ASSIGN_OR_RETURN(std::string png, readWholeFile(image));
  return writeBytesAtomically(png_path, png.data(), png.size());
}

}  // namespace gtn::cli

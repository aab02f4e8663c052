#include "render/transfer_function.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "convert/text_reader.h"
#include "format/file_io.h"

namespace gtn {

namespace {
TransferFunction fromTable(const std::vector<std::array<double, 5>>& rows) {
  TransferFunction tf;
  for (const auto& r : rows) {
    TransferPoint p;
    p.x = r[0];
    p.rgb[0] = r[1];
    p.rgb[1] = r[2];
    p.rgb[2] = r[3];
    p.opacity = r[4];
    tf.points.push_back(p);
  }
  return tf;
}
}  // namespace

double TransferFunction::position(double scalar) const {
  const double span = hi - lo;
  if (std::isfinite(span)) return span > 0 ? (scalar - lo) / span : 0.5;
  return (0.5 * scalar - 0.5 * lo) / (0.5 * hi - 0.5 * lo);
}

double TransferFunction::valueAt(double x) const {
  const double span = hi - lo;
  if (std::isfinite(span)) return lo + span * x;
  return 2.0 * (0.5 * lo + (0.5 * hi - 0.5 * lo) * x);
}

void TransferFunction::evaluate(double scalar, double rgb[3], double* extinction) const {
  double x = position(scalar);
  if (!(x >= 0)) x = 0;  // also catches NaN
  if (x > 1) x = 1;
  size_t i = 1;
  while (i + 1 < points.size() && points[i].x < x) ++i;
  const TransferPoint& a = points[i - 1];
  const TransferPoint& b = points[i];
  double w = b.x > a.x ? (x - a.x) / (b.x - a.x) : 1.0;
  w = std::clamp(w, 0.0, 1.0);
  for (int c = 0; c < 3; ++c) rgb[c] = a.rgb[c] + w * (b.rgb[c] - a.rgb[c]);
  *extinction = a.opacity + w * (b.opacity - a.opacity);
}

const std::vector<std::string>& transferPresetNames() {
  static const std::vector<std::string> names = {"cool-warm", "grey", "hot"};
  return names;
}

StatusOr<TransferFunction> transferPreset(const std::string& name) {
  if (name == "cool-warm") {
    return fromTable({{0.0, 0.230, 0.299, 0.754, 0.0},
                      {0.25, 0.552, 0.690, 0.996, 0.15},
                      {0.5, 0.865, 0.865, 0.865, 0.3},
                      {0.75, 0.958, 0.604, 0.482, 0.45},
                      {1.0, 0.706, 0.016, 0.150, 0.6}});
  }
  if (name == "grey") return fromTable({{0.0, 0, 0, 0, 0.0}, {1.0, 1, 1, 1, 0.6}});
  if (name == "hot") {
    return fromTable({{0.0, 0, 0, 0, 0.0}, {0.4, 0.9, 0, 0, 0.24}, {0.8, 1, 0.9, 0, 0.48}, {1.0, 1, 1, 1, 0.6}});
  }
  std::string known;
  for (const std::string& n : transferPresetNames()) known += (known.empty() ? "" : ", ") + n;
  return usageError("unknown transfer function preset '" + name + "' (known: " + known + ")");
}

StatusOr<TransferFunction> parseTransferFunction(const std::string& text, const std::string& what) {
  TransferFunction tf;
  // A UTF-8 byte order mark (editors on Windows write one) is no part of the first directive.
  const bool bom = text.rfind("\xEF\xBB\xBF", 0) == 0;
  std::istringstream lines(bom ? text.substr(3) : text);
  std::string line;
  int line_no = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream in(line);
    std::string word;
    if (!(in >> word)) continue;
    const std::string where = what + ":" + std::to_string(line_no) + ": ";
    if (word == "range") {
      if (!(in >> tf.lo >> tf.hi) || !std::isfinite(tf.lo) || !std::isfinite(tf.hi) || !(tf.lo < tf.hi))
        return invalidData(where + "expected 'range LO HI' with finite LO < HI");
      tf.has_range = true;
    } else if (word == "point") {
      TransferPoint p;
      if (!(in >> p.x >> p.rgb[0] >> p.rgb[1] >> p.rgb[2] >> p.opacity))
        return invalidData(where + "expected 'point X R G B O'");
      for (double v : {p.x, p.rgb[0], p.rgb[1], p.rgb[2], p.opacity})
        if (!(v >= 0 && v <= 1)) return invalidData(where + "point values must lie in [0, 1]");
      if (!tf.points.empty() && p.x < tf.points.back().x)
        return invalidData(where + "point positions must not decrease");
      tf.points.push_back(p);
    } else {
      return invalidData(where + "unknown directive " + quotedToken(word) + " (expected 'range' or 'point')");
    }
    std::string extra;
    if (in >> extra) return invalidData(where + "unexpected " + quotedToken(extra) + " at the end of the line");
  }
  if (tf.points.size() < 2) return invalidData(what + ": a transfer function needs at least two points");
  return tf;
}

StatusOr<TransferFunction> loadTransferFunction(const std::string& spec) {
  if (isRegularFile(spec)) {
    GTN_ASSIGN_OR_RETURN(std::string text, readWholeFile(spec, 1 << 20));
    return parseTransferFunction(text, spec);
  }
  auto preset = transferPreset(spec);
  if (!preset.isOk() && spec.find_first_of("./") != std::string::npos)
    return ioError(spec + ": cannot open the transfer function file (" +
                   (access(spec.c_str(), F_OK) == 0 ? "not a regular file" : "no such file") + ")");
  return preset;
}

}  // namespace gtn

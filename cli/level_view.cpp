#include "cli/level_view.h"

#include <cmath>
#include <cstdlib>

#include "codec/pieces.h"
#include "convert/import.h"

namespace gtn::cli {

StatusOr<std::unique_ptr<GtnReader>> openForView(const std::string& input, const std::string& command,
                                                 const std::string& convert_hint, HeldWarnings& damage) {
  GtnOpenOptions oo;
  oo.verify = false;  // random access through the directory; every chunk read is still checksummed
  auto reader = openGtnChecked(input, oo, damage.sink());
  if (reader.isOk()) return reader;
  const InputFormat in_format = detectInputFormat(input);
  if (in_format != InputFormat::kGtn && in_format != InputFormat::kUnknown)
    return usageError(input + ": a " + inputFormatName(in_format) + " file, not .gtn: 'gtn " + command +
                      "' reads .gtn files; " + convert_hint);
  return reader.status();
}

Status parseBox(const std::string& text, ViewRequest* v) {
  std::vector<double> values;
  size_t start = 0;
  for (;;) {
    const size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(x))
      return usageError("--box " + text + ": '" + item +
                        "' is not a finite number (expected XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX)");
    values.push_back(x);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (values.size() != 6)
    return usageError("--box " + text + ": " + std::to_string(values.size()) +
                      " numbers, not 6 (expected XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX)");
  for (int k = 0; k < 3; ++k) {
    v->box_lo[k] = values[k];
    v->box_hi[k] = values[k + 3];
    if (v->box_lo[k] > v->box_hi[k])
      return usageError("--box " + text + ": the minimum exceeds the maximum on the " + std::string(1, "xyz"[k]) +
                        " axis");
  }
  v->has_box = true;
  return Status::ok();
}

namespace {
// The pieces of the stored level v.level that meet v's box, decoded and emitted to `sink` as one mesh.
Status decodeBox(GtnReader& r, const std::string& input, const ViewRequest& v, MeshSink& sink,
                 const DecodeFields* fields) {
  const GtnLevelInfo& li = r.level(v.level);
  const std::vector<uint32_t> chosen = piecesInBox(li.pieces, v.box_lo, v.box_hi);
  if (chosen.empty())
    return usageError(input + ": --box: the box meets none of level " + std::to_string(v.level) + "'s " +
                      std::to_string(li.pieces.size()) + " piece(s); the level spans [" +
                      std::to_string(li.header.bbox_min[0]) + ", " + std::to_string(li.header.bbox_max[0]) + "] x [" +
                      std::to_string(li.header.bbox_min[1]) + ", " + std::to_string(li.header.bbox_max[1]) + "] x [" +
                      std::to_string(li.header.bbox_min[2]) + ", " + std::to_string(li.header.bbox_max[2]) + "]");
  // Every piece meets the box: the level as a whole (a one-piece level streams from its decoder).
  if (chosen.size() == li.pieces.size()) return r.decodeLevel(v.level, sink, nullptr, fields);
  GTN_ASSIGN_OR_RETURN(DecodedPieces decoded, r.decodeLevelPieces(v.level, chosen, fields));
  LevelHeader h = li.header;
  h.points = decoded.mesh.numPoints();
  h.tets = decoded.mesh.numTets();
  h.boundary_triangles = decoded.boundary.size();
  return emitDecoded(h, decoded, sink);
}
}  // namespace

Status decodeView(GtnReader& r, const std::string& input, const ViewRequest& v, MeshSink& sink, DecodeFields* fields,
                  SimplifyPlan* plan) {
  if (v.level >= r.levels())
    return usageError(input + ": --level " + std::to_string(v.level) + ": the file holds " +
                      std::to_string(r.levels()) + " level(s), 0 to " + std::to_string(r.levels() - 1));
  *fields = DecodeFields{};  // every field unless v.fields names some
  if (!v.fields.empty()) {
    auto selected = selectDecodeFields(r.level(v.level).header, v.fields, input, "--fields");
    if (!selected.isOk()) return selected.status();
    *fields = std::move(selected).value();
  }
  if (plan) plan->level = v.level;
  if (v.has_box) {
    if (v.ratio >= 0 || v.merges >= 0)
      return usageError(input + ": --box reads the pieces of a stored level: give --level, not --ratio or --merges");
    return decodeBox(r, input, v, sink, fields);
  }
  if (v.ratio < 0 && v.merges < 0) return r.decodeLevel(v.level, sink, nullptr, fields);
  StatusOr<uint64_t> target = uint64_t{0};
  if (v.merges >= 0) target = static_cast<uint64_t>(v.merges);
  else target = mergesForRatio(r, v.ratio);
  if (!target.isOk()) return target.status();
  return streamSimplified(r, *target, sink, plan, /*clamp=*/v.merges < 0, fields);
}

}  // namespace gtn::cli

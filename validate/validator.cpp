#include "validate/validator.h"

#include <algorithm>

#include <sys/mman.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "codec/merge_tree_coder.h"
#include "format/file_io.h"
#include "format/gtn_reader.h"
#include "simplify/levels.h"
#include "validate/mesh_checks.h"

namespace gtn {

namespace {

std::string levelScope(uint32_t level) { return "/levels/" + std::to_string(level); }

bool sameFields(const std::vector<Field>& a, const std::vector<Field>& b, std::string* why) {
  if (a.size() != b.size()) {
    *why = std::to_string(a.size()) + " fields, the source has " + std::to_string(b.size());
    return false;
  }
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].name != b[i].name || a[i].type != b[i].type || a[i].components != b[i].components) {
      *why = "field " + std::to_string(i) + " is '" + a[i].name + "' " + std::to_string(a[i].components) + " x " +
             scalarTypeName(a[i].type) + ", the source has '" + b[i].name + "' " + std::to_string(b[i].components) +
             " x " + scalarTypeName(b[i].type);
      return false;
    }
  }
  return true;
}

nlohmann::json statsJson(const MeshCheckStats& s) {
  return {{"points", s.points},
          {"tets", s.tets},
          {"faces", s.faces},
          {"boundary_faces", s.boundary_faces},
          {"inverted", s.inverted},
          {"zero_volume", s.zero_volume},
          {"unreferenced_points", s.unreferenced_points}};
}

}  // namespace

void compareWithSource(const TetMesh& level0, const TetMesh& source, ValidationReport& report,
                       const std::string& hint) {
  const std::string scope = "/levels/0";
  bool comparable = true;
  if (level0.numPoints() != source.numPoints() || level0.numTets() != source.numTets()) {
    report.add(IssueCode::kSourceCountMismatch, scope, scope,
               "level 0 has " + std::to_string(level0.numPoints()) + " points and " + std::to_string(level0.numTets()) +
                   " tetrahedra, the source " + std::to_string(source.numPoints()) + " and " +
                   std::to_string(source.numTets()) + hint);
  }
  std::string why;
  if (level0.coord_type != source.coord_type) {
    report.add(IssueCode::kSourceFieldMismatch, scope, scope + "/coordinates",
               std::string("coordinates are ") + scalarTypeName(level0.coord_type) + ", the source's " +
                   scalarTypeName(source.coord_type));
  }
  if (!sameFields(level0.point_fields, source.point_fields, &why)) {
    report.add(IssueCode::kSourceFieldMismatch, scope, scope + "/point_fields", "point fields: " + why);
    comparable = false;
  }
  if (!sameFields(level0.cell_fields, source.cell_fields, &why)) {
    report.add(IssueCode::kSourceFieldMismatch, scope, scope + "/cell_fields", "cell fields: " + why);
    comparable = false;
  }
  if (!comparable || level0.numPoints() != source.numPoints() || level0.numTets() != source.numTets()) return;
  std::vector<uint64_t> pa = pointKeys(level0), pb = pointKeys(source);
  const auto ta = sortedTetKeys(level0, pa), tb = sortedTetKeys(source, pb);
  std::sort(pa.begin(), pa.end());
  std::sort(pb.begin(), pb.end());
  const auto [extra_p, missing_p] = multisetDifference(pa, pb);
  const auto [extra_t, missing_t] = multisetDifference(ta, tb);
  if (extra_p || missing_p || extra_t || missing_t) {
    report.add(IssueCode::kSourceMeshMismatch, scope, scope,
               std::to_string(extra_t) + " tetrahedra and " + std::to_string(extra_p) +
                   " points of level 0 are not in the source; " + std::to_string(missing_t) + " tetrahedra and " +
                   std::to_string(missing_p) +
                   " points of the source are missing (positions and values compared "
                   "bit for bit, up to renumbering)");
  }
}

// A box as "[x0, x1] x [y0, y1] x [z0, z1]", every digit of each bound.
std::string boxText(const double mn[3], const double mx[3]) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "[%.17g, %.17g] x [%.17g, %.17g] x [%.17g, %.17g]", mn[0], mx[0], mn[1], mx[1], mn[2],
                mx[2]);
  return buf;
}

// Why the level's stored bounding box is not the box of its points, or empty: the smallest and largest
// x, y, z of all its points, or of the points its tetrahedra use (a level of several pieces boxes the
// vertices its pieces use). Region reads (--box) and the renderer's framing trust it. A level with no
// point, or with a coordinate that is not finite (reported as such), is not compared.
std::string boundingBoxMismatch(const TetMesh& mesh, const LevelHeader& h) {
  const size_t np = mesh.numPoints();
  if (np == 0) return "";
  for (double x : mesh.coords)
    if (!std::isfinite(x)) return "";
  double all_min[3], all_max[3], used_min[3], used_max[3];
  for (int a = 0; a < 3; ++a) {
    all_min[a] = used_min[a] = HUGE_VAL;
    all_max[a] = used_max[a] = -HUGE_VAL;
  }
  std::vector<char> used(np, 0);
  for (const Tet& t : mesh.tets)
    for (uint32_t v : t)
      if (v < np) used[v] = 1;
  for (size_t v = 0; v < np; ++v)
    for (int a = 0; a < 3; ++a) {
      const double x = mesh.coords[3 * v + a];
      all_min[a] = std::min(all_min[a], x);
      all_max[a] = std::max(all_max[a], x);
      if (!used[v]) continue;
      used_min[a] = std::min(used_min[a], x);
      used_max[a] = std::max(used_max[a], x);
    }
  auto same = [&](const double* mn, const double* mx) {
    for (int a = 0; a < 3; ++a)
      if (h.bbox_min[a] != mn[a] || h.bbox_max[a] != mx[a]) return false;
    return true;
  };
  if (same(all_min, all_max) || same(used_min, used_max)) return "";
  return "the header's bounding box " + boxText(h.bbox_min, h.bbox_max) + " is not the box of the level's points " +
         boxText(all_min, all_max) + "; region reads (--box) and rendering rely on it";
}

// A level of several pieces lists its tetrahedra piece by piece: each piece's stored box (LHDR) must
// hold the vertices of its tetrahedra, or a region read (--box) skips a piece that meets the region.
void checkPieceBoxes(const GtnLevelInfo& li, const TetMesh& mesh, const std::string& scope, ValidationReport& report) {
  if (li.pieces.size() < 2) return;  // one piece: its box is the level's
  uint64_t total = 0;
  for (const PieceInfo& p : li.pieces) total += p.tets;
  if (total != mesh.numTets()) return;  // reported as LEVEL_COUNT_MISMATCH
  // Whether vertex v lies in the piece's box (a vertex out of range or a NaN coordinate is reported
  // by the mesh checks).
  auto inside = [&](const PieceInfo& info, uint32_t v) {
    if (v >= mesh.numPoints()) return true;
    const double* x = mesh.point(v);
    for (int a = 0; a < 3; ++a)
      if (x[a] < info.bbox_min[a] || x[a] > info.bbox_max[a]) return false;
    return true;
  };
  uint64_t first = 0;
  for (size_t p = 0; p < li.pieces.size(); first += li.pieces[p].tets, ++p) {
    const PieceInfo& info = li.pieces[p];
    for (uint64_t t = first; t < first + info.tets; ++t) {
      const auto out =
          std::find_if(mesh.tets[t].begin(), mesh.tets[t].end(), [&](uint32_t v) { return !inside(info, v); });
      if (out == mesh.tets[t].end()) continue;
      report.add(IssueCode::kBoundingBoxMismatch, scope, scope + "/pieces/" + std::to_string(p),
                 "piece " + std::to_string(p) + "'s bounding box " + boxText(info.bbox_min, info.bbox_max) +
                     " does not hold vertex " + std::to_string(*out) + " of its tetrahedron " + std::to_string(t) +
                     "; a region read (--box) skips the piece where the region misses the box");
      break;  // one report per piece
    }
  }
}

void validateDecoded(const DecodedFile& file, const ValidateOptions& options, ValidationReport& report) {
  if (file.levels.empty() || file.levels.front().level != 0) {
    report.add(IssueCode::kNoLevels, "/levels", "/levels", "the file holds no level 0");
    return;
  }
  nlohmann::json levels_info = nlohmann::json::array();
  bool level0_ok = false;
  for (const DecodedLevel& level : file.levels) {
    const std::string scope = levelScope(level.level);
    const LevelHeader& h = level.header;
    if (h.points != level.mesh.numPoints() || h.tets != level.mesh.numTets() ||
        h.boundary_triangles != level.boundary.size()) {
      report.add(IssueCode::kLevelCountMismatch, scope, scope,
                 "the header declares " + std::to_string(h.points) + " points, " + std::to_string(h.tets) +
                     " tetrahedra and " + std::to_string(h.boundary_triangles) + " boundary triangles; decoding gave " +
                     std::to_string(level.mesh.numPoints()) + ", " + std::to_string(level.mesh.numTets()) + " and " +
                     std::to_string(level.boundary.size()));
    }
    if (const std::string why = boundingBoxMismatch(level.mesh, h); !why.empty())
      report.add(IssueCode::kBoundingBoxMismatch, scope, scope + "/bbox", why);
    MeshCheckStats stats;
    const bool ok = checkMesh(level.mesh, scope, report, &stats);
    if (ok) checkStoredBoundary(level.mesh, level.boundary, scope, report);
    if (level.level == 0) level0_ok = ok;
    nlohmann::json li = statsJson(stats);
    li["level"] = level.level;
    li["merges"] = h.merges;
    if (level.ratio >= 0) li["ratio"] = level.ratio;
    levels_info.push_back(std::move(li));
  }
  report.info()["levels"] = std::move(levels_info);

  const TetMesh& level0 = file.levels.front().mesh;
  if (!file.forest) {
    if (file.forest_undecodable) {
      // Already reported (MERGE_TREE_UNDECODABLE); the levels cannot be checked without it.
    } else if (file.levels.size() > 1) {
      report.add(IssueCode::kLevelWithoutMergeTree, "/levels", "/levels",
                 std::to_string(file.levels.size() - 1) + " mip levels but no merge tree");
    } else {
      report.add(IssueCode::kNoMergeTree, "/merge_tree", "/merge_tree");
    }
  } else if (level0_ok) {
    std::vector<StoredLevel> stored;
    for (size_t i = 1; i < file.levels.size(); ++i) {
      const DecodedLevel& l = file.levels[i];
      stored.push_back({l.level, l.header.merges, l.ratio, &l.mesh});
    }
    MergeReplayStats ms;
    const uint64_t errors_before = report.count(Severity::kError);
    checkMergeTree(level0, *file.forest, stored, report, &ms);
    // A replay without error shows that each stored level is level 0 after its merges and that no merge
    // flattened a tetrahedron: the levels' flat tetrahedra are level 0's.
    if (report.count(Severity::kError) == errors_before) {
      for (size_t i = 1; i < file.levels.size(); ++i) {
        report.reclassify(IssueCode::kZeroVolumeTet, IssueCode::kZeroVolumeTetFromSource,
                          levelScope(file.levels[i].level));
      }
    }
    report.info()["merge_tree"] = {{"merges", ms.merges},
                                   {"roots", ms.roots},
                                   {"boundary_merges", ms.boundary_merges},
                                   {"max_depth", ms.max_depth},
                                   {"tets_checked", ms.tets_checked}};
  }

  if (!options.against.empty()) {
    // The source is imported as the file was made: its split and --weld from level 0's metadata
    // unless given.
    ImportOptions io = options.import_options;
    const std::string* split = level0.findMetadata(kMetadataSplit);
    const std::string* weld = level0.findMetadata(kMetadataWeld);
    std::string taken;
    if (options.split_from_file && split && (*split == "5" || *split == "6")) {
      io.split = *split == "5" ? 5 : 6;
      taken += std::string(taken.empty() ? "" : ", ") + "--split " + *split;
    }
    if (options.weld_from_file && weld && *weld == "yes") {
      io.weld = true;
      taken += std::string(taken.empty() ? "" : ", ") + "--weld";
    }
    if (!taken.empty()) report.info()["against"]["from_metadata"] = taken;
    std::string hint = "; the source was imported with --split " + std::to_string(io.split) +
                       (io.weld ? " --weld" : " without --weld") +
                       (taken.empty() ? std::string() : " (" + taken + " from the file's metadata)");
    if (!file.command_line.empty()) hint += "; the file was made by: " + file.command_line;
    hint += "; give --split and --weld as it was converted";
    StatusOr<ImportResult> source = importMesh(options.against, io);
    if (!source.isOk()) {
      report.add(IssueCode::kSourceUnreadable, "/against", "/against", source.status().message());
    } else {
      const uint64_t errors_before = report.count(Severity::kError);
      compareWithSource(level0, source->mesh, report, hint);
      if (report.count(Severity::kError) == errors_before) {
        report.reclassify(IssueCode::kZeroVolumeTet, IssueCode::kZeroVolumeTetFromSource, levelScope(0));
      }
    }
  }
}

namespace {

bool containsText(const std::string& haystack, const char* needle) {
  auto lower = [](std::string x) {
    for (char& ch : x) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return x;
  };
  return lower(haystack).find(needle) != std::string::npos;
}

// The byte offset a reader message names ("...: byte offset N: ..."), if any.
std::optional<uint64_t> messageOffset(const std::string& message) {
  const std::string key = "byte offset ";
  const size_t at = message.find(key);
  if (at == std::string::npos) return std::nullopt;
  size_t i = at + key.size();
  if (i >= message.size() || !std::isdigit(static_cast<unsigned char>(message[i]))) return std::nullopt;
  uint64_t v = 0;
  for (; i < message.size() && std::isdigit(static_cast<unsigned char>(message[i])); ++i) {
    if (v > (UINT64_MAX - 9) / 10) return std::nullopt;
    v = v * 10 + static_cast<uint64_t>(message[i] - '0');
  }
  return v;
}

// The reader stops at the first defect of the container and says what it is in its status; this maps
// that status to the registry's code. The reader's wording is the contract here: the must-fail tests
// (tests/validate) pin every mapping.
IssueCode classifyContainerFailure(const Status& status) {
  const std::string& m = status.message();
  if (status.code() == StatusCode::kNotOurFile) return IssueCode::kBadMagic;
  if (status.code() == StatusCode::kVersionTooNew || containsText(m, "major version") ||
      (status.code() == StatusCode::kUnsupported &&
       (containsText(m, "format version") || containsText(m, "draft revision")))) {
    return IssueCode::kUnsupportedVersion;
  }
  if (containsText(m, "inside the 16-byte")) return IssueCode::kFileTooSmall;
  if (containsText(m, "checksum mismatch")) return IssueCode::kChecksumMismatch;
  if (containsText(m, "reserved")) return IssueCode::kReservedBitsSet;
  if (containsText(m, "trailing bytes")) return IssueCode::kTrailingBytes;
  if (containsText(m, "directory") || containsText(m, "end chunk")) return IssueCode::kDirectoryMismatch;
  if (containsText(m, "truncated") || containsText(m, "chunk type") || containsText(m, "zstd") ||
      containsText(m, "decompresses")) {
    return IssueCode::kChunkFraming;
  }
  if (containsText(m, "at most") || containsText(m, "exceeds") || containsText(m, "too large") ||
      containsText(m, "more levels than")) {
    return IssueCode::kSizeOutOfBounds;
  }
  return IssueCode::kMalformedContainer;
}

}  // namespace

StatusOr<ValidationReport> validateGtnFile(const std::string& path, const ValidateOptions& options) {
  ValidationReport report(options.max_issues);
  StatusOr<std::unique_ptr<GtnReader>> opened = GtnReader::open(path, GtnOpenOptions{true});
  if (!opened.isOk()) {
    const Status& st = opened.status();
    if (st.code() == StatusCode::kIo) return st;
    const std::optional<uint64_t> offset = messageOffset(st.message());
    report.add(classifyContainerFailure(st), "/container", "/container", st.message(), offset);
    return report;
  }
  GtnReader& reader = *opened.value();
  const GtnFileInfo& fi = reader.file();
  nlohmann::json& info = report.info();
  info["file_bytes"] = fi.bytes;
  info["version"] = std::to_string(fi.major) + "." + std::to_string(fi.minor);
  info["level_count"] = reader.levels();
  info["has_directory"] = fi.has_directory;
  info["tool_version"] = fi.header.tool_version;
  nlohmann::json sections = nlohmann::json::object();
  for (const GtnSection& s : reader.sections()) sections[s.name] = s.bytes;
  info["sections"] = std::move(sections);
  for (size_t i = 0; i < reader.levels(); ++i) {
    for (const GtnChunkInfo& c : reader.level(i).chunks) {
      if (c.section.rfind("unknown:", 0) == 0) {
        report.add(IssueCode::kUnknownChunk, "/container", "/levels/" + std::to_string(i) + "/" + c.section,
                   "level " + std::to_string(i) + " holds an ancillary chunk '" + c.tag.str() + "' (skipped)",
                   c.offset);
      }
    }
  }
  for (const GtnChunkInfo& c : fi.chunks) {
    if (c.section.rfind("unknown:", 0) == 0) {
      report.add(IssueCode::kUnknownChunk, "/container", "/" + c.section,
                 "ancillary chunk '" + c.tag.str() + "' (skipped)", c.offset);
    }
  }
  if (options.quick) return report;

  // Decoding: every level into memory, then the mesh, merge-tree and levels layers.
  DecodedFile decoded;
  decoded.command_line = fi.header.command_line;
  std::vector<std::vector<uint32_t>> base_ids(reader.levels());
  for (size_t i = 0; i < reader.levels(); ++i) {
    const std::string scope = "/levels/" + std::to_string(i);
    TetMeshBuilder builder;
    DecodeStats dstats;
    const Status st = reader.decodeLevel(i, builder, &dstats, nullptr, &base_ids[i]);
    if (!st.isOk()) {
      const std::optional<uint64_t> offset = messageOffset(st.message());
      const IssueCode code = (containsText(st.message(), "declares") || containsText(st.message(), "count"))
                                 ? IssueCode::kLevelCountMismatch
                                 : IssueCode::kLevelDecodeFailed;
      report.add(code, scope, scope, st.message(), offset);
      if (i == 0) break;
      continue;
    }
    checkPieceBoxes(reader.level(i), builder.mesh(), scope, report);
    DecodedLevel level;
    level.level = static_cast<uint32_t>(i);
    level.header = reader.level(i).header;
    level.ratio = i == 0 ? -1.0 : reader.level(i).ratio;
    level.mesh = std::move(builder.mesh());
    level.boundary.assign(builder.boundary().begin(), builder.boundary().end());
    decoded.levels.push_back(std::move(level));
    info["peak_live_vertices"][i] = dstats.peak_live_vertices;
  }
  if (decoded.levels.empty()) return report;  // level 0 did not decode: nothing else can be checked
  std::vector<const TetMesh*> level_meshes(reader.levels(), nullptr);  // what version 3 trees decode against
  for (const DecodedLevel& l : decoded.levels) level_meshes[l.level] = &l.mesh;
  for (size_t i = 0; i < reader.levels(); ++i) {
    StatusOr<std::optional<std::vector<uint8_t>>> payload = reader.mergeTreePayload(i);
    if (!payload.isOk()) {
      report.add(IssueCode::kMergeTreeUndecodable, "/merge_tree", "/levels/" + std::to_string(i) + "/merge_tree",
                 payload.status().message(), messageOffset(payload.status().message()));
      if (i == 0) decoded.forest_undecodable = true;
      continue;
    }
    if (!payload->has_value()) continue;
    const uint64_t points = reader.level(i).header.points;
    const std::string what = fi.path + ": level " + std::to_string(i) + " merge tree";
    StatusOr<MergeTree> tree = decodeMergeTree(**payload, points, what, level_meshes[i], UINT64_MAX,
                                               base_ids[i].empty() ? nullptr : &base_ids[i]);
    if (!tree.isOk()) {
      report.add(IssueCode::kMergeTreeUndecodable, "/merge_tree", "/levels/" + std::to_string(i) + "/merge_tree",
                 tree.status().message());
      if (i == 0) decoded.forest_undecodable = true;
      continue;
    }
    // Level 0's whole tree (with the next levels' where level 0 names their vertices) is the one every
    // level derives from; the trees of mip levels (what remains of it) are only checked to decode.
    if (i == 0) {
      StatusOr<std::optional<MergeTree>> whole = wholeMergeTree(reader, 0, &base_ids, &level_meshes);
      if (!whole.isOk()) {
        report.add(IssueCode::kMergeTreeUndecodable, "/merge_tree", "/levels/0/merge_tree", whole.status().message());
        decoded.forest_undecodable = true;
      } else if (whole->has_value()) {
        decoded.forest = forestFromTree(**whole);
      }
    }
  }
  validateDecoded(decoded, options, report);
  return report;
}

}  // namespace gtn

namespace gtn {

StatusOr<ValidationReport> validateMeshFiles(const std::vector<std::string>& inputs, const ValidateOptions& options) {
  ValidationReport report(options.max_issues);
  StatusOr<ImportResult> imported = importMesh(inputs, options.import_options);
  if (!imported.isOk()) {
    if (imported.status().code() == StatusCode::kIo) return imported.status();
    report.add(IssueCode::kImportFailed, "/import", "/import", imported.status().message());
    return report;
  }
  const ImportReport& r = imported->report;
  if (r.flipped) {
    report.addMany(IssueCode::kCellsReoriented, "/import", r.flipped, {}, "");
  }
  if (r.dropped_cells) {
    report.addMany(IssueCode::kCellsDropped, "/import", r.dropped_cells, {}, "");
  }
  // Each warning says something of its own (what was skipped, what was changed): a message each.
  for (size_t i = 0; i < r.warnings.size(); ++i) {
    const std::string path = "/import/warnings/" + std::to_string(i);
    report.add(IssueCode::kImportWarning, path, path, r.warnings[i]);
  }
  MeshCheckStats stats;
  checkMesh(imported->mesh, "/mesh", report, &stats);
  nlohmann::json mi = statsJson(stats);
  mi["format"] = inputFormatName(detectInputFormat(inputs.front()));
  if (r.welded_points) mi["welded_points"] = r.welded_points;
  if (r.collapsed_tets) mi["collapsed_tets"] = r.collapsed_tets;
  if (r.steiner_points) mi["steiner_points"] = r.steiner_points;
  report.info()["mesh"] = std::move(mi);
  return report;
}

ValidationReport validateGtnBytes(std::span<const uint8_t> bytes, const std::string& name,
                                  const ValidateOptions& options) {
  // The reader opens paths; an anonymous in-memory file gives it one without touching the disk.
  const int fd = memfd_create("gtn-validate", MFD_CLOEXEC);
  ValidationReport failed(options.max_issues);
  if (fd < 0) {
    failed.add(IssueCode::kMalformedContainer, "/container", "/container",
               name + ": cannot create an in-memory file: " + std::strerror(errno));
    return failed;
  }
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t w = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (w <= 0) break;
    done += static_cast<size_t>(w);
  }
  StatusOr<ValidationReport> report = validateGtnFile("/proc/self/fd/" + std::to_string(fd), options);
  ::close(fd);
  if (!report.isOk()) {
    failed.add(IssueCode::kMalformedContainer, "/container", "/container", name + ": " + report.status().message());
    return failed;
  }
  return std::move(report).value();
}

}  // namespace gtn

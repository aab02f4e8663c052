// Reading .gtn files (include/gatun/read.h), as `gtn export` and the Python package's gatun.read do.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <memory>
#include <numeric>
#include <utility>

#include "codec/pieces.h"
#include "convert/import.h"
#include "format/decode_fields.h"
#include "format/gtn_reader.h"
#include "gatun/read.h"
#include "internal.h"
#include "mesh/box_filter.h"
#include "simplify/levels.h"

namespace gatun {

struct Reader::Impl {
  std::unique_ptr<gtn::GtnReader> reader;
  FileInfo info;
};

namespace {
std::vector<FieldInfo> fieldInfos(const std::vector<gtn::FieldDesc>& fields) {
  std::vector<FieldInfo> out;
  for (const gtn::FieldDesc& f : fields) out.push_back({f.name, f.components, static_cast<ScalarType>(f.type)});
  return out;
}

FileInfo describe(const gtn::GtnReader& r) {
  const gtn::GtnFileInfo& file = r.file();
  const gtn::GtnFileHeader& h = file.header;
  FileInfo info;
  info.path = file.path;
  info.major = file.major;
  info.minor = file.minor;
  info.bytes = file.bytes;
  info.coord_type = static_cast<ScalarType>(h.coord_type);
  info.point_fields = fieldInfos(h.point_fields);
  info.cell_fields = fieldInfos(h.cell_fields);
  for (int k = 0; k < 3; ++k) {
    info.bbox_min[k] = h.bbox_min[k];
    info.bbox_max[k] = h.bbox_max[k];
  }
  info.tool_version = h.tool_version;
  info.command_line = h.command_line;
  info.metadata = h.metadata;
  for (size_t i = 0; i < r.levels(); ++i) {
    const gtn::GtnLevelInfo& l = r.level(i);
    LevelInfo level;
    level.points = l.header.points;
    level.tets = l.header.tets;
    level.merges = l.header.merges;
    level.ratio = l.ratio;
    level.has_merge_tree = l.has_merge_tree;
    level.bytes = l.bytes;
    for (size_t p = 0; p < l.pieces.size(); ++p) {
      const gtn::PieceInfo& pi = l.pieces[p];
      PieceInfo piece;
      piece.points = pi.points;
      piece.tets = pi.tets;
      for (int k = 0; k < 3; ++k) {
        piece.bbox_min[k] = pi.bbox_min[k];
        piece.bbox_max[k] = pi.bbox_max[k];
      }
      piece.bytes = l.pieceBytes(p);
      level.pieces.push_back(piece);
    }
    info.levels.push_back(level);
  }
  return info;
}
}  // namespace

Reader::Reader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Reader::Reader(Reader&& other) noexcept = default;
Reader& Reader::operator=(Reader&& other) noexcept = default;
Reader::~Reader() = default;

Result<Reader> Reader::open(const std::string& path) {
  gtn::GtnOpenOptions oo;
  oo.verify = false;  // random access through the directory; every chunk read is still checksummed
  auto opened = gtn::GtnReader::open(path, oo);
  if (!opened.isOk()) {
    // A mesh file given to read: say what reads it.
    const gtn::InputFormat format = gtn::detectInputFormat(path);
    if (format != gtn::InputFormat::kGtn && format != gtn::InputFormat::kUnknown)
      return Error(ErrorCode::kUsage, path + ": a " + gtn::inputFormatName(format) +
                                          " file, not .gtn: gatun::Reader reads .gtn files; gatun::importMesh reads "
                                          "this one, gatun::convert converts it");
    return gtn::api::toError(opened.status());
  }
  auto impl = std::make_unique<Impl>();
  impl->reader = std::move(opened).value();
  impl->info = describe(*impl->reader);
  return Reader(std::move(impl));
}

const FileInfo& Reader::info() const { return impl_->info; }

Result<Mesh> Reader::read(const ReadOptions& options, ReadReport* report) {
  gtn::GtnReader& r = *impl_->reader;
  const std::string& path = impl_->info.path;
  if (options.level && options.ratio) return Error(ErrorCode::kUsage, path + ": level and ratio exclude each other");
  if (options.ratio && !(*options.ratio >= 0 && *options.ratio <= 1))
    return Error(ErrorCode::kUsage, path + ": ratio " + std::to_string(*options.ratio) + " is not between 0 and 1");
  if (options.ratio && options.pieces)
    return Error(ErrorCode::kUsage,
                 path + ": pieces and ratio exclude each other (pieces are those of a stored level)");
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  if (options.box)
    for (int k = 0; k < 3; ++k) {
      lo[k] = (*options.box)[k];
      hi[k] = (*options.box)[k + 3];
      if (std::isnan(lo[k]) || std::isnan(hi[k]) || lo[k] > hi[k])
        return Error(ErrorCode::kUsage, path + ": box: its minimum must not exceed its maximum on each axis");
    }
  size_t level = options.level.value_or(0);
  if (level >= r.levels())
    return Error(ErrorCode::kUsage, path + ": level " + std::to_string(level) + ": the file holds " +
                                        std::to_string(r.levels()) + " level(s), 0 to " +
                                        std::to_string(r.levels() - 1));
  gtn::DecodeFields fields;  // every field unless options.fields names some
  if (!options.fields.empty()) {
    auto selected = gtn::selectDecodeFields(r.level(level).header, options.fields, path, "fields");
    if (!selected.isOk()) return gtn::api::toError(selected.status());
    fields = std::move(selected).value();
  }
  gtn::TetMeshBuilder builder;
  ReadReport done;
  const bool part = !options.ratio && (options.pieces || options.box);
  if (options.ratio) {
    auto target = gtn::mergesForRatio(r, *options.ratio);
    if (!target.isOk()) return gtn::api::toError(target.status());
    gtn::SimplifyPlan plan;
    if (gtn::Status st = gtn::streamSimplified(r, *target, builder, &plan, /*clamp=*/true, &fields); !st.isOk())
      return gtn::api::toError(st);
    done.level = plan.level;
    done.merges = r.level(plan.level).header.merges + plan.extra_merges;
    // Over the vertices tetrahedra use, as the stored levels' ratios and mergesForRatio count.
    auto free = gtn::levelZeroUnreferencedMerges(r);
    if (!free.isOk()) return gtn::api::toError(free.status());
    const uint64_t points = r.level(0).header.points;
    done.ratio = points > *free && done.merges > *free ? double(done.merges - *free) / double(points - *free) : 0.0;
  } else {
    // The pieces to decode: those named (every piece by default), of them those meeting the box.
    const std::vector<gtn::PieceInfo>& table = r.level(level).pieces;
    std::vector<uint32_t> chosen;
    if (options.pieces) {
      for (uint32_t p : *options.pieces)
        if (p >= table.size())
          return Error(ErrorCode::kUsage, path + ": level " + std::to_string(level) + ": pieces: no piece " +
                                              std::to_string(p) + " (the level has " + std::to_string(table.size()) +
                                              " piece(s), 0 to " + std::to_string(table.size() - 1) + ")");
      chosen = *options.pieces;
      std::sort(chosen.begin(), chosen.end());
      chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
    } else {
      chosen.resize(table.size());
      std::iota(chosen.begin(), chosen.end(), 0u);
    }
    if (options.box) {
      const std::vector<uint32_t> in_box = gtn::piecesInBox(table, lo, hi);
      std::vector<uint32_t> both;
      std::set_intersection(chosen.begin(), chosen.end(), in_box.begin(), in_box.end(), std::back_inserter(both));
      chosen = std::move(both);
    }
    if (chosen.size() == table.size()) {
      if (gtn::Status st = r.decodeLevel(level, builder, nullptr, &fields); !st.isOk()) return gtn::api::toError(st);
    } else if (chosen.empty()) {
      // Nothing to decode: no points, no tetrahedra, the level's fields.
      const gtn::LevelHeader& h = r.level(level).header;
      gtn::TetMesh& m = builder.mesh();
      m.coord_type = h.coord_type;
      m.metadata = h.metadata;
      for (const gtn::FieldDesc& f : h.point_fields) m.point_fields.emplace_back(f.name, f.components, f.type, 0);
      for (const gtn::FieldDesc& f : h.cell_fields) m.cell_fields.emplace_back(f.name, f.components, f.type, 0);
    } else {
      auto decoded = r.decodeLevelPieces(level, chosen, &fields);
      if (!decoded.isOk()) return gtn::api::toError(decoded.status());
      builder.mesh() = std::move(decoded.value().mesh);
      done.point_ids = std::move(decoded.value().global_vertex);
      done.tet_ids = std::move(decoded.value().global_tet);
    }
    done.level = level;
    done.merges = r.level(level).header.merges;
    done.ratio = r.level(level).ratio;
    done.pieces = std::move(chosen);
  }
  if (!options.fields.empty()) gtn::dropUndecodedFields(builder.mesh(), fields);
  if (part) {
    // The level's numbers: the indices themselves when every piece was decoded.
    if (done.point_ids.empty()) {
      done.point_ids.resize(builder.mesh().numPoints());
      std::iota(done.point_ids.begin(), done.point_ids.end(), 0u);
    }
    if (done.tet_ids.empty()) {
      done.tet_ids.resize(builder.mesh().numTets());
      std::iota(done.tet_ids.begin(), done.tet_ids.end(), uint64_t{0});
    }
  }
  if (options.box) {
    std::vector<size_t> kept_points, kept_tets;
    builder.mesh() = gtn::cropToBox(builder.mesh(), lo, hi, &kept_points, &kept_tets);
    if (part) {
      std::vector<uint32_t> point_ids(kept_points.size());
      for (size_t i = 0; i < kept_points.size(); ++i) point_ids[i] = done.point_ids[kept_points[i]];
      std::vector<uint64_t> tet_ids(kept_tets.size());
      for (size_t i = 0; i < kept_tets.size(); ++i) tet_ids[i] = done.tet_ids[kept_tets[i]];
      done.point_ids = std::move(point_ids);
      done.tet_ids = std::move(tet_ids);
    }
  }
  if (report) *report = std::move(done);
  return gtn::api::fromTetMesh(std::move(builder.mesh()));
}

Result<FileInfo> readInfo(const std::string& path) {
  Result<Reader> reader = Reader::open(path);
  if (!reader.ok()) return reader.error();
  return reader.value().info();
}

Result<Mesh> read(const std::string& path, const ReadOptions& options, ReadReport* report) {
  Result<Reader> reader = Reader::open(path);
  if (!reader.ok()) return reader.error();
  return reader.value().read(options, report);
}

}  // namespace gatun

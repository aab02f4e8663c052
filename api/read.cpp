// Reading .gtn files (include/gatun/read.h), as `gtn export` and the Python package's gatun.read do.
#include <cmath>
#include <memory>
#include <utility>

#include "convert/import.h"
#include "format/decode_fields.h"
#include "format/gtn_reader.h"
#include "gatun/read.h"
#include "internal.h"
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
    if (gtn::Status st = r.decodeLevel(level, builder, nullptr, &fields); !st.isOk()) return gtn::api::toError(st);
    done.level = level;
    done.merges = r.level(level).header.merges;
    done.ratio = r.level(level).ratio;
  }
  if (!options.fields.empty()) gtn::dropUndecodedFields(builder.mesh(), fields);
  if (report) *report = done;
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

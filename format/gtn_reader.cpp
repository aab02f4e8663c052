#include "format/gtn_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#define XXH_STATIC_LINKING_ONLY  // XXH3_state_t on the stack
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "format/file_io.h"

namespace gtn {

// Random-access bytes of the input: a regular file read with pread, or a buffered stream.
class GtnReader::Source {
 public:
  virtual ~Source() = default;
  virtual uint64_t size() const = 0;
  // Reads exactly n bytes at `offset` (the caller keeps offset + n within size()).
  virtual Status read(uint64_t offset, size_t n, uint8_t* out) = 0;
};

namespace {

class FileSource : public GtnReader::Source {
 public:
  FileSource(int fd, uint64_t size, std::string path) : fd_(fd), size_(size), path_(std::move(path)) {}
  ~FileSource() override { ::close(fd_); }
  uint64_t size() const override { return size_; }
  Status read(uint64_t offset, size_t n, uint8_t* out) override {
    while (n > 0) {
      const ssize_t r = ::pread(fd_, out, n, static_cast<off_t>(offset));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0)
        return ioError(path_ + ": read error at byte offset " + std::to_string(offset) + ": " +
                       (r == 0 ? std::string("the file shrank while being read") : std::strerror(errno)));
      out += r;
      offset += static_cast<uint64_t>(r);
      n -= static_cast<size_t>(r);
    }
    return Status::ok();
  }

 private:
  int fd_;
  uint64_t size_;
  std::string path_;
};

class MemorySource : public GtnReader::Source {
 public:
  explicit MemorySource(std::string data) : data_(std::move(data)) {}
  uint64_t size() const override { return data_.size(); }
  Status read(uint64_t offset, size_t n, uint8_t* out) override {
    std::memcpy(out, data_.data() + offset, n);
    return Status::ok();
  }

 private:
  std::string data_;
};

std::string at(const std::string& what, uint64_t offset) {
  return what + ": byte offset " + std::to_string(offset) + ": ";
}

bool isLevelTag(const ChunkTag& t) {
  return t == kTagBoundary || t == kTagConnectivity || t == kTagGeometry || t == kTagPointField || t == kTagCellField ||
         t == kTagMergeTree;
}
bool isKnownTag(const ChunkTag& t) {
  return isLevelTag(t) || t == kTagFileHeader || t == kTagLevelHeader || t == kTagDirectory || t == kTagEnd;
}

// Which tag the k-th known chunk after LHDR must have (k = 0, 1, ...): BNDY, CONN, GEOM, PFLD x np,
// CFLD x nc, then optionally MTRE.
ChunkTag expectedLevelTag(size_t k, size_t np, size_t nc) {
  if (k == 0) return kTagBoundary;
  if (k == 1) return kTagConnectivity;
  if (k == 2) return kTagGeometry;
  if (k < 3 + np) return kTagPointField;
  if (k < 3 + np + nc) return kTagCellField;
  return kTagMergeTree;
}

// Checks the next known chunk of a level against the required order; `k` counts known chunks so far.
Status checkLevelOrder(const ChunkTag& tag, size_t k, size_t np, size_t nc, uint64_t offset, size_t level,
                       const std::string& what) {
  if (k > 3 + np + nc)
    return invalidData(at(what, offset) + "chunk '" + tag.str() + "' after the end of level " + std::to_string(level) +
                       "'s chunks");
  const ChunkTag want = expectedLevelTag(k, np, nc);
  if (tag != want)
    return invalidData(at(what, offset) + "chunk '" + tag.str() + "' out of order in level " + std::to_string(level) +
                       ": expected '" + want.str() + "'");
  return Status::ok();
}

LevelHeader levelHeaderFrom(const GtnFileHeader& fh, const GtnLevelRecord& r) {
  LevelHeader h;
  h.level = static_cast<uint32_t>(r.level);
  h.merges = r.merges;
  h.points = r.points;
  h.tets = r.tets;
  h.boundary_triangles = r.boundary_triangles;
  h.coord_type = fh.coord_type;
  h.point_fields = fh.point_fields;
  h.cell_fields = fh.cell_fields;
  for (int i = 0; i < 3; ++i) {
    h.bbox_min[i] = r.bbox_min[i];
    h.bbox_max[i] = r.bbox_max[i];
  }
  h.metadata = fh.metadata;
  return h;
}

// Checks the decoder's event stream against the level header before passing it on.
class CheckingSink : public MeshSink {
 public:
  CheckingSink(MeshSink& inner, const LevelHeader& h, std::string what)
      : inner_(inner), h_(h), what_(std::move(what)) {}
  Status beginLevel(const LevelHeader& header) override { return inner_.beginLevel(header); }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    if (id != vertices_ || vertices_ >= h_.points)
      return fail("vertex " + std::to_string(id) + " out of sequence or beyond the declared " +
                  std::to_string(h_.points) + " points");
    ++vertices_;
    return inner_.vertex(id, xyz, values);
  }
  Status boundaryTriangle(const uint32_t v[3]) override {
    if (tris_ >= h_.boundary_triangles)
      return fail("more boundary triangles than the declared " + std::to_string(h_.boundary_triangles));
    for (int i = 0; i < 3; ++i)
      if (v[i] >= vertices_) return fail("boundary triangle refers to a vertex not yet emitted");
    ++tris_;
    return inner_.boundaryTriangle(v);
  }
  Status endBoundary() override { return inner_.endBoundary(); }
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override {
    if (tets_ >= h_.tets) return fail("more tetrahedra than the declared " + std::to_string(h_.tets));
    for (int i = 0; i < 4; ++i)
      if (v[i] >= vertices_) return fail("tetrahedron refers to a vertex not yet emitted");
    ++tets_;
    return inner_.tet(v, cell_values);
  }
  Status retireVertex(uint32_t id) override { return inner_.retireVertex(id); }
  Status endLevel() override {
    if (vertices_ != h_.points || tets_ != h_.tets || tris_ != h_.boundary_triangles)
      return fail("decoded " + std::to_string(vertices_) + " points, " + std::to_string(tets_) + " tetrahedra, " +
                  std::to_string(tris_) + " boundary triangles; the level header declares " +
                  std::to_string(h_.points) + ", " + std::to_string(h_.tets) + ", " +
                  std::to_string(h_.boundary_triangles));
    ended_ = true;
    return inner_.endLevel();
  }
  bool ended() const { return ended_; }

 private:
  Status fail(const std::string& reason) { return invalidData(what_ + ": " + reason); }
  MeshSink& inner_;
  const LevelHeader& h_;
  std::string what_;
  uint64_t vertices_ = 0, tets_ = 0, tris_ = 0;
  bool ended_ = false;
};

}  // namespace

LevelPayload GtnLevelStreams::payload() const {
  LevelPayload p;
  p.boundary = boundary;
  p.connectivity = connectivity;
  p.geometry = geometry;
  for (const auto& s : point_fields) p.point_fields.emplace_back(s);
  for (const auto& s : cell_fields) p.cell_fields.emplace_back(s);
  return p;
}

GtnReader::~GtnReader() = default;

StatusOr<std::unique_ptr<GtnReader>> GtnReader::open(const std::string& path, const GtnOpenOptions& options) {
  std::unique_ptr<GtnReader> r(new GtnReader());
  r->file_.path = path == "-" ? std::string("<stdin>") : path;
  if (path != "-" && isRegularFile(path)) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return ioError(path + ": cannot open: " + std::strerror(errno));
    struct stat sb;
    if (::fstat(fd, &sb) != 0) {
      ::close(fd);
      return ioError(path + ": cannot stat: " + std::strerror(errno));
    }
    r->source_ = std::make_unique<FileSource>(fd, static_cast<uint64_t>(sb.st_size), path);
  } else {
    GTN_ASSIGN_OR_RETURN(std::string data, readWholeFile(path));
    r->source_ = std::make_unique<MemorySource>(std::move(data));
  }
  r->tolerant_scan_ = !options.verify;
  return finishOpen(std::move(r), !options.verify && path != "-");
}

StatusOr<std::unique_ptr<GtnReader>> GtnReader::openMemory(std::string bytes, const std::string& name,
                                                           const GtnOpenOptions& options) {
  std::unique_ptr<GtnReader> r(new GtnReader());
  r->file_.path = name;
  r->source_ = std::make_unique<MemorySource>(std::move(bytes));
  r->tolerant_scan_ = !options.verify;
  return finishOpen(std::move(r), !options.verify);
}

StatusOr<std::unique_ptr<GtnReader>> GtnReader::finishOpen(std::unique_ptr<GtnReader> r, bool try_directory) {
  r->file_.bytes = r->source_->size();
  if (try_directory && r->openByDirectory().isOk()) {
    r->by_directory_ = true;
    return r;
  }
  GtnFileInfo fresh;
  fresh.path = r->file_.path;
  fresh.bytes = r->source_->size();
  r->file_ = std::move(fresh);
  r->levels_.clear();
  GTN_RETURN_IF_ERROR(r->scan());
  return r;
}

std::string GtnReader::sectionName(const ChunkTag& tag, size_t index_in_level) const {
  if (tag == kTagFileHeader) return "header";
  if (tag == kTagLevelHeader) return "level_header";
  if (tag == kTagBoundary) return "boundary";
  if (tag == kTagConnectivity) return "connectivity";
  if (tag == kTagGeometry) return "geometry";
  if (tag == kTagMergeTree) return "merge_tree";
  if (tag == kTagDirectory) return "directory";
  if (tag == kTagEnd) return "trailer";
  const auto& pf = file_.header.point_fields;
  const auto& cf = file_.header.cell_fields;
  if (tag == kTagPointField && index_in_level >= 3 && index_in_level - 3 < pf.size())
    return "point_field:" + pf[index_in_level - 3].name;
  if (tag == kTagCellField && index_in_level >= 3 + pf.size() && index_in_level - 3 - pf.size() < cf.size())
    return "cell_field:" + cf[index_in_level - 3 - pf.size()].name;
  return "unknown:" + tag.str();
}

StatusOr<std::vector<uint8_t>> GtnReader::readChunkBytes(const GtnChunkInfo& c, ChunkHeader* out_header) {
  const uint64_t size = source_->size();
  const std::string& what = file_.path;
  if (c.offset >= size) return invalidData(at(what, c.offset) + "chunk offset beyond the end of the file");
  uint8_t head[kChunkFixedHeaderSize + 8];
  const size_t avail = static_cast<size_t>(std::min<uint64_t>(sizeof head, size - c.offset));
  GTN_RETURN_IF_ERROR(source_->read(c.offset, avail, head));
  ChunkHeader h;
  size_t needed;
  GTN_RETURN_IF_ERROR(parseGtnChunkHeader({head, avail}, c.offset, size - c.offset, what, &h, &needed));
  if (c.bytes != 0 && (h.tag != c.tag || h.totalSize() != c.bytes))
    return invalidData(at(what, c.offset) + "expected chunk '" + c.tag.str() + "' of " + std::to_string(c.bytes) +
                       " bytes, found '" + h.tag.str() + "' of " + std::to_string(h.totalSize()) + " bytes");
  std::vector<uint8_t> chunk(h.totalSize());
  GTN_RETURN_IF_ERROR(source_->read(c.offset, chunk.size(), chunk.data()));
  *out_header = h;
  return chunk;
}

StatusOr<std::vector<uint8_t>> GtnReader::readChunk(const GtnChunkInfo& c, ChunkHeader* out_header) {
  ChunkHeader h;
  GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> chunk, readChunkBytes(c, &h));
  if (out_header) *out_header = h;
  return openGtnChunk(h, chunk, file_.path);
}

StatusOr<bool> GtnReader::checksumMatches(const GtnChunkInfo& c) {
  // c.offset and c.bytes come from a scan or a checked directory: the chunk lies within the file.
  if (c.bytes < kChunkFixedHeaderSize + kChunkChecksumSize || c.offset > source_->size() ||
      c.bytes > source_->size() - c.offset)
    return invalidData(at(file_.path, c.offset) + "chunk '" + c.tag.str() + "' reaches beyond the end of the file");
  XXH3_state_t state;
  XXH3_64bits_reset(&state);
  std::vector<uint8_t> buffer(static_cast<size_t>(std::min<uint64_t>(c.bytes, uint64_t{1} << 20)));
  const uint64_t body = c.bytes - kChunkChecksumSize;
  Status st;
  for (uint64_t done = 0; done < body && st.isOk();) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(buffer.size(), body - done));
    st = source_->read(c.offset + done, n, buffer.data());
    XXH3_64bits_update(&state, buffer.data(), n);
    done += n;
  }
  const uint64_t digest = XXH3_64bits_digest(&state);
  GTN_RETURN_IF_ERROR(st);
  uint8_t stored[kChunkChecksumSize];
  GTN_RETURN_IF_ERROR(source_->read(c.offset + body, kChunkChecksumSize, stored));
  uint64_t expected = 0;
  for (size_t i = 0; i < kChunkChecksumSize; ++i) expected |= static_cast<uint64_t>(stored[i]) << (8 * i);
  return digest == expected;
}

StatusOr<std::vector<GtnDamagedChunk>> GtnReader::damagedChunks() {
  std::vector<GtnDamagedChunk> out;
  auto check = [&](const GtnChunkInfo& c, int64_t level) -> Status {
    GTN_ASSIGN_OR_RETURN(bool ok, checksumMatches(c));
    if (ok) return Status::ok();
    GtnDamagedChunk d;
    d.chunk = c;
    d.level = level;
    d.message = at(file_.path, c.offset) + "checksum mismatch in chunk '" + c.tag.str() + "' (" +
                (level >= 0 ? "level " + std::to_string(level) + ", " : std::string()) + c.section + ", " +
                std::to_string(c.bytes) + " bytes): the chunk is damaged";
    out.push_back(std::move(d));
    return Status::ok();
  };
  for (const GtnChunkInfo& c : file_.chunks)
    if (c.tag == kTagFileHeader) GTN_RETURN_IF_ERROR(check(c, -1));
  for (size_t i = 0; i < levels_.size(); ++i)
    for (const GtnChunkInfo& c : levels_[i].chunks) GTN_RETURN_IF_ERROR(check(c, static_cast<int64_t>(i)));
  for (const GtnChunkInfo& c : file_.chunks)
    if (c.tag != kTagFileHeader) GTN_RETURN_IF_ERROR(check(c, -1));
  std::stable_sort(out.begin(), out.end(),
                   [](const GtnDamagedChunk& a, const GtnDamagedChunk& b) { return a.chunk.offset < b.chunk.offset; });
  return out;
}

StatusOr<std::unique_ptr<GtnReader>> openGtnChecked(const std::string& path, const GtnOpenOptions& options,
                                                    const std::function<void(const std::string&)>& warn) {
  GTN_ASSIGN_OR_RETURN(std::unique_ptr<GtnReader> reader, GtnReader::open(path, options));
  GTN_ASSIGN_OR_RETURN(std::vector<GtnDamagedChunk> damaged, reader->damagedChunks());
  if (warn)
    for (const GtnDamagedChunk& d : damaged) warn(d.message);
  return reader;
}

Status GtnReader::scan() {
  const uint64_t size = source_->size();
  const std::string& what = file_.path;
  uint8_t prefix[kGtnPrefixSize];
  const size_t n = static_cast<size_t>(std::min<uint64_t>(size, kGtnPrefixSize));
  GTN_RETURN_IF_ERROR(source_->read(0, n, prefix));
  GTN_RETURN_IF_ERROR(checkGtnPrefix({prefix, n}, what, &file_.major, &file_.minor));

  uint64_t pos = kGtnPrefixSize;
  bool have_header = false, have_dir = false, level_open = false;
  size_t known_in_level = 0;  // known chunks after the current LHDR
  GtnDirectory dir;
  uint64_t dir_offset = 0, dir_size = 0;

  auto closeLevel = [&](uint64_t offset) -> Status {
    if (!level_open) return Status::ok();
    level_open = false;
    const size_t required = 3 + file_.header.point_fields.size() + file_.header.cell_fields.size();
    if (known_in_level < required)
      return invalidData(
          at(what, offset) + "level " + std::to_string(levels_.size() - 1) + " ends without its '" +
          expectedLevelTag(known_in_level, file_.header.point_fields.size(), file_.header.cell_fields.size()).str() +
          "' chunk");
    return Status::ok();
  };
  auto checkLevelCount = [&](uint64_t offset) -> Status {
    if (levels_.size() != file_.header.level_count)
      return invalidData(at(what, offset) + "the file holds " + std::to_string(levels_.size()) +
                         " levels, the header declares " + std::to_string(file_.header.level_count));
    return Status::ok();
  };

  for (;;) {
    if (pos == size) return invalidData(at(what, pos) + "truncated: the file ends without its end chunk (GEND)");
    GtnChunkInfo c;
    c.offset = pos;
    ChunkHeader h;
    GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> chunk, readChunkBytes(c, &h));
    // A scan for partial reading goes past a damaged content chunk (nothing here reads its payload);
    // damagedChunks() names it and reading it fails. Structural chunks must be intact.
    const bool content = isLevelTag(h.tag) || (!isKnownTag(h.tag) && h.ancillary());
    std::vector<uint8_t> payload;
    if (!(tolerant_scan_ && content && !gtnChunkChecksumMatches(h, chunk))) {
      GTN_ASSIGN_OR_RETURN(payload, openGtnChunk(h, chunk, what));
    }
    std::vector<uint8_t>().swap(chunk);
    c.tag = h.tag;
    c.bytes = h.totalSize();
    c.stored_bytes = h.stored_size;
    c.raw_bytes = h.raw_size;
    c.zstd = h.zstd();
    const uint64_t payload_offset = pos + h.header_size;

    if (!have_header && h.tag != kTagFileHeader)
      return invalidData(at(what, pos) + "the first chunk must be 'GHDR', found '" + h.tag.str() + "'");
    if (h.tag == kTagFileHeader) {
      if (have_header) return invalidData(at(what, pos) + "a second 'GHDR' chunk");
      GTN_RETURN_IF_ERROR(decodeFileHeader(payload, payload_offset, what, &file_.header));
      have_header = true;
      c.section = sectionName(h.tag, 0);
      file_.chunks.push_back(c);
    } else if (h.tag == kTagLevelHeader) {
      if (have_dir) return invalidData(at(what, pos) + "a level after the directory");
      GTN_RETURN_IF_ERROR(closeLevel(pos));
      if (levels_.size() >= file_.header.level_count)
        return invalidData(at(what, pos) + "more levels than the " + std::to_string(file_.header.level_count) +
                           " the header declares");
      GtnLevelRecord rec;
      GTN_RETURN_IF_ERROR(decodeLevelRecord(payload, payload_offset, what, &rec));
      if (rec.level != levels_.size())
        return invalidData(at(what, payload_offset) + "level header says level " + std::to_string(rec.level) +
                           " where level " + std::to_string(levels_.size()) + " comes");
      if (rec.level == 0 && (rec.points != file_.header.points || rec.tets != file_.header.tets || rec.merges != 0))
        return invalidData(at(what, payload_offset) + "level 0's counts disagree with the file header");
      GtnLevelInfo li;
      li.header = levelHeaderFrom(file_.header, rec);
      li.ratio = rec.ratio;
      c.section = sectionName(h.tag, 0);
      li.chunks.push_back(c);
      li.bytes = c.bytes;
      levels_.push_back(std::move(li));
      level_open = true;
      known_in_level = 0;
    } else if (isLevelTag(h.tag)) {
      if (!level_open) return invalidData(at(what, pos) + "chunk '" + h.tag.str() + "' outside a level");
      GtnLevelInfo& li = levels_.back();
      GTN_RETURN_IF_ERROR(checkLevelOrder(h.tag, known_in_level, file_.header.point_fields.size(),
                                          file_.header.cell_fields.size(), pos, levels_.size() - 1, what));
      c.section = sectionName(h.tag, known_in_level);
      ++known_in_level;
      if (h.tag == kTagMergeTree) li.has_merge_tree = true;
      li.chunks.push_back(c);
      li.bytes += c.bytes;
    } else if (h.tag == kTagDirectory) {
      if (have_dir) return invalidData(at(what, pos) + "a second 'DIRC' chunk");
      GTN_RETURN_IF_ERROR(closeLevel(pos));
      GTN_RETURN_IF_ERROR(checkLevelCount(pos));
      GTN_RETURN_IF_ERROR(decodeDirectory(payload, payload_offset, what, file_.header.level_count, &dir));
      have_dir = true;
      dir_offset = pos;
      dir_size = c.bytes;
      c.section = sectionName(h.tag, 0);
      file_.chunks.push_back(c);
    } else if (h.tag == kTagEnd) {
      GTN_RETURN_IF_ERROR(closeLevel(pos));
      GTN_RETURN_IF_ERROR(checkLevelCount(pos));
      GtnTrailer t;
      GTN_RETURN_IF_ERROR(decodeTrailer(payload, payload_offset, what, &t));
      if (h.zstd() || h.ancillary() || c.bytes != kGtnTrailerSize)
        return invalidData(at(what, pos) + "the end chunk must be stored raw, critical, " +
                           std::to_string(kGtnTrailerSize) + " bytes");
      if (t.directory_offset != dir_offset || t.directory_size != dir_size)
        return invalidData(at(what, payload_offset) + "the end chunk points to a directory at offset " +
                           std::to_string(t.directory_offset) + " (" + std::to_string(t.directory_size) +
                           " bytes), but " +
                           (have_dir ? "the directory is at offset " + std::to_string(dir_offset) + " (" +
                                           std::to_string(dir_size) + " bytes)"
                                     : std::string("the file has none")));
      c.section = sectionName(h.tag, 0);
      file_.chunks.push_back(c);
      pos += c.bytes;
      if (pos != size)
        return invalidData(at(what, pos) + std::to_string(size - pos) +
                           " trailing bytes after the end chunk (GEND); the file must end there");
      break;
    } else {
      if (!h.ancillary())
        return invalidData(at(what, pos) + "unknown critical chunk '" + h.tag.str() +
                           "': this file needs a newer reader");
      c.section = sectionName(h.tag, 0);
      if (level_open) {
        levels_.back().chunks.push_back(c);
        levels_.back().bytes += c.bytes;
      } else {
        file_.chunks.push_back(c);
      }
    }
    pos += c.bytes;
  }

  file_.has_directory = have_dir;
  if (have_dir) {
    for (size_t i = 0; i < levels_.size(); ++i) {
      const auto& chunks = levels_[i].chunks;
      bool same = chunks.size() == dir[i].size();
      for (size_t k = 0; same && k < chunks.size(); ++k)
        same =
            chunks[k].tag == dir[i][k].tag && chunks[k].offset == dir[i][k].offset && chunks[k].bytes == dir[i][k].size;
      if (!same)
        return invalidData(at(what, dir_offset) + "the directory's entries for level " + std::to_string(i) +
                           " do not match the chunks in the file");
    }
  }
  return Status::ok();
}

Status GtnReader::openByDirectory() {
  const uint64_t size = source_->size();
  const std::string& what = file_.path;
  if (size < kGtnPrefixSize + kGtnTrailerSize) return invalidData(what + ": too short for random access");
  uint8_t prefix[kGtnPrefixSize];
  GTN_RETURN_IF_ERROR(source_->read(0, kGtnPrefixSize, prefix));
  GTN_RETURN_IF_ERROR(checkGtnPrefix(prefix, what, &file_.major, &file_.minor));

  GtnChunkInfo hc;
  hc.offset = kGtnPrefixSize;
  ChunkHeader h;
  GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> hp, readChunk(hc, &h));
  if (h.tag != kTagFileHeader) return invalidData(what + ": first chunk is not GHDR");
  GTN_RETURN_IF_ERROR(decodeFileHeader(hp, hc.offset + h.header_size, what, &file_.header));
  hc = {h.tag, "header", hc.offset, h.totalSize(), h.stored_size, h.raw_size, h.zstd()};
  const uint64_t levels_begin = hc.offset + hc.bytes;

  GtnChunkInfo ec{kTagEnd, "trailer", size - kGtnTrailerSize, kGtnTrailerSize, kGtnEndPayloadSize, kGtnEndPayloadSize,
                  false};
  GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> ep, readChunk(ec, &h));
  if (h.zstd() || h.ancillary()) return invalidData(what + ": malformed end chunk");
  GtnTrailer t;
  GTN_RETURN_IF_ERROR(decodeTrailer(ep, ec.offset + h.header_size, what, &t));
  if (t.directory_offset == 0) return invalidData(what + ": no directory");
  if (t.directory_offset < levels_begin || t.directory_offset + t.directory_size != ec.offset)
    return invalidData(what + ": the directory is not right before the end chunk");

  GtnChunkInfo dc{kTagDirectory, "directory", t.directory_offset, t.directory_size, 0, 0, false};
  GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> dp, readChunk(dc, &h));
  dc.stored_bytes = h.stored_size;
  dc.raw_bytes = h.raw_size;
  dc.zstd = h.zstd();
  GtnDirectory dir;
  GTN_RETURN_IF_ERROR(decodeDirectory(dp, dc.offset + h.header_size, what, file_.header.level_count, &dir));

  uint64_t expect_offset = levels_begin;
  const size_t np = file_.header.point_fields.size(), nc = file_.header.cell_fields.size();
  for (size_t i = 0; i < dir.size(); ++i) {
    if (dir[i].empty() || dir[i][0].tag != kTagLevelHeader)
      return invalidData(what + ": directory level " + std::to_string(i) + " does not start with LHDR");
    GtnLevelInfo li;
    size_t known = 0;
    for (const GtnDirectoryEntry& e : dir[i]) {
      // Levels may be preceded by ancillary chunks; within a level the chunks are contiguous.
      if (e.offset < expect_offset || (&e != &dir[i][0] && e.offset != expect_offset) ||
          e.offset > t.directory_offset || e.size > t.directory_offset - e.offset)
        return invalidData(what + ": directory entry out of place");
      expect_offset = e.offset + e.size;
      GtnChunkInfo c{e.tag, "", e.offset, e.size, 0, 0, false};
      if (e.tag == kTagLevelHeader) {
        if (&e != &dir[i][0]) return invalidData(what + ": directory level with two LHDR");
        c.section = "level_header";
        GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> lp, readChunk(c, &h));
        c.stored_bytes = h.stored_size;
        c.raw_bytes = h.raw_size;
        c.zstd = h.zstd();
        GtnLevelRecord rec;
        GTN_RETURN_IF_ERROR(decodeLevelRecord(lp, c.offset + h.header_size, what, &rec));
        if (rec.level != i) return invalidData(what + ": level index mismatch");
        if (rec.level == 0 && (rec.points != file_.header.points || rec.tets != file_.header.tets || rec.merges != 0))
          return invalidData(what + ": level 0's counts disagree with the file header");
        li.header = levelHeaderFrom(file_.header, rec);
        li.ratio = rec.ratio;
      } else if (isLevelTag(e.tag)) {
        GTN_RETURN_IF_ERROR(checkLevelOrder(e.tag, known, np, nc, e.offset, i, what));
        c.section = sectionName(e.tag, known);
        ++known;
        if (e.tag == kTagMergeTree) li.has_merge_tree = true;
      } else if (isKnownTag(e.tag)) {
        return invalidData(what + ": directory lists a '" + e.tag.str() + "' chunk inside a level");
      } else {
        c.section = "unknown:" + e.tag.str();
      }
      li.chunks.push_back(c);
      li.bytes += c.bytes;
    }
    if (known < 3 + np + nc) return invalidData(what + ": directory level " + std::to_string(i) + " is incomplete");
    levels_.push_back(std::move(li));
  }
  if (expect_offset != t.directory_offset) return invalidData(what + ": gap between the last level and the directory");
  file_.has_directory = true;
  file_.chunks = {hc, dc, ec};
  return Status::ok();
}

StatusOr<GtnLevelStreams> GtnReader::readLevelStreams(size_t i) {
  if (i >= levels_.size())
    return usageError(file_.path + ": level " + std::to_string(i) + " does not exist (the file has " +
                      std::to_string(levels_.size()) + ")");
  const GtnLevelInfo& li = levels_[i];
  GtnLevelStreams s;
  s.header = li.header;
  for (const GtnChunkInfo& c : li.chunks) {
    if (c.tag == kTagLevelHeader || c.tag == kTagMergeTree || !isLevelTag(c.tag)) continue;
    GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> p, readChunk(c));
    if (c.tag == kTagBoundary) s.boundary = std::move(p);
    else if (c.tag == kTagConnectivity) s.connectivity = std::move(p);
    else if (c.tag == kTagGeometry) s.geometry = std::move(p);
    else if (c.tag == kTagPointField) s.point_fields.push_back(std::move(p));
    else s.cell_fields.push_back(std::move(p));
  }
  return s;
}

StatusOr<std::optional<std::vector<uint8_t>>> GtnReader::mergeTreePayload(size_t i) {
  if (i >= levels_.size())
    return usageError(file_.path + ": level " + std::to_string(i) + " does not exist (the file has " +
                      std::to_string(levels_.size()) + ")");
  for (const GtnChunkInfo& c : levels_[i].chunks) {
    if (c.tag != kTagMergeTree) continue;
    GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> p, readChunk(c));
    return std::optional<std::vector<uint8_t>>(std::move(p));
  }
  return std::optional<std::vector<uint8_t>>();
}

Status GtnReader::decodeLevel(size_t i, MeshSink& sink, DecodeStats* stats, const DecodeFields* fields) {
  GTN_ASSIGN_OR_RETURN(GtnLevelStreams s, readLevelStreams(i));
  const std::string what = file_.path + ": level " + std::to_string(i);
  CheckingSink checker(sink, s.header, what);
  // The streams of the fields left out are freed once their declarations are read (a render of
  // blunt fin's density holds 0.3 MB less at its peak, and so does combustion's).
  DecodeFields selected;
  if (fields) {
    selected = *fields;
    selected.streams_done = [&s, fields](const std::vector<char>& point_out, const std::vector<char>& cell_out) {
      for (size_t f = 0; f < point_out.size() && f < s.point_fields.size(); ++f)
        if (point_out[f]) std::vector<uint8_t>().swap(s.point_fields[f]);
      for (size_t f = 0; f < cell_out.size() && f < s.cell_fields.size(); ++f)
        if (cell_out[f]) std::vector<uint8_t>().swap(s.cell_fields[f]);
      if (fields->streams_done) fields->streams_done(point_out, cell_out);
    };
  }
  GTN_RETURN_IF_ERROR(gtn::decodeLevel(s.header, s.payload(), checker, stats, what, fields ? &selected : nullptr));
  if (!checker.ended()) return invalidData(what + ": the decoder stopped before the end of the level");
  return Status::ok();
}

std::vector<GtnSection> GtnReader::sections() const {
  std::vector<GtnSection> out;
  auto add = [&](const std::string& name, uint64_t bytes) {
    for (GtnSection& s : out)
      if (s.name == name) {
        s.bytes += bytes;
        return;
      }
    out.push_back({name, bytes});
  };
  add("prefix", kGtnPrefixSize);
  for (const GtnChunkInfo& c : file_.chunks)
    if (c.tag == kTagFileHeader) add(c.section, c.bytes);
  for (const GtnLevelInfo& l : levels_)
    for (const GtnChunkInfo& c : l.chunks) add(c.section, c.bytes);
  for (const GtnChunkInfo& c : file_.chunks)
    if (c.tag != kTagFileHeader) add(c.section, c.bytes);
  return out;
}

}  // namespace gtn

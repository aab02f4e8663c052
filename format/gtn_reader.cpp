#include "format/gtn_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#define XXH_STATIC_LINKING_ONLY  // XXH3_state_t on the stack
#include <xxhash.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "codec/structured_piece.h"
#include "format/file_io.h"
#include "mesh/fresh_memory.h"

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

bool isLevelTag(const ChunkTag& t) { return t == kTagSeam || t == kTagPiece || t == kTagGrid || t == kTagMergeTree; }
bool isKnownTag(const ChunkTag& t) {
  return isLevelTag(t) || t == kTagFileHeader || t == kTagLevelHeader || t == kTagDirectory || t == kTagEnd;
}

// The chunks a level must hold after its LHDR, as its piece table lays them out: SEAM when it has
// several pieces, then each piece's chunk in piece order (kind 0: PIEC; kind 1: GRID). An optional
// MTRE follows them.
struct LevelLayout {
  std::vector<ChunkTag> tags;
  std::vector<uint32_t> piece;  // per entry: its piece, or kNoIndex (SEAM)
  size_t size() const { return tags.size(); }
};

LevelLayout levelLayout(const std::vector<PieceInfo>& pieces) {
  LevelLayout l;
  if (pieces.size() > 1) {
    l.tags.push_back(kTagSeam);
    l.piece.push_back(kNoIndex);
  }
  for (size_t p = 0; p < pieces.size(); ++p) {
    l.tags.push_back(pieces[p].kind == kPieceStructured ? kTagGrid : kTagPiece);
    l.piece.push_back(static_cast<uint32_t>(p));
  }
  return l;
}

std::string inPiece(const LevelLayout& l, size_t k) {
  return k < l.size() && l.piece[k] != kNoIndex ? " (piece " + std::to_string(l.piece[k]) + ")" : std::string();
}

// Checks the k-th known chunk after a level's LHDR (k = 0, 1, ...) against the level's layout.
Status checkLevelOrder(const ChunkTag& tag, size_t k, const LevelLayout& layout, uint64_t offset, size_t level,
                       const std::string& what) {
  if (k > layout.size())
    return invalidData(at(what, offset) + "chunk '" + tag.str() + "' after the end of level " + std::to_string(level) +
                       "'s chunks");
  const ChunkTag want = k < layout.size() ? layout.tags[k] : kTagMergeTree;
  if (tag == want) return Status::ok();
  if (want == kTagSeam)
    return invalidData(at(what, offset) + "level " + std::to_string(level) +
                       " has several pieces but no 'SEAM' chunk after its 'LHDR' (found '" + tag.str() + "')");
  return invalidData(at(what, offset) + "chunk '" + tag.str() + "' out of order in level " + std::to_string(level) +
                     inPiece(layout, k) + ": expected '" + want.str() + "'");
}

// A PIEC chunk's payload must hold exactly the streams its LHDR entry lists.
Status checkPieceStreams(const GtnLevelInfo& li, const GtnChunkInfo& c, uint64_t payload_size,
                         const std::string& what) {
  const uint64_t sum = li.pieceStreamBytes(c.piece);
  if (sum != payload_size)
    return invalidData(at(what, c.offset) + "piece " + std::to_string(c.piece) + "'s stream sizes (LHDR) sum to " +
                       std::to_string(sum) + " bytes, but its 'PIEC' payload holds " + std::to_string(payload_size));
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
    peak_live_ = std::max(peak_live_, ++live_);
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
  Status retireVertex(uint32_t id) override {
    if (live_ > 0) --live_;
    return inner_.retireVertex(id);
  }
  Status endLevel() override {
    if (vertices_ != h_.points || tets_ != h_.tets || tris_ != h_.boundary_triangles)
      return fail("decoded " + std::to_string(vertices_) + " points, " + std::to_string(tets_) + " tetrahedra, " +
                  std::to_string(tris_) + " boundary triangles; the level header declares " +
                  std::to_string(h_.points) + ", " + std::to_string(h_.tets) + ", " +
                  std::to_string(h_.boundary_triangles));
    ended_ = true;
    return inner_.endLevel();
  }
  bool takesWholeLevel() const override { return inner_.takesWholeLevel(); }
  Status wholeLevel(const LevelHeader& header, TetMesh&& mesh,
                    std::vector<std::array<uint32_t, 3>>&& boundary) override {
    const uint64_t points = mesh.numPoints();
    if (points != h_.points || mesh.numTets() != h_.tets || boundary.size() != h_.boundary_triangles)
      return fail("decoded " + std::to_string(points) + " points, " + std::to_string(mesh.numTets()) + " tetrahedra, " +
                  std::to_string(boundary.size()) + " boundary triangles; the level header declares " +
                  std::to_string(h_.points) + ", " + std::to_string(h_.tets) + ", " +
                  std::to_string(h_.boundary_triangles));
    // The largest vertex named, over the tetrahedra in parallel (a grid's level is millions of them).
    uint32_t top = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, mesh.tets.size(), size_t{1} << 16), uint32_t{0},
        [&](const tbb::blocked_range<size_t>& r, uint32_t m) {
          for (size_t i = r.begin(); i < r.end(); ++i) {
            const Tet& t = mesh.tets[i];
            m = std::max({m, t[0], t[1], t[2], t[3]});
          }
          return m;
        },
        [](uint32_t a, uint32_t b) { return std::max(a, b); });
    for (const auto& t : boundary) top = std::max({top, t[0], t[1], t[2]});
    if ((h_.tets > 0 || h_.boundary_triangles > 0) && top >= points)
      return fail("a tetrahedron or boundary triangle refers to vertex " + std::to_string(top) + " of " +
                  std::to_string(points));
    vertices_ = points, tets_ = h_.tets, tris_ = h_.boundary_triangles;
    ended_ = true;
    return inner_.wholeLevel(header, std::move(mesh), std::move(boundary));
  }
  bool ended() const { return ended_; }
  uint64_t peakLive() const { return peak_live_; }  // most vertices emitted and not yet retired

 private:
  Status fail(const std::string& reason) { return invalidData(what_ + ": " + reason); }
  MeshSink& inner_;
  const LevelHeader& h_;
  std::string what_;
  uint64_t vertices_ = 0, tets_ = 0, tris_ = 0, live_ = 0, peak_live_ = 0;
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

Status GtnReader::readSource(uint64_t offset, size_t n, uint8_t* out) {
  bytes_read_ += n;
  return source_->read(offset, n, out);
}

uint64_t GtnLevelInfo::pieceStreamBytes(size_t piece) const {
  uint64_t sum = 0;
  for (uint64_t size : piece_streams.at(piece)) sum += size;
  return sum;
}

bool GtnLevelInfo::pieceStoredRaw(const GtnChunkInfo& c) const {
  return c.tag == kTagPiece && c.bytes == kChunkFixedHeaderSize + pieceStreamBytes(c.piece) + kChunkChecksumSize;
}

uint64_t GtnLevelInfo::pieceBytes(size_t piece) const {
  uint64_t n = 0;
  for (size_t k = piece_chunk.at(piece); k < chunks.size(); ++k) {
    if (chunks[k].piece == piece) n += chunks[k].bytes;
    else if (chunks[k].piece != kNoIndex) break;
  }
  return n;
}

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
  // A level that names the next level's vertices needs that level.
  auto checkBases = [](const GtnReader& g) -> Status {
    if (!g.levels_.empty() && g.levels_.back().base != 0)
      return invalidData(g.file_.path + ": level " + std::to_string(g.levels_.size() - 1) +
                         " names the vertices of the next level (LHDR base 1), but it is the file's last level");
    uint64_t run = 0;
    for (size_t i = 0; i < g.levels_.size(); ++i) {
      run = g.levels_[i].base != 0 ? run + 1 : 0;
      if (run > kGtnMaxNamingRun)
        return invalidData(g.file_.path + ": levels " + std::to_string(i + 1 - run) + " to " + std::to_string(i) +
                           " each name the next level's vertices, more than " + std::to_string(kGtnMaxNamingRun) +
                           " in a row");
    }
    return Status::ok();
  };
  if (try_directory && r->openByDirectory().isOk()) {
    r->by_directory_ = true;
    GTN_RETURN_IF_ERROR(checkBases(*r));
    return r;
  }
  GtnFileInfo fresh;
  fresh.path = r->file_.path;
  fresh.bytes = r->source_->size();
  r->file_ = std::move(fresh);
  r->levels_.clear();
  GTN_RETURN_IF_ERROR(r->scan());
  GTN_RETURN_IF_ERROR(checkBases(*r));
  return r;
}

std::string GtnReader::sectionName(const ChunkTag& tag) const {
  if (tag == kTagFileHeader) return "header";
  if (tag == kTagLevelHeader) return "level_header";
  if (tag == kTagSeam) return "seam";
  if (tag == kTagGrid) return "grid";
  if (tag == kTagPiece) return "piece";
  if (tag == kTagMergeTree) return "merge_tree";
  if (tag == kTagDirectory) return "directory";
  if (tag == kTagEnd) return "trailer";
  return "unknown:" + tag.str();
}

std::string GtnReader::streamSectionName(size_t k) const {
  const auto& pf = file_.header.point_fields;
  const auto& cf = file_.header.cell_fields;
  if (k == 0) return "boundary";
  if (k == 1) return "connectivity";
  if (k == 2) return "geometry";
  if (k - 3 < pf.size()) return "point_field:" + pf[k - 3].name;
  if (k - 3 - pf.size() < cf.size()) return "cell_field:" + cf[k - 3 - pf.size()].name;
  return "stream " + std::to_string(k);
}

StatusOr<std::vector<uint8_t>> GtnReader::readChunkBytes(const GtnChunkInfo& c, ChunkHeader* out_header) {
  const uint64_t size = source_->size();
  const std::string& what = file_.path;
  if (c.offset >= size) return invalidData(at(what, c.offset) + "chunk offset beyond the end of the file");
  uint8_t head[kChunkFixedHeaderSize + 8];
  const size_t avail = static_cast<size_t>(std::min<uint64_t>(sizeof head, size - c.offset));
  GTN_RETURN_IF_ERROR(readSource(c.offset, avail, head));
  ChunkHeader h;
  size_t needed;
  GTN_RETURN_IF_ERROR(parseGtnChunkHeader({head, avail}, c.offset, size - c.offset, what, &h, &needed));
  if (c.bytes != 0 && (h.tag != c.tag || h.totalSize() != c.bytes))
    return invalidData(at(what, c.offset) + "expected chunk '" + c.tag.str() + "' of " + std::to_string(c.bytes) +
                       " bytes, found '" + h.tag.str() + "' of " + std::to_string(h.totalSize()) + " bytes");
  std::vector<uint8_t> chunk;
  resizePopulated(chunk, h.totalSize());
  GTN_RETURN_IF_ERROR(readSource(c.offset, chunk.size(), chunk.data()));
  *out_header = h;
  return chunk;
}

StatusOr<std::vector<uint8_t>> GtnReader::readChunk(const GtnChunkInfo& c, ChunkHeader* out_header) {
  ChunkHeader h;
  GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> chunk, readChunkBytes(c, &h));
  if (out_header) *out_header = h;
  return openGtnChunk(h, std::move(chunk), file_.path);
}

StatusOr<bool> GtnReader::checksumMatches(const GtnChunkInfo& c) {
  // c.offset and c.bytes come from a scan or a checked directory: the chunk lies within the file.
  if (c.bytes < kChunkFixedHeaderSize + kChunkChecksumSize || c.offset > source_->size() ||
      c.bytes > source_->size() - c.offset)
    return invalidData(at(file_.path, c.offset) + "chunk '" + c.tag.str() + "' reaches beyond the end of the file");
  XXH3_state_t state;
  XXH3_64bits_reset(&state);
  // A buffer that stays in cache (and in pages already mapped), read again for each part.
  std::vector<uint8_t> buffer(static_cast<size_t>(std::min<uint64_t>(c.bytes, uint64_t{1} << 16)));
  const uint64_t body = c.bytes - kChunkChecksumSize;
  Status st;
  for (uint64_t done = 0; done < body && st.isOk();) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(buffer.size(), body - done));
    st = readSource(c.offset + done, n, buffer.data());
    XXH3_64bits_update(&state, buffer.data(), n);
    done += n;
  }
  const uint64_t digest = XXH3_64bits_digest(&state);
  GTN_RETURN_IF_ERROR(st);
  uint8_t stored[kChunkChecksumSize];
  GTN_RETURN_IF_ERROR(readSource(c.offset + body, kChunkChecksumSize, stored));
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
  GTN_RETURN_IF_ERROR(readSource(0, n, prefix));
  GTN_RETURN_IF_ERROR(checkGtnPrefix({prefix, n}, what, &file_.major, &file_.minor));

  uint64_t pos = kGtnPrefixSize;
  bool have_header = false, have_dir = false, level_open = false;
  LevelRecordContext record_context;  // what the next LHDR is coded against (set by GHDR)
  size_t known_in_level = 0;          // known chunks after the current LHDR
  LevelLayout layout;                 // the chunks the current level must hold after its LHDR
  GtnDirectory dir;
  uint64_t dir_offset = 0, dir_size = 0;

  auto closeLevel = [&](uint64_t offset) -> Status {
    if (!level_open) return Status::ok();
    level_open = false;
    if (known_in_level < layout.size())
      return invalidData(at(what, offset) + "level " + std::to_string(levels_.size() - 1) + " ends without its '" +
                         layout.tags[known_in_level].str() + "' chunk" + inPiece(layout, known_in_level));
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
    const bool opened = !(tolerant_scan_ && content && !gtnChunkChecksumMatches(h, chunk));
    if (opened) {
      GTN_ASSIGN_OR_RETURN(payload, openGtnChunk(h, std::move(chunk), what));
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
      record_context = levelRecordContext(file_.header);
      have_header = true;
      c.section = sectionName(h.tag);
      file_.chunks.push_back(c);
    } else if (h.tag == kTagLevelHeader) {
      if (have_dir) return invalidData(at(what, pos) + "a level after the directory");
      GTN_RETURN_IF_ERROR(closeLevel(pos));
      if (levels_.size() >= file_.header.level_count)
        return invalidData(at(what, pos) + "more levels than the " + std::to_string(file_.header.level_count) +
                           " the header declares");
      GtnLevelRecord rec;
      GTN_RETURN_IF_ERROR(decodeLevelRecord(payload, payload_offset, what, record_context, &rec));
      record_context = nextLevelRecordContext(record_context, rec);
      if (rec.level != levels_.size())
        return invalidData(at(what, payload_offset) + "level header says level " + std::to_string(rec.level) +
                           " where level " + std::to_string(levels_.size()) + " comes");
      if (rec.level == 0 && (rec.points != file_.header.points || rec.tets != file_.header.tets || rec.merges != 0))
        return invalidData(at(what, payload_offset) + "level 0's counts disagree with the file header");
      GtnLevelInfo li;
      li.header = levelHeaderFrom(file_.header, rec);
      li.ratio = rec.ratio;
      layout = levelLayout(rec.pieces);
      li.pieces = std::move(rec.pieces);
      li.piece_streams = std::move(rec.streams);
      li.piece_chunk.assign(li.pieces.size(), 0);
      li.base = rec.base;
      c.section = sectionName(h.tag);
      li.chunks.push_back(c);
      li.bytes = c.bytes;
      levels_.push_back(std::move(li));
      level_open = true;
      known_in_level = 0;
    } else if (isLevelTag(h.tag)) {
      if (!level_open) return invalidData(at(what, pos) + "chunk '" + h.tag.str() + "' outside a level");
      GtnLevelInfo& li = levels_.back();
      GTN_RETURN_IF_ERROR(checkLevelOrder(h.tag, known_in_level, layout, pos, levels_.size() - 1, what));
      if (h.tag == kTagSeam && opened) {
        GtnSeamTable table;
        GTN_RETURN_IF_ERROR(
            decodeSeamTable(payload, payload_offset, what, levels_.size() - 1, li.header.points, li.pieces, &table));
      }
      const bool in_piece = known_in_level < layout.size() && layout.piece[known_in_level] != kNoIndex;
      c.piece = in_piece ? layout.piece[known_in_level] : kNoIndex;
      c.section = sectionName(h.tag);
      if (in_piece) {
        li.piece_chunk[c.piece] = li.chunks.size();
        if (h.tag == kTagPiece && opened) GTN_RETURN_IF_ERROR(checkPieceStreams(li, c, payload.size(), what));
      }
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
      c.section = sectionName(h.tag);
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
      c.section = sectionName(h.tag);
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
      c.section = sectionName(h.tag);
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
  GTN_RETURN_IF_ERROR(readSource(0, kGtnPrefixSize, prefix));
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
  LevelRecordContext record_context = levelRecordContext(file_.header);
  for (size_t i = 0; i < dir.size(); ++i) {
    if (dir[i].empty() || dir[i][0].tag != kTagLevelHeader)
      return invalidData(what + ": directory level " + std::to_string(i) + " does not start with LHDR");
    GtnLevelInfo li;
    LevelLayout layout;
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
        GTN_RETURN_IF_ERROR(decodeLevelRecord(lp, c.offset + h.header_size, what, record_context, &rec));
        record_context = nextLevelRecordContext(record_context, rec);
        if (rec.level != i) return invalidData(what + ": level index mismatch");
        if (rec.level == 0 && (rec.points != file_.header.points || rec.tets != file_.header.tets || rec.merges != 0))
          return invalidData(what + ": level 0's counts disagree with the file header");
        li.header = levelHeaderFrom(file_.header, rec);
        li.ratio = rec.ratio;
        layout = levelLayout(rec.pieces);
        li.pieces = std::move(rec.pieces);
        li.piece_streams = std::move(rec.streams);
        li.piece_chunk.assign(li.pieces.size(), 0);
        li.base = rec.base;
      } else if (isLevelTag(e.tag)) {
        GTN_RETURN_IF_ERROR(checkLevelOrder(e.tag, known, layout, e.offset, i, what));
        const bool in_piece = known < layout.size() && layout.piece[known] != kNoIndex;
        c.piece = in_piece ? layout.piece[known] : kNoIndex;
        c.section = sectionName(e.tag);
        if (in_piece) li.piece_chunk[c.piece] = li.chunks.size();
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
    if (known < layout.size()) return invalidData(what + ": directory level " + std::to_string(i) + " is incomplete");
    levels_.push_back(std::move(li));
  }
  if (expect_offset != t.directory_offset) return invalidData(what + ": gap between the last level and the directory");
  file_.has_directory = true;
  file_.chunks = {hc, dc, ec};
  return Status::ok();
}

StatusOr<GtnLevelStreams> GtnReader::readPieceStreams(size_t i, size_t piece) {
  if (i >= levels_.size())
    return usageError(file_.path + ": level " + std::to_string(i) + " does not exist (the file has " +
                      std::to_string(levels_.size()) + ")");
  const GtnLevelInfo& li = levels_[i];
  if (piece >= li.pieces.size())
    return usageError(file_.path + ": level " + std::to_string(i) + " has no piece " + std::to_string(piece) +
                      " (it has " + std::to_string(li.pieces.size()) + ")");
  GtnLevelStreams s;
  s.header = li.pieces.size() == 1 ? li.header : pieceHeader(li.header, li.pieces[piece]);
  const GtnChunkInfo& c = li.chunks.at(li.piece_chunk[piece]);
  GTN_ASSIGN_OR_RETURN(std::vector<uint8_t> p, readChunk(c));
  if (c.tag == kTagGrid) {
    s.connectivity = std::move(p);
    return s;
  }
  // A PIEC: its streams in order, as long as LHDR says.
  GTN_RETURN_IF_ERROR(checkPieceStreams(li, c, p.size(), file_.path));
  const std::vector<uint64_t>& sizes = li.piece_streams[piece];
  const size_t np = file_.header.point_fields.size();
  uint64_t at = 0;
  for (size_t k = 0; k < sizes.size(); ++k) {
    std::vector<uint8_t> stream(p.begin() + static_cast<std::ptrdiff_t>(at),
                                p.begin() + static_cast<std::ptrdiff_t>(at + sizes[k]));
    at += sizes[k];
    if (k == 0) s.boundary = std::move(stream);
    else if (k == 1) s.connectivity = std::move(stream);
    else if (k == 2) s.geometry = std::move(stream);
    else if (k - 3 < np) s.point_fields.push_back(std::move(stream));
    else s.cell_fields.push_back(std::move(stream));
  }
  return s;
}

StatusOr<GtnLevelStreams> GtnReader::readLevelStreams(size_t i) {
  if (i < levels_.size() && levels_[i].pieces.size() > 1)
    return usageError(file_.path + ": level " + std::to_string(i) + " has " + std::to_string(levels_[i].pieces.size()) +
                      " pieces; read them one by one");
  return readPieceStreams(i, 0);
}

StatusOr<GtnSeamTable> GtnReader::readSeamTable(size_t i, std::vector<uint8_t>* payload) {
  if (i >= levels_.size())
    return usageError(file_.path + ": level " + std::to_string(i) + " does not exist (the file has " +
                      std::to_string(levels_.size()) + ")");
  const GtnLevelInfo& li = levels_[i];
  GtnSeamTable table;
  payload->clear();
  if (li.pieces.size() == 1) return table;
  for (const GtnChunkInfo& c : li.chunks) {
    if (c.tag != kTagSeam) continue;
    ChunkHeader h;
    GTN_ASSIGN_OR_RETURN(*payload, readChunk(c, &h));
    GTN_RETURN_IF_ERROR(
        decodeSeamTable(*payload, c.offset + h.header_size, file_.path, i, li.header.points, li.pieces, &table));
    return table;
  }
  return invalidData(file_.path + ": level " + std::to_string(i) + " has several pieces but no 'SEAM' chunk");
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

StatusOr<DecodedPieces> GtnReader::decodeLevelPieces(size_t i, const std::vector<uint32_t>& chosen,
                                                     const DecodeFields* fields) {
  if (i >= levels_.size())
    return usageError(file_.path + ": level " + std::to_string(i) + " does not exist (the file has " +
                      std::to_string(levels_.size()) + ")");
  const GtnLevelInfo& li = levels_[i];
  const size_t n = li.pieces.size();
  for (size_t k = 0; k < chosen.size(); ++k)
    if (chosen[k] >= n || (k > 0 && chosen[k] <= chosen[k - 1]))
      return usageError(file_.path + ": level " + std::to_string(i) + ": pieces must be chosen in increasing order, " +
                        "each below " + std::to_string(n));
  if (li.base != 0) {
    // One piece that names the next level's vertices: decoded as a stream, after the levels it names.
    TetMeshBuilder builder;
    GTN_RETURN_IF_ERROR(decodeLevel(i, builder, nullptr, fields));
    DecodedPieces out;
    out.mesh = std::move(builder.mesh());
    out.boundary = builder.boundary();
    return out;
  }
  std::vector<char> wanted(n, chosen.empty() ? 1 : 0);
  for (uint32_t p : chosen) wanted[p] = 1;
  std::vector<uint8_t> seam_payload;
  GTN_ASSIGN_OR_RETURN(GtnSeamTable table, readSeamTable(i, &seam_payload));
  PiecedLevelView view;
  view.header = &li.header;
  view.pieces = li.pieces;
  view.classes = table.classes;
  view.seam_streams.resize(table.classes.size());
  for (size_t c = 0; c < table.classes.size(); ++c) {
    bool needed = false;
    for (uint32_t p : table.classes[c].pieces) needed = needed || wanted[p];
    if (needed)
      view.seam_streams[c] =
          std::span<const uint8_t>(seam_payload).subspan(table.streams[c].first, table.streams[c].second);
  }
  // The chosen pieces' chunks, read and decompressed in parallel; the first failure in piece order is
  // reported, whatever the thread count.
  std::vector<GtnLevelStreams> streams(n);
  std::vector<Status> failed(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t p = range.begin(); p < range.end(); ++p) {
      if (!wanted[p]) continue;
      auto s = readPieceStreams(i, p);
      if (s.isOk()) streams[p] = std::move(s).value();
      else failed[p] = s.status();
    }
  });
  for (const Status& st : failed) GTN_RETURN_IF_ERROR(st);
  view.payloads.resize(n);
  for (size_t p = 0; p < n; ++p) {
    if (!wanted[p]) continue;
    view.payloads[p].header = streams[p].header;
    view.payloads[p].streams = streams[p].payload();
  }
  return decodePieces(view, chosen, file_.path + ": level " + std::to_string(i), fields);
}

namespace {

// Collects a level's vertices (coordinates and point values, by id) as the seam values of the level
// that names them.
class BaseValues : public MeshSink {
 public:
  Status beginLevel(const LevelHeader& header) override {
    item_ = 0;
    for (const FieldDesc& f : header.point_fields) item_ += f.itemBytes();
    return Status::ok();
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    if (id != count_) return invalidData("base level: vertex ids out of order");
    coords.insert(coords.end(), xyz, xyz + 3);
    if (item_) this->values.insert(this->values.end(), values, values + item_);
    ++count_;
    return Status::ok();
  }
  Status boundaryTriangle(const uint32_t*) override { return Status::ok(); }
  Status endBoundary() override { return Status::ok(); }
  Status tet(const uint32_t*, const uint8_t*) override { return Status::ok(); }
  Status retireVertex(uint32_t) override { return Status::ok(); }
  Status endLevel() override { return Status::ok(); }
  uint32_t count() const { return count_; }

  std::vector<double> coords;
  std::vector<uint8_t> values;

 private:
  size_t item_ = 0;
  uint32_t count_ = 0;
};

}  // namespace

Status GtnReader::decodeLevel(size_t i, MeshSink& sink, DecodeStats* stats, const DecodeFields* fields,
                              std::vector<uint32_t>* base_ids) {
  if (base_ids) base_ids->clear();
  if (i >= levels_.size() || levels_[i].base == 0) return decodeOnePiece(i, sink, stats, fields, nullptr);
  // The levels it names, coarsest first, each with the values of the one after it (the reader checked
  // at open that the run ends within the file and is at most kGtnMaxNamingRun long).
  size_t last = i;
  while (levels_[last].base != 0) ++last;
  BaseValues next;
  GTN_RETURN_IF_ERROR(decodeOnePiece(last, next, nullptr, fields, nullptr));
  std::vector<uint32_t> local;
  for (size_t k = last; k-- > i + 1;) {
    BaseValues values;
    SeamValues seams{next.count(), next.coords.data(), next.values.data(), &local};
    GTN_RETURN_IF_ERROR(decodeOnePiece(k, values, nullptr, fields, &seams));
    local.clear();
    next = std::move(values);
  }
  SeamValues seams{next.count(), next.coords.data(), next.values.data(), base_ids ? base_ids : &local};
  return decodeOnePiece(i, sink, stats, fields, &seams);
}

Status GtnReader::decodeOnePiece(size_t i, MeshSink& sink, DecodeStats* stats, const DecodeFields* fields,
                                 const SeamValues* seams) {
  const std::string what = file_.path + ": level " + std::to_string(i);
  if (i < levels_.size() && levels_[i].pieces.size() > 1) {
    GTN_ASSIGN_OR_RETURN(DecodedPieces decoded, decodeLevelPieces(i, {}, fields));
    const LevelHeader& header = levels_[i].header;
    CheckingSink checker(sink, header, what);
    GTN_RETURN_IF_ERROR(emitDecoded(header, decoded, checker));
    if (!checker.ended()) return invalidData(what + ": the decoded level was not emitted to its end");
    if (stats) stats->peak_live_vertices = checker.peakLive();
    return Status::ok();
  }
  GTN_ASSIGN_OR_RETURN(GtnLevelStreams s, readLevelStreams(i));
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
  if (i < levels_.size() && !levels_[i].pieces.empty() && levels_[i].pieces[0].kind == kPieceStructured) {
    GTN_RETURN_IF_ERROR(decodeStructuredPiece(s.header, s.connectivity, checker, what, fields));
  } else {
    GTN_RETURN_IF_ERROR(
        gtn::decodeLevel(s.header, s.payload(), checker, stats, what, fields ? &selected : nullptr, seams));
  }
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
    for (const GtnChunkInfo& c : l.chunks) {
      // A piece stored raw: its streams each to their own section, its framing to "piece_framing";
      // stored compressed, the whole chunk to "piece".
      if (!l.pieceStoredRaw(c)) {
        add(c.section, c.bytes);
        continue;
      }
      const std::vector<uint64_t>& sizes = l.piece_streams[c.piece];
      for (size_t k = 0; k < sizes.size(); ++k) add(streamSectionName(k), sizes[k]);
      add("piece_framing", kChunkFixedHeaderSize + kChunkChecksumSize);
    }
  for (const GtnChunkInfo& c : file_.chunks)
    if (c.tag != kTagFileHeader) add(c.section, c.bytes);
  return out;
}

}  // namespace gtn

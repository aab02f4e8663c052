// Reading .gtn files (spec/gtn-format.md): validation of the prefix, framing, checksums, sizes and
// chunk order; per-level information; decoding a level to a MeshSink; random access to a level through
// the directory when the file is seekable.
//
// Every failure is a Status whose message names the file, the byte offset and the reason: kNotOurFile
// (bad magic), kVersionTooNew (newer major version), kInvalidData (truncation, trailing bytes, checksum
// mismatch, unknown critical chunk, bad sizes, chunks out of order, corrupt codec streams), kIo (cannot
// open or read). Allocations are bounded by the file's size: no length is trusted beyond the bytes that
// remain.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "codec/pieces.h"
#include "format/gtn_records.h"
#include "mesh/index.h"
#include "mesh/mesh_stream.h"

namespace gtn {

struct GtnChunkInfo {
  ChunkTag tag;
  std::string section;        // "piece", "grid", "seam", "unknown:abcd", ... (see sections())
  uint64_t offset = 0;        // of the chunk's first byte
  uint64_t bytes = 0;         // the whole chunk: framing, stored payload, checksum
  uint64_t stored_bytes = 0;  // payload as stored (0 when only known from the directory)
  uint64_t raw_bytes = 0;     // payload after decompression (0 when only known from the directory)
  bool zstd = false;
  uint32_t piece = kNoIndex;  // the piece whose stream it holds; kNoIndex for LHDR, SEAM, MTRE, unknown ones
};

struct GtnLevelInfo {
  LevelHeader header;  // counts, bounding box of this level; fields and metadata from the file header
  double ratio = 0.0;  // vertices merged away / vertices of level 0
  bool has_merge_tree = false;
  std::vector<GtnChunkInfo> chunks;  // LHDR first, in file order
  uint64_t bytes = 0;                // all chunks of the level
  std::vector<PieceInfo> pieces;     // the piece table (LHDR), in piece order; at least one
  std::vector<size_t> piece_chunk;   // per piece: the index in `chunks` of its chunk (PIEC or GRID)
  // Per piece of kind 0: the byte sizes of its codec streams in its PIEC payload (LHDR).
  std::vector<std::vector<uint64_t>> piece_streams;
  uint8_t base = 0;                         // 1: names level i + 1's vertices (LHDR base, spec 7.7)
  uint64_t pieceBytes(size_t piece) const;  // the piece's chunks, framing included
  // The sum of piece_streams[piece]: its PIEC payload's size, decompressed.
  uint64_t pieceStreamBytes(size_t piece) const;
  // Whether chunk c is a PIEC stored raw (framing and its streams, nothing else), so that each of its
  // streams' bytes is known from LHDR.
  bool pieceStoredRaw(const GtnChunkInfo& c) const;
};

struct GtnFileInfo {
  std::string path;
  uint16_t major = 0, minor = 0;
  uint64_t bytes = 0;  // file size
  GtnFileHeader header;
  bool has_directory = false;
  std::vector<GtnChunkInfo> chunks;  // file-level chunks: GHDR, ancillary chunks outside levels, DIRC, GEND
};

struct GtnSection {
  std::string name;
  uint64_t bytes = 0;
};

// The coded streams of one piece as stored (decompressed), with the header to decode them (the
// level's fields; the piece's counts and bounding box: for a one-piece level, the level's header).
struct GtnLevelStreams {
  LevelHeader header;
  std::vector<uint8_t> boundary, connectivity, geometry;
  std::vector<std::vector<uint8_t>> point_fields, cell_fields;
  LevelPayload payload() const;  // views of the buffers above
};

struct GtnOpenOptions {
  // true: read every chunk front to back at open, checking framing, order and checksums, and reject
  // truncation and trailing bytes. false: with a seekable file that has a valid trailer and directory,
  // read only the prefix, GHDR, trailer, directory and level headers (each chunk still checksummed
  // when read); without them, fall back to the full scan, which then goes past a level's content
  // chunk (SEAM, PIEC, GRID, MTRE, or an ancillary chunk) whose checksum fails: reading that chunk fails.
  bool verify = true;
};

// A chunk whose stored checksum does not match its bytes.
struct GtnDamagedChunk {
  GtnChunkInfo chunk;
  int64_t level = -1;   // the level that holds it; -1 for a file-level chunk
  std::string message;  // names the file, the byte offset, the chunk and its level
};

class GtnReader {
 public:
  // `path` "-" reads standard input (buffered whole, since a pipe cannot seek; the scan itself never
  // seeks backwards). Non-regular files (pipes, devices) are buffered too.
  static StatusOr<std::unique_ptr<GtnReader>> open(const std::string& path, const GtnOpenOptions& options = {});
  // Reads a file already in memory (`name` names it in messages); scans it front to back.
  static StatusOr<std::unique_ptr<GtnReader>> openMemory(std::string bytes, const std::string& name,
                                                         const GtnOpenOptions& options = {});
  ~GtnReader();

  const GtnFileInfo& file() const { return file_; }
  size_t levels() const { return levels_.size(); }
  const GtnLevelInfo& level(size_t i) const { return levels_.at(i); }
  // Whether open() used the directory instead of scanning every chunk.
  bool openedByDirectory() const { return by_directory_; }

  // Decodes level `i` with the codec and streams it to `sink`; checks the stream's counts against the
  // level header. A one-piece level streams from its decoder; a level of several pieces is decoded
  // whole (decodeLevelPieces) and then emitted (emitDecoded). `stats` (optional) receives the
  // decoder's statistics; `fields` (optional) says which fields to decode (level_codec.h).
  // A level that names the next level's vertices (GtnLevelInfo::base) decodes that level first (and so
  // on down the chain) for their values; `base_ids` (optional) then receives, per vertex of level i,
  // its id in level i + 1, or kNoIndex for a vertex level i stores (left empty for other levels).
  Status decodeLevel(size_t i, MeshSink& sink, DecodeStats* stats = nullptr, const DecodeFields* fields = nullptr,
                     std::vector<uint32_t>* base_ids = nullptr);
  // Decodes the pieces `chosen` of level `i` (increasing piece indices; empty: every piece), stitched
  // into one mesh (codec/pieces.h), reading only the level's header, its seam table and the chosen
  // pieces' chunks. `fields` as for decodeLevel.
  StatusOr<DecodedPieces> decodeLevelPieces(size_t i, const std::vector<uint32_t>& chosen,
                                            const DecodeFields* fields = nullptr);
  // Reads (and checksums) the coded streams of piece `piece` of level `i` without decoding them.
  StatusOr<GtnLevelStreams> readPieceStreams(size_t i, size_t piece);
  // readPieceStreams(i, 0) of a one-piece level; a level of several pieces is a usage error.
  StatusOr<GtnLevelStreams> readLevelStreams(size_t i);
  // Reads (and checksums) level `i`'s seam table and class streams (SEAM); an empty table for a
  // one-piece level. `payload` receives the chunk's payload, which the table's stream ranges index.
  StatusOr<GtnSeamTable> readSeamTable(size_t i, std::vector<uint8_t>* payload);
  // The raw merge-tree payload of level `i` (MTRE), or nullopt when the level has none.
  StatusOr<std::optional<std::vector<uint8_t>>> mergeTreePayload(size_t i);

  // Checks the checksum of every chunk the reader knows of (all of them after a full scan; with the
  // directory, those it lists and the header, directory and trailer): one pass of XXH3-64 over the
  // stored bytes, nothing decompressed, memory bounded. Lists the chunks that fail, in file order.
  StatusOr<std::vector<GtnDamagedChunk>> damagedChunks();

  // Bytes per kind of content, summed over the file; the sizes add up to the file size. Names:
  // prefix, header, level_header, seam, boundary, connectivity, geometry, point_field:<name>,
  // cell_field:<name>, merge_tree, directory, trailer, unknown:<type>.
  std::vector<GtnSection> sections() const;

  // Bytes read from the file so far (open included): what a region read costs.
  uint64_t bytesRead() const { return bytes_read_.load(); }

  class Source;

 private:
  GtnReader() = default;
  static StatusOr<std::unique_ptr<GtnReader>> finishOpen(std::unique_ptr<GtnReader> r, bool try_directory);
  Status scan();
  // decodeLevel of one level of one piece, with the seam values of the level it names (null: none).
  Status decodeOnePiece(size_t i, MeshSink& sink, DecodeStats* stats, const DecodeFields* fields,
                        const SeamValues* seams);
  Status openByDirectory();
  StatusOr<std::vector<uint8_t>> readChunk(const GtnChunkInfo& c, ChunkHeader* header = nullptr);
  // The whole chunk at c.offset (framing, stored payload, checksum), its framing checked, not its checksum.
  StatusOr<std::vector<uint8_t>> readChunkBytes(const GtnChunkInfo& c, ChunkHeader* header);
  StatusOr<bool> checksumMatches(const GtnChunkInfo& c);
  Status readSource(uint64_t offset, size_t n, uint8_t* out);
  std::string sectionName(const ChunkTag& tag) const;
  // The section of an unstructured piece's k-th codec stream: boundary, connectivity, geometry,
  // point_field:NAME, cell_field:NAME.
  std::string streamSectionName(size_t k) const;

  std::unique_ptr<Source> source_;
  GtnFileInfo file_;
  std::vector<GtnLevelInfo> levels_;
  bool by_directory_ = false;
  bool tolerant_scan_ = false;           // the scan goes past damaged content chunks (GtnOpenOptions::verify false)
  std::atomic<uint64_t> bytes_read_{0};  // pieces are read in parallel
};

// How every command opens a .gtn file: GtnReader::open, then GtnReader::damagedChunks, with `warn`
// called once per damaged chunk (its message names the file, offset, chunk and level). A command that
// needs a damaged chunk still fails when it reads it; one that does not (level 0 of a file whose merge
// tree or a coarse level is damaged) goes on after the warning.
StatusOr<std::unique_ptr<GtnReader>> openGtnChecked(const std::string& path, const GtnOpenOptions& options,
                                                    const std::function<void(const std::string&)>& warn);

}  // namespace gtn

// <gatun/read.h>: reading .gtn files: their description, any stored level or simplification ratio.
// Part of the Gatun API; <gatun/gatun.h> includes every part and says how errors, ownership and
// threads work for all of them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gatun/mesh.h"
#include "gatun/result.h"

namespace gatun {

/*-************************************
 *  Reading .gtn files
 **************************************/

/*! FieldInfo : a field as a file declares it (no values). */
struct FieldInfo {
  std::string name;
  uint32_t components = 1;
  ScalarType type = ScalarType::kFloat32;
};

/*! PieceInfo : one piece of a stored level. A level is stored as pieces of at most
 *  WriteOptions::piece_tets tetrahedra (`gtn convert --piece-tets`), cut by recursive bisection at
 *  the median, so that consecutive pieces are close in space; points on the seams between pieces are
 *  stored once and belong to every piece that uses them. */
struct PieceInfo {
  uint64_t points = 0;                          /* points the piece uses (its own and seam points) */
  uint64_t tets = 0;                            /* its tetrahedra */
  std::array<double, 3> bbox_min{}, bbox_max{}; /* of the points it uses */
  uint64_t bytes = 0;                           /* its chunks in the file */
};

/*! LevelInfo : one stored level. Level 0 is the lossless mesh; level i > 0 is the mesh after
 *  `merges` merges (edge collapses) of level 0's merge tree, ratio = vertices merged away / vertices
 *  of level 0. */
struct LevelInfo {
  uint64_t points = 0, tets = 0;
  uint64_t merges = 0;
  double ratio = 0.0;
  bool has_merge_tree = false;   /* the level stores a merge tree (simplification on the fly) */
  uint64_t bytes = 0;            /* all chunks of the level in the file */
  std::vector<PieceInfo> pieces; /* the piece table, in piece order (at least one piece) */
};

/*! FileInfo : what a .gtn file's headers and directory say, without decoding anything. */
struct FileInfo {
  std::string path;
  uint16_t major = 0, minor = 0; /* format version */
  uint64_t bytes = 0;            /* file size */
  ScalarType coord_type = ScalarType::kFloat64;
  std::vector<FieldInfo> point_fields, cell_fields;
  std::array<double, 3> bbox_min{}, bbox_max{}; /* of level 0 */
  std::string tool_version, command_line;       /* provenance */
  std::vector<std::pair<std::string, std::string>> metadata;
  std::vector<LevelInfo> levels; /* level 0 first */
};

/*! ReadOptions : what Reader::read() decodes.
 *  With neither `level` nor `ratio`, level 0 (the lossless mesh).
 *  `level`: a stored level as it is stored.
 *  `ratio`: the mesh simplified to this ratio in [0, 1] (vertices merged away / vertices of level 0),
 *     from the finest stored level not beyond it with the remaining merges applied on the fly, as
 *     `gtn export --ratio` does; a ratio beyond what the merge tree allows gives the coarsest mesh.
 *  `fields`: the point and cell fields to decode, by name; empty = all. The others are not decoded
 *     and are absent from the mesh. A name the file lacks is a kUsage error listing the fields.
 *  `pieces`: of a stored level (not with `ratio`), the pieces to decode (indices into
 *     LevelInfo::pieces, any order): their tetrahedra and the points they use, seam points once.
 *  `box` {xmin, ymin, zmin, xmax, ymax, zmax}: only the tetrahedra that meet this closed box, with the
 *     points they use. Of a stored level only the pieces whose bounding boxes meet the box (of those
 *     `pieces` names, if set) are decoded, then filtered; with `ratio` the simplified mesh is decoded
 *     whole, then filtered.
 *  A read with `pieces` or `box` of a stored level is a part read: ReadReport says which pieces it
 *  decoded and the level's numbers of the mesh's points and tetrahedra. */
struct ReadOptions {
  std::optional<size_t> level{};
  std::optional<double> ratio{};
  std::vector<std::string> fields{};
  std::optional<std::vector<uint32_t>> pieces{};
  std::optional<std::array<double, 6>> box{};
};

/*! ReadReport : what a read decoded. */
struct ReadReport {
  size_t level = 0;    /* the stored level decoded */
  uint64_t merges = 0; /* merges of level 0's merge tree the mesh reflects (stored and on the fly) */
  double ratio = 0.0;  /* vertices merged away / vertices of level 0 */
  /* Of a stored level: the pieces decoded (increasing; every piece for a whole read). Empty with a ratio. */
  std::vector<uint32_t> pieces;
  /* Of a part read (ReadOptions::pieces or box, no ratio): the level's numbers of the mesh's points and
   * tetrahedra, i.e. the indices a whole read of the level gives them. Empty otherwise. */
  std::vector<uint32_t> point_ids;
  std::vector<uint64_t> tet_ids;
};

/*! Reader : an open .gtn file.
 *  open() reads the prefix, the file header and, when the file has them, the trailer, directory and
 *  level headers, so that any level is read without touching the others; a file without a directory
 *  (or a stream such as "-", standard input, which is buffered whole) is scanned front to back. Every
 *  chunk read is checked against its checksum.
 *  A Reader owns its open file and releases it when destroyed. It is move-only (a moved-from Reader
 *  may only be destroyed or assigned to); one thread at a time may use it. */
class Reader {
 public:
  /*! open() : opens `path` ("-" = standard input).
   *  Errors: kIo (cannot open or read), kNotOurFile (not a .gtn file; a mesh file that `gtn convert`
   *  reads is a kUsage error saying so), kVersionTooNew, kInvalidData (damage, truncation). */
  static Result<Reader> open(const std::string& path);

  Reader(Reader&& other) noexcept;
  Reader& operator=(Reader&& other) noexcept;
  ~Reader();

  /*! info() : the file's description. The reference is valid as long as the Reader. */
  const FileInfo& info() const;

  /*! read() : decodes the mesh `options` asks for (see ReadOptions). `report` (optional) receives the
   *  level decoded and its merges and ratio. May be called any number of times.
   *  Errors: kUsage (a level the file lacks, a ratio outside [0, 1], both a level and a ratio, a field
   *  the level lacks, a piece the level lacks, pieces with a ratio, a box whose minimum exceeds its
   *  maximum), kInvalidData (a damaged chunk or stream, naming its byte offset), kIo. */
  Result<Mesh> read(const ReadOptions& options = {}, ReadReport* report = nullptr);

 private:
  struct Impl;
  explicit Reader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/*! readInfo() : Reader::open(path) and its info(). */
Result<FileInfo> readInfo(const std::string& path);

/*! read() : Reader::open(path) and one read(options, report). */
Result<Mesh> read(const std::string& path, const ReadOptions& options = {}, ReadReport* report = nullptr);

}  // namespace gatun

// VTK XML import: UnstructuredGrid (.vtu), StructuredGrid (.vts), RectilinearGrid (.vtr), ImageData
// (.vti), and their parallel files (.pvtu, .pvts, .pvtr, .pvti) naming pieces of their own kind.
// ascii, binary (base64) and appended (raw or base64) data arrays, uncompressed or compressed by any
// of VTK's compressors (zlib, LZ4, LZMA), UInt32 or UInt64 headers, either byte order, several pieces.
#include <lz4.h>
#include <lzma.h>
#include <zlib.h>
#include <pugixml.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <sstream>

#include "convert/ascii_rows.h"
#include "convert/cell_split.h"
#include "convert/import.h"
#include "convert/text_reader.h"
#include "convert/vtk_common.h"
#include "format/file_io.h"
#include "mesh/fresh_memory.h"

namespace gtn {

namespace {

// VTK's compressors, each block compressed on its own (vtkZLibDataCompressor, vtkLZ4DataCompressor,
// vtkLZMADataCompressor).
enum class Compressor { kNone, kZlib, kLz4, kLzma };

// How many bytes one compressed byte may become, which bounds what a block may claim before anything
// is allocated: zlib cannot expand a byte into more than 1032, LZ4 into more than 255; an .xz stream
// of a VTK block (32 KiB by default) takes 60 bytes or more, and 2^12 leaves room for larger blocks.
uint64_t maxRatio(Compressor c) {
  switch (c) {
    case Compressor::kLz4: return 256;
    case Compressor::kLzma: return uint64_t{1} << 12;
    default: return 1032;
  }
}
// What an LZMA block's decoder may allocate: the dictionary of xz's strongest preset (64 MiB) and more.
constexpr uint64_t kLzmaMemLimit = uint64_t{128} << 20;

struct Array {
  ScalarType type = ScalarType::kFloat32;
  uint32_t components = 1;
  std::vector<uint8_t> bytes;  // little-endian
};

// A block of a structured grid as one <Piece> holds it: its extent (within the whole, cells of its
// own) and its arrays.
struct StructuredPiece {
  int64_t extent[6];
  uint64_t np = 0, nc = 0;
  Array points;                 // StructuredGrid
  std::vector<double> axis[3];  // RectilinearGrid
  bool axis_f32 = true;
  std::vector<Field> point_fields, cell_fields;
  std::string file, at;  // its file and "Piece i", for messages
  int source = -1;       // k for the file of the k-th piece of a parallel file
};

// ImageData's placement of point (i, j, k): Origin + Direction (i Sx, j Sy, k Sz).
struct ImageGeometry {
  double origin[3] = {0, 0, 0};
  double spacing[3] = {1, 1, 1};
  double dir[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// The directory of `path` with its slash, "./" for a file in the working directory (so that a piece
// named "-" is a file, never standard input).
bool isParallelType(const std::string& type) {
  return type == "PUnstructuredGrid" || type == "PStructuredGrid" || type == "PRectilinearGrid" || type == "PImageData";
}

// An attribute holding a non-negative integer: `absent` when it is missing, -1 when it is not such a
// number ("x", "-3", "1.5": pugixml's own conversion reads "x" as 0).
long long integerAttribute(const pugi::xml_node& node, const char* name, long long absent) {
  const pugi::xml_attribute a = node.attribute(name);
  if (!a) return absent;
  std::string_view text = a.value();
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  int64_t v = 0;
  if (!parseInt(text, &v) || v < 0) return -1;
  return v;
}

// "<Name>" of an element, for messages.
std::string tagOf(const pugi::xml_node& node) {
  std::string tag(1, '<');
  tag.append(node.name());
  tag.push_back('>');
  return tag;
}

// The text of a piece named by a parallel file. A FIFO or a device named there would block or never
// end: only regular files are read (a missing one gets readWholeFile's error).
StatusOr<std::string> readPieceFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !isRegularFile(path))
    return Status(StatusCode::kIo, path + ": not a regular file (a directory, a FIFO or a device)");
  return readWholeFile(path);
}

std::string parentDirectory(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "./" : path.substr(0, slash + 1);
}

// The ghost marks are VTK's bookkeeping, not data: a mesh made of several pieces does not keep them.
void dropGhostArrays(TetMesh& mesh) {
  for (std::vector<Field>* fields : {&mesh.point_fields, &mesh.cell_fields})
    fields->erase(
        std::remove_if(fields->begin(), fields->end(), [](const Field& f) { return f.name == kVtkGhostArray; }),
        fields->end());
}

// In a piece of several, the points marked as copies of another piece's (vtkGhostType
// DUPLICATEPOINT) that no tetrahedron left uses: the ghost cells' own points, which went with them.
// Removed, with their values; returns how many.
size_t dropGhostOnlyPoints(TetMesh& mesh) {
  const size_t n = mesh.numPoints();
  const uint8_t* marks = vtkGhostMarks(mesh.point_fields, n);
  if (!marks) return 0;
  std::vector<uint8_t> used(n, 0);
  for (const Tet& t : mesh.tets)
    for (uint32_t v : t) used[v] = 1;
  std::vector<uint8_t> keep(n);
  for (size_t p = 0; p < n; ++p) keep[p] = used[p] || !(marks[p] & kVtkDuplicatePoint);
  if (std::find(keep.begin(), keep.end(), 0) == keep.end()) return 0;
  const std::vector<uint32_t> new_index = keepPoints(mesh, keep);
  for (Tet& t : mesh.tets)
    for (uint32_t& v : t) v = new_index[v];
  return n - mesh.numPoints();
}

// What reading several unstructured pieces into one mesh did (a .pvtu's files, or the <Piece>s of one
// .vtu): the ghost copies of other pieces' cells went, the points the pieces share stayed apart.
void reportPieces(size_t pieces, size_t ghost_tets, size_t ghost_points, bool weld, ImportReport* report) {
  if (ghost_tets > 0)
    report->warnings.push_back(std::to_string(ghost_tets) +
                               " tetrahedra of ghost cells (vtkGhostType duplicates of other pieces' cells) dropped");
  if (ghost_points > 0)
    report->warnings.push_back(
        std::to_string(ghost_points) +
        " points of ghost cells alone (vtkGhostType duplicates of other pieces' points) dropped");
  if (pieces > 1 && !weld)
    report->warnings.push_back(std::to_string(pieces) +
                               " pieces read; the points they share are kept once per piece (--weld merges them)");
}

class VtuReader {
 public:
  VtuReader(const std::string& path, const std::string& text) : path_(path), text_(text) {}
  StatusOr<ImportResult> read(const ImportOptions& options);
  // read() once parse() has given the <VTKFile> element.
  StatusOr<ImportResult> readParsed(const pugi::xml_node& root, const ImportOptions& options);

 private:
  // "file: Piece i", or "parallel file: piece k: file: Piece i".
  std::string pieceName(const StructuredPiece& p) const {
    if (p.source < 0) return path_ + ": " + p.at;
    return path_ + ": piece " + std::to_string(p.source) + ": " + p.file + ": " + p.at;
  }
  Status fail(const std::string& where, const std::string& reason) const {
    return invalidData(path_ + ": " + where + ": " + reason);
  }
  // Reads one DataArray of `tuples` tuples into *out; `where` names it in messages. With `at_least`
  // the array may hold more tuples, which are kept (for arrays whose length the file does not state).
  Status readArray(const pugi::xml_node& node, uint64_t tuples, const std::string& where, Array* out,
                   bool at_least = false);
  // A DataArray of integers (one component) as int64 values: exactly `count`, or with `at_least` at
  // least that many.
  Status readIndices(const pugi::xml_node& node, uint64_t count, const std::string& where, std::vector<int64_t>* out,
                     bool at_least = false);
  // Polyhedra in VTK 9.4's layout, made into the face streams of the earlier layout (VtkCells).
  Status readPolyhedronTables(const pugi::xml_node* nodes, const std::vector<int64_t>& types, int64_t np,
                              size_t point_base, size_t cell_base, const std::string& at);
  Status decodeBinary(std::string_view b64, const std::string& where, std::vector<uint8_t>* out);
  Status decodeRaw(size_t offset, const std::string& where, std::vector<uint8_t>* out);
  uint64_t headerValue(const uint8_t* p) const;
  Status inflateBlocks(const uint8_t* header, const uint8_t* blocks, size_t available, const std::string& where,
                       std::vector<uint8_t>* out) const;
  // One compressed block of the file's compressor: exactly out_size bytes from in_size.
  Status inflateBlock(const uint8_t* in, uint64_t in_size, uint8_t* out, uint64_t out_size, const std::string& where,
                      uint64_t index) const;
  StatusOr<size_t> compressedHeaderBytes(const uint8_t* first3, const std::string& where) const;
  Status readPiece(const pugi::xml_node& piece, size_t index);
  // A parallel file (.pvtu): its pieces' .vtu files, read one after the other into one mesh.
  StatusOr<ImportResult> readParallel(const pugi::xml_node& root, const ImportOptions& options);
  // The structured files: StructuredGrid (.vts), RectilinearGrid (.vtr), ImageData (.vti), of pieces
  // that together cover the whole extent.
  StatusOr<ImportResult> readStructured(const pugi::xml_node& root, const std::string& type,
                                        const ImportOptions& options);
  // A parallel structured file (.pvts, .pvtr, .pvti): the pieces of its files as one structured grid.
  StatusOr<ImportResult> readParallelStructured(const pugi::xml_node& root, const std::string& type,
                                                const ImportOptions& options);
  // The WholeExtent of `grid` and its point counts; `file_bytes` bounds the points that no array holds.
  Status structuredWhole(const pugi::xml_node& grid, const std::string& type, uint64_t file_bytes, bool one_file,
                         int64_t whole[6], uint64_t dims[3]) const;
  // The <Piece> elements of `grid`, each within `whole`, appended to *pieces.
  Status readStructuredPieces(const pugi::xml_node& grid, const std::string& type, const int64_t whole[6],
                              std::vector<StructuredPiece>* pieces);
  // The pieces placed in the whole extent (`grid` gives ImageData's Origin, Spacing and Direction),
  // checked to carry the same arrays and to cover every point and cell, then split into tetrahedra.
  StatusOr<ImportResult> assembleStructured(const pugi::xml_node& grid, const std::string& type, const int64_t whole[6],
                                            const uint64_t dims[3], const std::vector<StructuredPiece>& pieces,
                                            const ImageGeometry& image, const ImportOptions& options);
  // ImageData's Origin, Spacing and Direction where `grid` gives them (others are left as they are).
  Status imageGeometry(const pugi::xml_node& grid, ImageGeometry* image) const;
  // Parses the file's XML (kept in doc_) and its byte order, header type, compressor and appended
  // data; returns the <VTKFile> element.
  StatusOr<pugi::xml_node> parse();
  // A piece's PointData or CellData arrays of `items` tuples each, in file order, appended to *fields.
  Status readSection(const pugi::xml_node& piece, const char* section, uint64_t items, const std::string& at,
                     std::vector<Field>* fields);

  const std::string& path_;
  const std::string& text_;
  bool big_endian_ = false;
  int header_bytes_ = 4;
  bool compressed_ = false;
  bool in_parallel_ = false;              // a piece of a .pvtu, which must not be one itself
  size_t duplicate_tets_ = 0;             // tetrahedra of a piece's ghost cells (copies of other pieces'), dropped
  std::set<std::string> skipped_arrays_;  // "PointData/name" of the non-numeric arrays warned about
  Compressor compressor_ = Compressor::kNone;
  bool appended_base64_ = false;
  size_t appended_begin_ = 0, appended_end_ = 0;  // bytes after '_' in the file
  std::string xml_;                               // the XML text doc_ was parsed from, in place (it must outlive doc_)
  pugi::xml_document doc_;
  ImportResult result_;
  VtkCells cells_;
  std::vector<Field> cell_fields_;
  bool coords_float64_ = false;
  uint64_t expected_bytes_ = 0;  // of the array being decoded
  bool at_least_ = false;        // expected_bytes_ is only the fewest the array may hold
};

uint64_t VtuReader::headerValue(const uint8_t* p) const {
  uint64_t v = 0;
  for (int i = 0; i < header_bytes_; ++i) {
    const int shift = big_endian_ ? 8 * (header_bytes_ - 1 - i) : 8 * i;
    v |= uint64_t{p[i]} << shift;
  }
  return v;
}

StatusOr<size_t> VtuReader::compressedHeaderBytes(const uint8_t* first3, const std::string& where) const {
  const uint64_t blocks = headerValue(first3);
  if (blocks > text_.size()) return fail(where, "compression header claims " + std::to_string(blocks) + " blocks");
  return static_cast<size_t>((3 + blocks) * header_bytes_);
}

Status VtuReader::inflateBlock(const uint8_t* in, uint64_t in_size, uint8_t* out, uint64_t out_size,
                               const std::string& where, uint64_t index) const {
  auto corrupt = [&](const char* codec, const std::string& why) {
    return fail(where, std::string(codec) + " block " + std::to_string(index) + " is corrupt (" + why + ")");
  };
  auto sizes = [&](uint64_t got) {
    return "inflates to " + std::to_string(got) + " bytes, header says " + std::to_string(out_size);
  };
  switch (compressor_) {
    case Compressor::kLz4: {
      if (in_size > INT32_MAX || out_size > INT32_MAX) return corrupt("LZ4", "larger than LZ4 blocks can be");
      const int got = LZ4_decompress_safe(reinterpret_cast<const char*>(in), reinterpret_cast<char*>(out),
                                          static_cast<int>(in_size), static_cast<int>(out_size));
      if (got < 0) return corrupt("LZ4", "not a valid LZ4 block of at most " + std::to_string(out_size) + " bytes");
      if (static_cast<uint64_t>(got) != out_size) return corrupt("LZ4", sizes(static_cast<uint64_t>(got)));
      return Status::ok();
    }
    case Compressor::kLzma: {
      uint64_t memlimit = kLzmaMemLimit;
      size_t in_pos = 0, out_pos = 0;
      const lzma_ret rc =
          lzma_stream_buffer_decode(&memlimit, 0, nullptr, in, &in_pos, in_size, out, &out_pos, out_size);
      if (rc == LZMA_MEMLIMIT_ERROR)
        return corrupt("LZMA", "its decoder would need more than " + std::to_string(kLzmaMemLimit >> 20) + " MiB");
      if (rc == LZMA_BUF_ERROR)
        return corrupt(
            "LZMA", "it holds more than the " + std::to_string(out_size) + " bytes its header says, or is cut short");
      if (rc != LZMA_OK) return corrupt("LZMA", "liblzma error " + std::to_string(static_cast<int>(rc)));
      if (out_pos != out_size) return corrupt("LZMA", sizes(out_pos));
      return Status::ok();
    }
    default: {
      uLongf got = static_cast<uLongf>(out_size);
      const int rc = uncompress(out, &got, in, static_cast<uLong>(in_size));
      if (rc != Z_OK) return corrupt("zlib", zError(rc));
      if (got != out_size) return corrupt("zlib", sizes(got));
      return Status::ok();
    }
  }
}

Status VtuReader::inflateBlocks(const uint8_t* header, const uint8_t* blocks, size_t available,
                                const std::string& where, std::vector<uint8_t>* out) const {
  const uint64_t num_blocks = headerValue(header);
  const uint64_t block_size = headerValue(header + header_bytes_);
  const uint64_t last_size = headerValue(header + 2 * header_bytes_);
  uint64_t compressed_total = 0, total = 0;
  for (uint64_t b = 0; b < num_blocks; ++b) {
    const uint64_t c = headerValue(header + (3 + b) * header_bytes_);
    const uint64_t u = (b + 1 == num_blocks && last_size != 0) ? last_size : block_size;
    if (c > available || compressed_total > available - c)
      return fail(where, "compressed block " + std::to_string(b) + " runs past the end of the data (" +
                             std::to_string(available) + " bytes)");
    if (u > maxRatio(compressor_) * c + 64)
      return fail(where, "compressed block " + std::to_string(b) + " claims " + std::to_string(u) + " bytes from " +
                             std::to_string(c));
    compressed_total += c;
    total += u;
  }
  // Checked before allocating: a header cannot make us reserve more than the array needs.
  if (total < expected_bytes_ || (!at_least_ && total != expected_bytes_))
    return fail(where, "compressed blocks hold " + std::to_string(total) + " bytes, expected " +
                           (at_least_ ? "at least " : "") + std::to_string(expected_bytes_));
  resizePopulated(*out, total);
  uint64_t in_pos = 0, out_pos = 0;
  for (uint64_t b = 0; b < num_blocks; ++b) {
    const uint64_t c = headerValue(header + (3 + b) * header_bytes_);
    const uint64_t u = (b + 1 == num_blocks && last_size != 0) ? last_size : block_size;
    GTN_RETURN_IF_ERROR(inflateBlock(blocks + in_pos, c, out->data() + out_pos, u, where, b));
    in_pos += c;
    out_pos += u;
  }
  return Status::ok();
}

Status VtuReader::decodeBinary(std::string_view b64, const std::string& where, std::vector<uint8_t>* out) {
  // The header and the data may be base64-encoded apart (VTK) or together (some writers). Apart, the
  // header's last quartet ends in '=' whenever its size is not a multiple of 3; when it is a multiple
  // of 3 both encodings are the same text. The text may run on into the next appended array, so only
  // the quartets this array needs are decoded.
  auto decode = [&](std::string_view s, std::vector<uint8_t>* into, const char* what) -> Status {
    if (!base64Decode(s, into)) return fail(where, std::string("bad base64 in the ") + what);
    return Status::ok();
  };
  auto quartets = [](uint64_t bytes) { return (bytes + 2) / 3 * 4; };
  std::vector<uint8_t> head;
  const size_t first = compressed_ ? 3 * static_cast<size_t>(header_bytes_) : header_bytes_;
  if (b64.size() < quartets(first)) return fail(where, "base64 data ends inside the header");
  GTN_RETURN_IF_ERROR(decode(b64.substr(0, quartets(first)), &head, "header"));
  size_t header_size = header_bytes_;
  if (compressed_) {
    GTN_ASSIGN_OR_RETURN(header_size, compressedHeaderBytes(head.data(), where));
    if (b64.size() < quartets(header_size)) return fail(where, "base64 data ends inside the compression header");
    GTN_RETURN_IF_ERROR(decode(b64.substr(0, quartets(header_size)), &head, "header"));
  }
  if (head.size() < header_size) return fail(where, "base64 data ends inside the header");
  head.resize(header_size);
  uint64_t data_size = 0;
  if (compressed_) {
    const uint64_t blocks = headerValue(head.data());
    for (uint64_t b = 0; b < blocks; ++b) {
      const uint64_t c = headerValue(head.data() + (3 + b) * header_bytes_);
      if (c > b64.size()) return fail(where, "compressed block " + std::to_string(b) + " is longer than the data");
      data_size += c;
    }
  } else {
    data_size = headerValue(head.data());
  }
  // Apart, the header's last quartet ends in as many '=' as its size leaves over (two after a UInt32
  // header, one after a UInt64 one); together, the data's first bytes fill some of those places (a
  // header and 1 or 2 bytes of data can end in one '=', or none, at the same place).
  const size_t header_chars = quartets(header_size);
  const size_t header_pads = (3 - header_size % 3) % 3;
  size_t pads = 0;
  while (pads < 2 && b64[header_chars - 1 - pads] == '=') ++pads;
  const bool apart = header_pads != 0 && pads == header_pads;
  const uint64_t need = apart ? header_chars + quartets(data_size) : quartets(header_size + data_size);
  if (data_size > b64.size() || need > b64.size())
    return fail(where, "base64 data is cut short: the header announces " + std::to_string(data_size) +
                           " bytes, which need " + std::to_string(need) + " characters, but only " +
                           std::to_string(b64.size()) + " are there");
  std::vector<uint8_t> data;
  if (apart) {
    GTN_RETURN_IF_ERROR(decode(b64.substr(header_chars, quartets(data_size)), &data, "data"));
  } else {
    GTN_RETURN_IF_ERROR(decode(b64.substr(0, need), &data, "data"));
    data.erase(data.begin(), data.begin() + header_size);
  }
  if (data.size() < data_size) return fail(where, "base64 data is shorter than its header says");
  data.resize(data_size);
  if (compressed_) return inflateBlocks(head.data(), data.data(), data.size(), where, out);
  *out = std::move(data);
  return Status::ok();
}

Status VtuReader::decodeRaw(size_t offset, const std::string& where, std::vector<uint8_t>* out) {
  const size_t size = appended_end_ - appended_begin_;
  if (offset > size || size - offset < static_cast<size_t>(header_bytes_))
    return fail(where, "appended data offset " + std::to_string(offset) + " is past the end of the " +
                           std::to_string(size) + " bytes of appended data");
  const uint8_t* p = reinterpret_cast<const uint8_t*>(text_.data()) + appended_begin_ + offset;
  size_t left = size - offset;
  if (compressed_) {
    if (left < 3 * static_cast<size_t>(header_bytes_)) return fail(where, "appended data ends inside the header");
    GTN_ASSIGN_OR_RETURN(size_t header_size, compressedHeaderBytes(p, where));
    if (left < header_size) return fail(where, "appended data ends inside the compression header");
    return inflateBlocks(p, p + header_size, left - header_size, where, out);
  }
  const uint64_t n = headerValue(p);
  left -= header_bytes_;
  if (n > left)
    return fail(where, "byte offset " + std::to_string(appended_begin_ + offset) + ": header says " +
                           std::to_string(n) + " bytes but only " + std::to_string(left) + " remain in the file");
  reservePopulated(*out, n);
  out->assign(p + header_bytes_, p + header_bytes_ + n);
  return Status::ok();
}

Status VtuReader::readArray(const pugi::xml_node& node, uint64_t tuples, const std::string& where, Array* out,
                            bool at_least) {
  const std::string type_name = node.attribute("type").as_string();
  // vtkBitArray: one 0/1 value per token in ASCII, packed eight to a byte (first value in the high
  // bit) in binary; read as UInt8.
  const bool bits = type_name == "Bit" && !at_least;
  if (bits) {
    out->type = ScalarType::kUInt8;
  } else if (!vtkXmlTypeFromName(type_name, &out->type)) {
    return Status(StatusCode::kUnsupported, path_ + ": " + where + ": data type '" + type_name + "' is not supported");
  }
  const int comps =
      static_cast<int>(std::clamp<long long>(integerAttribute(node, "NumberOfComponents", 1), -1, 1 << 20));
  if (comps < 1 || comps > 4096) return fail(where, "bad NumberOfComponents " + std::to_string(comps));
  out->components = static_cast<uint32_t>(comps);
  const size_t size = scalarSize(out->type);
  const std::string format = node.attribute("format").as_string("ascii");
  if (tuples > UINT64_MAX / comps / size) return fail(where, "too many values");
  const uint64_t count = tuples * comps;
  expected_bytes_ = bits ? (count + 7) / 8 : count * size;
  at_least_ = at_least;
  if (format == "ascii") {
    const std::string_view body = node.text().get();
    if (count > body.size() / 2 + 1)
      return fail(where, "holds fewer than the " + std::to_string(count) + " values expected");
    TextReader tr(path_, body, '\0');
    out->bytes.resize(count * size);
    std::string_view t;
    uint64_t i = 0;
    for (; i < count || at_least; ++i) {
      if (!tr.next(&t)) {
        if (i >= count) break;
        return fail(where, "has " + std::to_string(i) + " values, expected " + std::to_string(count));
      }
      if (i >= count) out->bytes.resize((i + 1) * size);  // at_least: bounded by the text's length
      if (!parseScalarToken(t, out->type, out->bytes.data() + i * size) || (bits && out->bytes[i] > 1))
        return fail(where, "value " + std::to_string(i) + " " + quotedToken(t) + " is not a " +
                               (bits ? "bit (0 or 1)" : scalarTypeName(out->type)));
    }
    if (at_least && i % comps != 0)
      return fail(where, "has " + std::to_string(i) + " values, not a whole number of " + std::to_string(comps) +
                             "-component tuples");
    if (!at_least && tr.next(&t)) return fail(where, "has more than the " + std::to_string(count) + " values expected");
    return Status::ok();  // text is already in host (little-endian) order
  }
  if (format == "binary") {
    std::string b64;
    reservePopulated(b64, std::strlen(node.text().get()));
    for (const char* c = node.text().get(); *c; ++c)
      if (!std::isspace(static_cast<unsigned char>(*c))) b64 += *c;
    GTN_RETURN_IF_ERROR(decodeBinary(b64, where, &out->bytes));
  } else if (format == "appended") {
    if (appended_end_ == 0) return fail(where, "format=\"appended\" but the file has no <AppendedData>");
    const long long offset = integerAttribute(node, "offset", -1);
    if (offset < 0) return fail(where, "appended array without a valid offset");
    if (appended_base64_) {
      const std::string_view region(text_.data() + appended_begin_, appended_end_ - appended_begin_);
      if (static_cast<size_t>(offset) > region.size()) return fail(where, "appended data offset is past the end");
      // Base64 runs until whitespace or the next array; every array starts on a quartet boundary.
      std::string_view rest = region.substr(static_cast<size_t>(offset));
      size_t end = 0;
      while (end < rest.size() && !std::isspace(static_cast<unsigned char>(rest[end])) && rest[end] != '<') ++end;
      rest = rest.substr(0, end);
      GTN_RETURN_IF_ERROR(decodeBinary(rest, where, &out->bytes));
    } else {
      GTN_RETURN_IF_ERROR(decodeRaw(static_cast<size_t>(offset), where, &out->bytes));
    }
  } else {
    return fail(where, "unknown format '" + format + "'");
  }
  if (bits) {
    if (out->bytes.size() != expected_bytes_)
      return fail(where, "holds " + std::to_string(out->bytes.size()) + " bytes, expected " +
                             std::to_string(expected_bytes_) + " (" + std::to_string(count) + " bits)");
    std::vector<uint8_t> packed;
    packed.swap(out->bytes);
    out->bytes.resize(count);
    for (uint64_t i = 0; i < count; ++i) out->bytes[i] = (packed[i / 8] >> (7 - i % 8)) & 1;
    return Status::ok();
  }
  if (at_least && out->bytes.size() >= count * size && out->bytes.size() % (comps * size) == 0) {
    // as many tuples as it holds
  } else if (out->bytes.size() != count * size) {
    return fail(where, "holds " + std::to_string(out->bytes.size()) + " bytes, expected " +
                           (at_least ? "at least " : "") + std::to_string(count * size) + " (" +
                           std::to_string(tuples) + " tuples of " + std::to_string(comps) + " " +
                           vtkXmlTypeName(out->type) + ")");
  }
  if (big_endian_) swapByteOrder(out->bytes.data(), out->bytes.size(), size);
  return Status::ok();
}

Status VtuReader::readPiece(const pugi::xml_node& piece, size_t index) {
  const std::string at = "Piece " + std::to_string(index);
  const long long np = integerAttribute(piece, "NumberOfPoints", -1);
  const long long nc = integerAttribute(piece, "NumberOfCells", -1);
  if (np < 0 || nc < 0) return fail(at, "missing or bad NumberOfPoints/NumberOfCells");
  const size_t point_base = result_.mesh.numPoints();
  const size_t cell_base = cells_.types.size();

  const pugi::xml_node points = piece.child("Points").child("DataArray");
  Array pts;
  if (np > 0) {
    if (!points) return fail(at, "no <Points> DataArray");
    GTN_RETURN_IF_ERROR(readArray(points, static_cast<uint64_t>(np), at + " Points", &pts));
    if (pts.components != 3) return fail(at + " Points", "NumberOfComponents is not 3");
  }
  std::vector<double> xyz;
  scalarsToDouble(pts.type, pts.bytes.data(), pts.bytes.size() / scalarSize(pts.type), &xyz);
  if (np > 0 && pts.type != ScalarType::kFloat32) coords_float64_ = true;
  result_.mesh.coords.insert(result_.mesh.coords.end(), xyz.begin(), xyz.end());

  const pugi::xml_node cells = piece.child("Cells");
  Array conn, offs, types;
  pugi::xml_node conn_node, offs_node, types_node, faces_node, face_offs_node;
  // VTK 9.4's polyhedron tables: polyhedron_offsets, polyhedron_to_faces, face_offsets, face_connectivity.
  pugi::xml_node table_nodes[4];
  for (pugi::xml_node a : cells.children("DataArray")) {
    const std::string name = a.attribute("Name").as_string();
    if (name == "connectivity") conn_node = a;
    else if (name == "offsets") offs_node = a;
    else if (name == "types") types_node = a;
    else if (name == "faces") faces_node = a;
    else if (name == "faceoffsets") face_offs_node = a;
    else if (name == "polyhedron_offsets") table_nodes[0] = a;
    else if (name == "polyhedron_to_faces") table_nodes[1] = a;
    else if (name == "face_offsets") table_nodes[2] = a;
    else if (name == "face_connectivity") table_nodes[3] = a;
  }
  const bool tables = table_nodes[0] || table_nodes[1] || table_nodes[2] || table_nodes[3];
  if (nc > 0 && (!offs_node || !types_node || !conn_node))
    return fail(at, "<Cells> lacks one of the connectivity, offsets and types arrays");
  std::vector<int64_t> offsets, connectivity, type_values;
  size_t bad = 0;
  if (nc > 0) {
    GTN_RETURN_IF_ERROR(readArray(offs_node, static_cast<uint64_t>(nc), at + " Cells offsets", &offs));
    if (!scalarsToInt64(offs.type, offs.bytes.data(), static_cast<size_t>(nc), &offsets, &bad))
      return fail(at + " Cells offsets", "value " + std::to_string(bad) + " is not an index");
    GTN_RETURN_IF_ERROR(readArray(types_node, static_cast<uint64_t>(nc), at + " Cells types", &types));
    if (!scalarsToInt64(types.type, types.bytes.data(), static_cast<size_t>(nc), &type_values, &bad))
      return fail(at + " Cells types", "value " + std::to_string(bad) + " is not a cell type");
    for (size_t c = 1; c < offsets.size(); ++c)
      if (offsets[c] < offsets[c - 1]) return fail(at + " Cells offsets", "decrease at cell " + std::to_string(c));
    if (offsets.front() < 0) return fail(at + " Cells offsets", "negative offset");
    // The connectivity length is the last offset; it must be backed by the file (checked by readArray).
    GTN_RETURN_IF_ERROR(readArray(conn_node, static_cast<uint64_t>(offsets.back()), at + " Cells connectivity", &conn));
    if (!scalarsToInt64(conn.type, conn.bytes.data(), static_cast<size_t>(offsets.back()), &connectivity, &bad))
      return fail(at + " Cells connectivity", "value " + std::to_string(bad) + " is not an index");
  }
  const int64_t conn_base = static_cast<int64_t>(cells_.connectivity.size());
  // Room for this piece's cells, mapped at once (and doubled, so that many pieces copy little).
  auto room = [](auto& v, size_t adding) {
    if (v.size() + adding > v.capacity()) reservePopulated(v, std::max(v.size() + adding, 2 * v.capacity()));
  };
  room(cells_.types, type_values.size());
  room(cells_.offsets, type_values.size());
  room(cells_.connectivity, connectivity.size());
  for (size_t c = 0; c < type_values.size(); ++c) {
    if (type_values[c] < 0 || type_values[c] > 255)
      return fail(at + " Cells types", "cell " + std::to_string(c) + " has type " + std::to_string(type_values[c]));
    cells_.types.push_back(static_cast<int32_t>(type_values[c]));
    cells_.offsets.push_back(conn_base + offsets[c]);
  }
  for (int64_t v : connectivity) {
    // Indices are local to the piece; out-of-range ones stay out of range after the shift.
    if (v < 0 || v >= np)
      return fail(at + " Cells connectivity",
                  "refers to point " + std::to_string(v) + " but the piece has " + std::to_string(np) + " points");
    cells_.connectivity.push_back(v + static_cast<int64_t>(point_base));
  }

  if (!face_offs_node && !tables &&
      std::find(type_values.begin(), type_values.end(), int64_t{kVtkPolyhedron}) != type_values.end())
    return fail(at + " Cells",
                "VTK_POLYHEDRON cells without the faces and faceoffsets arrays (or VTK 9.4's "
                "polyhedron_offsets, polyhedron_to_faces, face_offsets and face_connectivity) that "
                "describe them");
  if (tables && (faces_node || face_offs_node))
    return fail(at + " Cells", "both polyhedron layouts (faces/faceoffsets and VTK 9.4's tables)");
  if (nc > 0 && tables) {
    GTN_RETURN_IF_ERROR(readPolyhedronTables(table_nodes, type_values, np, point_base, cell_base, at));
  } else if (nc > 0 && (faces_node || face_offs_node)) {
    // Polyhedra: their face streams, with point indices and offsets made global like the cells'.
    if (!faces_node || !face_offs_node) return fail(at, "<Cells> has one of faces and faceoffsets without the other");
    Array fo, fs;
    std::vector<int64_t> face_offsets, faces;
    GTN_RETURN_IF_ERROR(readArray(face_offs_node, static_cast<uint64_t>(nc), at + " Cells faceoffsets", &fo));
    if (!scalarsToInt64(fo.type, fo.bytes.data(), static_cast<size_t>(nc), &face_offsets, &bad))
      return fail(at + " Cells faceoffsets", "value " + std::to_string(bad) + " is not an offset");
    const int64_t num_faces = *std::max_element(face_offsets.begin(), face_offsets.end());
    if (num_faces > 0) {
      GTN_RETURN_IF_ERROR(readArray(faces_node, static_cast<uint64_t>(num_faces), at + " Cells faces", &fs));
      if (!scalarsToInt64(fs.type, fs.bytes.data(), static_cast<size_t>(num_faces), &faces, &bad))
        return fail(at + " Cells faces", "value " + std::to_string(bad) + " is not an index");
    }
    // Earlier pieces without polyhedra get their -1 offsets now.
    cells_.face_offsets.resize(cell_base, -1);
    const int64_t face_base = static_cast<int64_t>(cells_.faces.size());
    for (int64_t o : face_offsets) cells_.face_offsets.push_back(o < 0 ? -1 : o + face_base);
    // Within each polyhedron's stream: the face count, then per face its point count and its points,
    // which become global. A stream that does not parse is copied as it is: splitVtkCells rejects it.
    size_t begin = 0;
    for (int64_t end : face_offsets) {
      if (end < 0) continue;
      const size_t stop = std::min(static_cast<size_t>(end), faces.size());
      size_t e = begin;
      if (e < stop) {
        cells_.faces.push_back(faces[e]);
        for (int64_t k = faces[e++]; k > 0 && e < stop; --k) {
          const int64_t n = faces[e];
          cells_.faces.push_back(faces[e++]);
          for (int64_t i = 0; i < n && e < stop; ++i, ++e)
            cells_.faces.push_back(faces[e] + static_cast<int64_t>(point_base));
        }
      }
      for (; e < stop; ++e) cells_.faces.push_back(faces[e]);
      begin = std::max(begin, stop);
    }
  } else if (!cells_.face_offsets.empty()) {
    cells_.face_offsets.resize(cells_.types.size(), -1);
  }

  // Point and cell data: kept in file order, matched by name across pieces.
  auto readData = [&](const char* section, uint64_t items, std::vector<Field>& fields, size_t items_before) -> Status {
    std::vector<Field> arrays;
    GTN_RETURN_IF_ERROR(readSection(piece, section, items, at, &arrays));
    // An empty piece's arrays hold nothing (VTK's writer names them as it likes, e.g. ImageScalars
    // for RTData): they are not matched. The first piece with items sets the arrays.
    if (items == 0 && index > 0) return Status::ok();
    if (index == 0 || items_before == 0) {
      fields = std::move(arrays);
      return Status::ok();
    }
    for (size_t k = 0; k < arrays.size(); ++k) {
      const Field& a = arrays[k];
      if (k >= fields.size() || fields[k].name != a.name || fields[k].type != a.type ||
          fields[k].components != a.components || fields[k].itemCount() != items_before)
        return fail(at + " " + section + " '" + a.name + "'",
                    "does not match the arrays of Piece 0 (pieces must carry the same arrays)");
      fields[k].bytes.insert(fields[k].bytes.end(), a.bytes.begin(), a.bytes.end());
    }
    if (arrays.size() != fields.size()) return fail(at + " " + section, "does not carry the same arrays as Piece 0");
    return Status::ok();
  };
  GTN_RETURN_IF_ERROR(readData("PointData", static_cast<uint64_t>(np), result_.mesh.point_fields, point_base));
  GTN_RETURN_IF_ERROR(readData("CellData", static_cast<uint64_t>(nc), cell_fields_, cell_base));
  return Status::ok();
}

Status VtuReader::readIndices(const pugi::xml_node& node, uint64_t count, const std::string& where,
                              std::vector<int64_t>* out, bool at_least) {
  Array a;
  GTN_RETURN_IF_ERROR(readArray(node, count, where, &a, at_least));
  if (a.components != 1) return fail(where, "NumberOfComponents is not 1");
  size_t bad = 0;
  if (!scalarsToInt64(a.type, a.bytes.data(), a.bytes.size() / scalarSize(a.type), out, &bad))
    return fail(where, "value " + std::to_string(bad) + " is not an index");
  return Status::ok();
}

// VTK 9.4 keeps a polyhedron's faces in two tables: polyhedron_offsets (per cell, the end of its run in
// polyhedron_to_faces; other cells have empty runs) and polyhedron_to_faces (face numbers), then
// face_offsets (per face, the end of its points in face_connectivity) and face_connectivity. Both
// offset arrays leave out the leading 0, as the cells' offsets do. Neighbouring polyhedra may share a
// face. The tables become the stream of the earlier layout: per polyhedron its face count, then per
// face its point count and its points, made global.
Status VtuReader::readPolyhedronTables(const pugi::xml_node* nodes, const std::vector<int64_t>& types, int64_t np,
                                       size_t point_base, size_t cell_base, const std::string& at) {
  static const char* const kNames[4] = {"polyhedron_offsets", "polyhedron_to_faces", "face_offsets",
                                        "face_connectivity"};
  for (int k = 0; k < 4; ++k)
    if (!nodes[k]) return fail(at + " Cells", std::string("VTK 9.4's polyhedron tables lack ") + kNames[k]);
  const std::string where[4] = {at + " Cells polyhedron_offsets", at + " Cells polyhedron_to_faces",
                                at + " Cells face_offsets", at + " Cells face_connectivity"};
  auto checkEnds = [&](const std::vector<int64_t>& ends, size_t count, const std::string& w) -> Status {
    for (size_t i = 0; i < count; ++i)
      if (ends[i] < (i == 0 ? 0 : ends[i - 1]))
        return fail(w, i == 0 ? "negative offset" : "decrease at entry " + std::to_string(i));
    return Status::ok();
  };
  const size_t nc = types.size();
  std::vector<int64_t> poly_ends, poly_faces, face_ends, face_points;
  GTN_RETURN_IF_ERROR(readIndices(nodes[0], nc, where[0], &poly_ends));
  GTN_RETURN_IF_ERROR(checkEnds(poly_ends, nc, where[0]));
  const uint64_t refs = nc == 0 ? 0 : static_cast<uint64_t>(poly_ends.back());
  if (refs > 0) GTN_RETURN_IF_ERROR(readIndices(nodes[1], refs, where[1], &poly_faces));
  int64_t num_faces = 0;
  for (size_t i = 0; i < poly_faces.size(); ++i) {
    if (poly_faces[i] < 0 || poly_faces[i] >= INT32_MAX)
      return fail(where[1], "entry " + std::to_string(i) + " names face " + std::to_string(poly_faces[i]));
    num_faces = std::max(num_faces, poly_faces[i] + 1);
  }
  // The face tables may hold faces no polyhedron names; they are read, not used.
  if (num_faces > 0) {
    GTN_RETURN_IF_ERROR(readIndices(nodes[2], static_cast<uint64_t>(num_faces), where[2], &face_ends, true));
    GTN_RETURN_IF_ERROR(checkEnds(face_ends, static_cast<size_t>(num_faces), where[2]));
    GTN_RETURN_IF_ERROR(
        readIndices(nodes[3], static_cast<uint64_t>(face_ends[num_faces - 1]), where[3], &face_points, true));
  }
  // A face bounds two cells at most: so the streams cannot grow much longer than the tables.
  std::vector<uint8_t> uses(static_cast<size_t>(num_faces), 0);
  uint64_t stream = 0;
  for (size_t c = 0; c < nc; ++c) {
    const int64_t begin = c == 0 ? 0 : poly_ends[c - 1];
    if (types[c] != kVtkPolyhedron) {
      if (poly_ends[c] != begin)
        return fail(where[0], "cell " + std::to_string(c) + " (" + vtkCellTypeName(static_cast<int>(types[c])) +
                                  ") is not a polyhedron but has " + std::to_string(poly_ends[c] - begin) + " faces");
      continue;
    }
    stream += 1 + static_cast<uint64_t>(poly_ends[c] - begin);
    for (int64_t i = begin; i < poly_ends[c]; ++i) {
      const int64_t f = poly_faces[static_cast<size_t>(i)];
      if (++uses[static_cast<size_t>(f)] > 2)
        return fail(where[1], "face " + std::to_string(f) + " is named by more than two polyhedra");
      stream += static_cast<uint64_t>(face_ends[f] - (f == 0 ? 0 : face_ends[f - 1]));
    }
  }
  for (size_t i = 0; i < face_points.size(); ++i)
    if (face_points[i] < 0 || face_points[i] >= np)
      return fail(where[3], "refers to point " + std::to_string(face_points[i]) + " but the piece has " +
                                std::to_string(np) + " points");
  cells_.face_offsets.resize(cell_base, -1);  // earlier pieces without polyhedra
  cells_.faces.reserve(cells_.faces.size() + stream);
  for (size_t c = 0; c < nc; ++c) {
    if (types[c] != kVtkPolyhedron) {
      cells_.face_offsets.push_back(-1);
      continue;
    }
    const int64_t begin = c == 0 ? 0 : poly_ends[c - 1];
    cells_.faces.push_back(poly_ends[c] - begin);
    for (int64_t i = begin; i < poly_ends[c]; ++i) {
      const int64_t f = poly_faces[static_cast<size_t>(i)], first = f == 0 ? 0 : face_ends[f - 1];
      cells_.faces.push_back(face_ends[f] - first);
      for (int64_t k = first; k < face_ends[f]; ++k)
        cells_.faces.push_back(face_points[static_cast<size_t>(k)] + static_cast<int64_t>(point_base));
    }
    cells_.face_offsets.push_back(static_cast<int64_t>(cells_.faces.size()));
  }
  return Status::ok();
}

Status VtuReader::readSection(const pugi::xml_node& piece, const char* section, uint64_t items, const std::string& at,
                              std::vector<Field>* fields) {
  for (pugi::xml_node a : piece.child(section).children()) {
    const std::string name = a.attribute("Name").as_string();
    // VTK writes its string arrays as <Array type="String"> (VTK 5 to 8: <DataArray type="String">):
    // text, not mesh data.
    if (std::string(a.name()) != "DataArray" || std::string(a.attribute("type").as_string()) == "String") {
      if (a.type() == pugi::node_element && skipped_arrays_.insert(std::string(section) + "/" + name).second)
        result_.report.warnings.push_back(std::string("skipped <") + a.name() + "> '" + name + "' (" +
                                          a.attribute("type").as_string() + ") of " + section +
                                          ": only numeric DataArrays are mesh data");
      continue;
    }
    Array arr;
    GTN_RETURN_IF_ERROR(readArray(a, items, at + " " + section + " '" + name + "'", &arr));
    Field f(name, arr.components, arr.type, 0);
    f.bytes = std::move(arr.bytes);
    fields->push_back(std::move(f));
  }
  return Status::ok();
}

// Six integers "x0 x1 y0 y1 z0 z1" (WholeExtent, Extent).
bool parseExtent(const char* text, int64_t out[6]) {
  std::istringstream in(text);
  for (int i = 0; i < 6; ++i)
    if (!(in >> out[i])) return false;
  std::string rest;
  return !(in >> rest);
}

// n finite doubles (Origin, Spacing, Direction).
bool parseDoubles(const char* text, int n, double* out) {
  std::istringstream in(text);
  for (int i = 0; i < n; ++i)
    if (!(in >> out[i]) || !std::isfinite(out[i])) return false;
  std::string rest;
  return !(in >> rest);
}

// Copies a piece's block of items (i fastest) into the whole extent's (i fastest), marking them in
// *seen. `cells`: the blocks are of cells (one fewer than points along each axis).
void scatterBlock(const int64_t piece[6], const int64_t whole[6], bool cells, size_t item, const uint8_t* src,
                  uint8_t* dst, std::vector<bool>* seen) {
  uint64_t lo[3], n[3], wn[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<uint64_t>(piece[2 * a]) - static_cast<uint64_t>(whole[2 * a]);
    n[a] = static_cast<uint64_t>(piece[2 * a + 1]) - static_cast<uint64_t>(piece[2 * a]) + (cells ? 0 : 1);
    wn[a] = static_cast<uint64_t>(whole[2 * a + 1]) - static_cast<uint64_t>(whole[2 * a]) + (cells ? 0 : 1);
  }
  for (uint64_t k = 0; k < n[2]; ++k)
    for (uint64_t j = 0; j < n[1]; ++j) {
      const uint64_t from = (k * n[1] + j) * n[0], to = ((lo[2] + k) * wn[1] + lo[1] + j) * wn[0] + lo[0];
      std::memcpy(dst + to * item, src + from * item, n[0] * item);
      for (uint64_t i = 0; i < n[0]; ++i) (*seen)[to + i] = true;
    }
}

Status VtuReader::structuredWhole(const pugi::xml_node& grid, const std::string& type, uint64_t file_bytes,
                                  bool one_file, int64_t whole[6], uint64_t dims[3]) const {
  const std::string element = tagOf(grid);
  if (!parseExtent(grid.attribute("WholeExtent").as_string(), whole))
    return fail(element, "missing or bad WholeExtent (six integers)");
  for (int a = 0; a < 3; ++a) {
    // The span in unsigned arithmetic: the signed difference of extreme extents would overflow.
    const uint64_t span = static_cast<uint64_t>(whole[2 * a + 1]) - static_cast<uint64_t>(whole[2 * a]);
    if (whole[2 * a + 1] < whole[2 * a] || span >= UINT32_MAX) return fail(element, "bad WholeExtent");
    dims[a] = span + 1;
  }
  const std::string dims_text =
      std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " + std::to_string(dims[2]);
  if (dims[0] < 2 || dims[1] < 2 || dims[2] < 2)
    return unsupported(path_ + ": a " + dims_text +
                       " grid has fewer than 2 points along an axis, hence no volume cells; only 3D grids can be "
                       "split into tetrahedra");
  // 32-bit point indices; and the points of rectilinear grids and of image data are not in the file:
  // a few bytes could declare billions, so their number is bounded by the files' size.
  const uint64_t limit =
      type != "StructuredGrid" ? std::min<uint64_t>(UINT32_MAX, 64 * file_bytes + (1u << 20)) : UINT32_MAX;
  if (dims[0] > limit || dims[1] > limit / dims[0] || dims[2] > limit / (dims[0] * dims[1]))
    return invalidData(path_ + ": a grid of " + dims_text + " points, more than " +
                       (limit == UINT32_MAX ? std::string("32-bit indices can number")
                                            : (one_file ? "a file of " : "files of ") + std::to_string(file_bytes) +
                                                  (one_file ? " bytes describes" : " bytes describe")));
  return Status::ok();
}

Status VtuReader::readStructuredPieces(const pugi::xml_node& grid, const std::string& type, const int64_t whole[6],
                                       std::vector<StructuredPiece>* pieces) {
  size_t index = 0;
  for (pugi::xml_node node : grid.children("Piece")) {
    const std::string at = "Piece " + std::to_string(index++);
    StructuredPiece p;
    if (!parseExtent(node.attribute("Extent").as_string(), p.extent)) return fail(at, "missing or bad Extent");
    uint64_t pd[3];
    for (int a = 0; a < 3; ++a) {
      if (p.extent[2 * a] < whole[2 * a] || p.extent[2 * a + 1] > whole[2 * a + 1] ||
          p.extent[2 * a + 1] <= p.extent[2 * a])
        return fail(at, "Extent \"" + std::string(node.attribute("Extent").as_string()) +
                            "\" is not a 3D block within the WholeExtent");
      pd[a] = static_cast<uint64_t>(p.extent[2 * a + 1]) - static_cast<uint64_t>(p.extent[2 * a]) + 1;
    }
    p.np = pd[0] * pd[1] * pd[2];
    p.nc = (pd[0] - 1) * (pd[1] - 1) * (pd[2] - 1);
    if (type == "StructuredGrid") {
      const pugi::xml_node points = node.child("Points").child("DataArray");
      if (!points) return fail(at, "no <Points> DataArray");
      GTN_RETURN_IF_ERROR(readArray(points, p.np, at + " Points", &p.points));
      if (p.points.components != 3) return fail(at + " Points", "NumberOfComponents is not 3");
    } else if (type == "RectilinearGrid") {
      int a = 0;
      for (pugi::xml_node c : node.child("Coordinates").children("DataArray")) {
        if (a == 3) return fail(at + " Coordinates", "more than three DataArrays");
        Array arr;
        const std::string where = at + " Coordinates " + std::string(1, static_cast<char>('x' + a));
        GTN_RETURN_IF_ERROR(readArray(c, pd[a], where, &arr));
        if (arr.components != 1) return fail(where, "NumberOfComponents is not 1");
        scalarsToDouble(arr.type, arr.bytes.data(), pd[a], &p.axis[a]);
        p.axis_f32 = p.axis_f32 && arr.type == ScalarType::kFloat32;
        ++a;
      }
      if (a != 3) return fail(at, "<Coordinates> needs three DataArrays (x, y, z)");
    }
    GTN_RETURN_IF_ERROR(readSection(node, "PointData", p.np, at, &p.point_fields));
    GTN_RETURN_IF_ERROR(readSection(node, "CellData", p.nc, at, &p.cell_fields));
    p.file = path_;
    p.at = at;
    pieces->push_back(std::move(p));
  }
  if (index == 0) return fail(tagOf(grid), "no <Piece>");
  return Status::ok();
}

StatusOr<ImportResult> VtuReader::readStructured(const pugi::xml_node& root, const std::string& type,
                                                 const ImportOptions& options) {
  const pugi::xml_node grid = root.child(type.c_str());
  if (!grid) return invalidData(path_ + ": no <" + type + "> element");
  int64_t whole[6];
  uint64_t dims[3];
  GTN_RETURN_IF_ERROR(structuredWhole(grid, type, text_.size(), true, whole, dims));
  std::vector<StructuredPiece> pieces;
  GTN_RETURN_IF_ERROR(readStructuredPieces(grid, type, whole, &pieces));
  ImageGeometry image;
  if (type == "ImageData") GTN_RETURN_IF_ERROR(imageGeometry(grid, &image));
  return assembleStructured(grid, type, whole, dims, pieces, image, options);
}

StatusOr<ImportResult> VtuReader::readParallelStructured(const pugi::xml_node& root, const std::string& type,
                                                         const ImportOptions& options) {
  const std::string ptype = "P" + type;
  const pugi::xml_node grid = root.child(ptype.c_str());
  if (!grid) return invalidData(path_ + ": no <" + ptype + "> element");
  // The pieces' files first: together with this one they bound the points of a grid whose
  // coordinates no array holds.
  std::vector<std::string> paths, texts;
  uint64_t bytes = text_.size();
  for (pugi::xml_node piece : grid.children("Piece")) {
    const std::string source = piece.attribute("Source").as_string();
    if (source.empty()) return invalidData(path_ + ": <Piece> " + std::to_string(paths.size()) + " has no Source");
    const std::string piece_path = source[0] == '/' ? source : parentDirectory(path_) + source;
    const std::string at = path_ + ": piece " + std::to_string(paths.size()) + ": ";
    StatusOr<std::string> text = readPieceFile(piece_path);
    if (!text.isOk()) return Status(text.status().code(), at + text.status().message());
    bytes += text->size();
    paths.push_back(piece_path);
    texts.push_back(std::move(*text));
  }
  if (paths.empty()) return invalidData(path_ + ": <" + ptype + "> names no <Piece> file");
  int64_t whole[6];
  uint64_t dims[3];
  GTN_RETURN_IF_ERROR(structuredWhole(grid, type, bytes, false, whole, dims));
  std::vector<StructuredPiece> pieces;
  ImageGeometry image;
  for (size_t k = 0; k < paths.size(); ++k) {
    auto pieceError = [&](const Status& st) {
      return Status(st.code(), path_ + ": piece " + std::to_string(k) + ": " + st.message());
    };
    VtuReader reader(paths[k], texts[k]);
    reader.in_parallel_ = true;
    StatusOr<pugi::xml_node> piece_root = reader.parse();
    if (!piece_root.isOk()) return pieceError(piece_root.status());
    const std::string piece_type = piece_root->attribute("type").as_string();
    if (isParallelType(piece_type))
      return pieceError(invalidData(paths[k] + ": a piece of a parallel file is itself a parallel file"));
    if (piece_type != type)
      return pieceError(invalidData(paths[k] + ": a VTKFile of type \"" + piece_type + "\", not " + type));
    const pugi::xml_node piece_grid = piece_root->child(type.c_str());
    if (!piece_grid) return pieceError(invalidData(paths[k] + ": no <" + type + "> element"));
    // The extents of a piece file's <Piece> elements are within the whole grid's, not only its own.
    const size_t before = pieces.size();
    if (Status st = reader.readStructuredPieces(piece_grid, type, whole, &pieces); !st.isOk()) return pieceError(st);
    for (size_t i = before; i < pieces.size(); ++i) pieces[i].source = static_cast<int>(k);
    if (type == "ImageData" && k == 0) {
      // VTK's writers put Origin and Spacing on both elements but Direction only on the piece's.
      if (Status st = reader.imageGeometry(piece_grid, &image); !st.isOk()) return pieceError(st);
    }
  }
  if (type == "ImageData") GTN_RETURN_IF_ERROR(imageGeometry(grid, &image));
  // Ghost marks differ from piece to piece for the points and cells that pieces share (DUPLICATE
  // bits); the blanking bits (HIDDENPOINT 2, HIDDENCELL 32) are the grid's and agree. Only those are
  // kept while the grid is assembled and split (finishStructuredImport drops blanked cells); the
  // arrays, VTK's bookkeeping rather than data, are not kept after that.
  constexpr uint8_t kBlanking = kVtkHiddenPoint | kVtkHiddenCell;
  size_t ghost_arrays = 0;
  for (StructuredPiece& p : pieces)
    for (std::vector<Field>* fields : {&p.point_fields, &p.cell_fields})
      for (Field& f : *fields) {
        if (f.name != kVtkGhostArray) continue;
        ++ghost_arrays;
        if (f.type != ScalarType::kUInt8 || f.components != 1) {
          f.name += "_";  // not VTK's marks: kept as data under another name than the bookkeeping's
          continue;
        }
        for (uint8_t& b : f.bytes) b &= kBlanking;
      }
  StatusOr<ImportResult> result = assembleStructured(grid, type, whole, dims, pieces, image, options);
  if (result.isOk() && ghost_arrays > 0) {
    dropGhostArrays(result->mesh);
    result->report.warnings.push_back(
        "the pieces' vtkGhostType arrays (VTK's marks of shared points and cells) "
        "were not kept");
  }
  return result;
}

Status VtuReader::imageGeometry(const pugi::xml_node& grid, ImageGeometry* image) const {
  const std::string element = tagOf(grid);
  if (grid.attribute("Origin") && !parseDoubles(grid.attribute("Origin").as_string(), 3, image->origin))
    return fail(element, "bad Origin (three numbers)");
  if (grid.attribute("Spacing") && !parseDoubles(grid.attribute("Spacing").as_string(), 3, image->spacing))
    return fail(element, "bad Spacing (three numbers)");
  if (grid.attribute("Direction") && !parseDoubles(grid.attribute("Direction").as_string(), 9, image->dir))
    return fail(element, "bad Direction (nine numbers)");
  return Status::ok();
}

StatusOr<ImportResult> VtuReader::assembleStructured(const pugi::xml_node& grid, const std::string& type,
                                                     const int64_t whole[6], const uint64_t dims[3],
                                                     const std::vector<StructuredPiece>& pieces,
                                                     const ImageGeometry& image, const ImportOptions& options) {
  const std::string element = tagOf(grid);
  const uint64_t np = dims[0] * dims[1] * dims[2];
  const uint64_t nc = (dims[0] - 1) * (dims[1] - 1) * (dims[2] - 1);
  const StructuredPiece& first = pieces[0];
  uint64_t piece_points = 0;
  for (const StructuredPiece& p : pieces) {
    piece_points += p.np;
    // The same arrays as the first piece, in the same order.
    auto same = [](const std::vector<Field>& x, const std::vector<Field>& y) {
      if (x.size() != y.size()) return false;
      for (size_t i = 0; i < x.size(); ++i)
        if (x[i].name != y[i].name || x[i].type != y[i].type || x[i].components != y[i].components) return false;
      return true;
    };
    const std::string first_name = p.file == first.file ? first.at : first.file + ": " + first.at;
    if (!same(p.point_fields, first.point_fields) || !same(p.cell_fields, first.cell_fields))
      return invalidData(pieceName(p) + ": does not carry the same point and cell arrays as " + first_name);
    if (type == "StructuredGrid" && p.points.type != first.points.type)
      return invalidData(pieceName(p) + " Points: a type other than " + first_name + "'s");
  }
  // Pieces share their boundary layers; together they must hold every point of the whole extent (a
  // check before the whole grid is allocated: the pieces' data is in the file, the whole's is not).
  if (piece_points < np)
    return fail(element, "its pieces hold " + std::to_string(piece_points) + " points, fewer than the " +
                             std::to_string(np) + " of the WholeExtent");

  TetMesh& mesh = result_.mesh;
  const bool one = pieces.size() == 1;  // then it covers the whole (checked above) and is used as it is
  std::vector<bool> point_seen(one ? 0 : np), cell_seen(one ? 0 : nc);
  auto gather = [&](const std::vector<Field> StructuredPiece::*fields, bool cells, std::vector<Field>* out) {
    const uint64_t items = cells ? nc : np;
    for (size_t f = 0; f < (first.*fields).size(); ++f) {
      const Field& proto = (first.*fields)[f];
      if (one) {
        out->push_back(proto);
        continue;
      }
      Field whole_field(proto.name, proto.components, proto.type, items);
      for (const StructuredPiece& p : pieces)
        scatterBlock(p.extent, whole, cells, proto.components * proto.valueSize(), (p.*fields)[f].bytes.data(),
                     whole_field.bytes.data(), cells ? &cell_seen : &point_seen);
      out->push_back(std::move(whole_field));
    }
  };
  if (type == "StructuredGrid") {
    const size_t item = 3 * scalarSize(first.points.type);
    std::vector<uint8_t> xyz;
    if (!one) {
      xyz.resize(np * item);
      for (const StructuredPiece& p : pieces)
        scatterBlock(p.extent, whole, false, item, p.points.bytes.data(), xyz.data(), &point_seen);
    }
    scalarsToDouble(first.points.type, one ? first.points.bytes.data() : xyz.data(), 3 * np, &mesh.coords);
    mesh.coord_type = first.points.type == ScalarType::kFloat32 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  } else if (type == "RectilinearGrid") {
    std::vector<double> axis[3];
    bool all_f32 = true;
    for (int a = 0; a < 3; ++a) {
      axis[a].assign(dims[a], 0.0);
      std::vector<bool> seen(dims[a]);
      for (const StructuredPiece& p : pieces) {
        const uint64_t lo = static_cast<uint64_t>(p.extent[2 * a]) - static_cast<uint64_t>(whole[2 * a]);
        for (size_t i = 0; i < p.axis[a].size(); ++i) axis[a][lo + i] = p.axis[a][i], seen[lo + i] = true;
        all_f32 = all_f32 && p.axis_f32;
      }
      if (std::find(seen.begin(), seen.end(), false) != seen.end())
        return fail(element, "its pieces leave out coordinates of the WholeExtent");
    }
    rectilinearPoints(axis, &mesh.coords);
    mesh.coord_type = all_f32 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  } else {
    // ImageData: point (i, j, k) of the extent at Origin + Direction (i Sx, j Sy, k Sz), in double.
    const double* dir = image.dir;
    const bool axis_aligned = dir[0] == 1 && dir[1] == 0 && dir[2] == 0 && dir[3] == 0 && dir[4] == 1 && dir[5] == 0 &&
                              dir[6] == 0 && dir[7] == 0 && dir[8] == 1;
    const int64_t lower[3] = {whole[0], whole[2], whole[4]};
    imagePoints(dims, lower, image.origin, image.spacing, axis_aligned ? nullptr : dir, &mesh.coords);
    mesh.coord_type = ScalarType::kFloat64;
  }
  gather(&StructuredPiece::point_fields, false, &mesh.point_fields);
  gather(&StructuredPiece::cell_fields, true, &cell_fields_);
  if (one && !std::equal(first.extent, first.extent + 6, whole))
    return invalidData(pieceName(first) + ": Extent differs from the WholeExtent, which a single piece must cover");
  if (!one) {
    // Every point and cell of the whole extent from some piece. The points of a StructuredGrid were
    // marked with its coordinates; an ImageData or RectilinearGrid without arrays has none to leave out.
    const bool points_marked = type == "StructuredGrid" || !first.point_fields.empty();
    if (points_marked && std::find(point_seen.begin(), point_seen.end(), false) != point_seen.end())
      return fail(element, "its pieces leave out points of the WholeExtent");
    if (!first.cell_fields.empty() && std::find(cell_seen.begin(), cell_seen.end(), false) != cell_seen.end())
      return fail(element, "its pieces leave out cells of the WholeExtent");
  }
  GTN_RETURN_IF_ERROR(finishStructuredImport(path_, dims, cell_fields_, options, &result_));
  return std::move(result_);
}

namespace {

// Appends field `b` (of the piece `where`) to `a`, which must have its name, type and components.
Status appendField(Field& a, const Field& b, const std::string& where) {
  if (a.name != b.name || a.type != b.type || a.components != b.components)
    return invalidData(where + ": its array '" + b.name + "' (" + std::to_string(b.components) + " " +
                       scalarTypeName(b.type) + ") does not match the first piece's '" + a.name + "' (" +
                       std::to_string(a.components) + " " + scalarTypeName(a.type) + ")");
  a.bytes.insert(a.bytes.end(), b.bytes.begin(), b.bytes.end());
  return Status::ok();
}

}  // namespace

StatusOr<ImportResult> VtuReader::readParallel(const pugi::xml_node& root, const ImportOptions& options) {
  const pugi::xml_node grid = root.child("PUnstructuredGrid");
  if (!grid) return invalidData(path_ + ": no <PUnstructuredGrid> element");
  std::vector<std::string> sources;
  for (pugi::xml_node piece : grid.children("Piece")) {
    const std::string source = piece.attribute("Source").as_string();
    if (source.empty()) return invalidData(path_ + ": <Piece> " + std::to_string(sources.size()) + " has no Source");
    sources.push_back(source);
  }
  if (sources.empty()) return invalidData(path_ + ": <PUnstructuredGrid> names no <Piece> file");
  const std::string dir = parentDirectory(path_);
  ImportResult all;
  bool float64 = false;
  size_t ghosts = 0, ghost_points = 0;
  for (size_t k = 0; k < sources.size(); ++k) {
    const std::string piece_path = sources[k][0] == '/' ? sources[k] : dir + sources[k];
    auto pieceError = [&](const Status& st) {
      return Status(st.code(), path_ + ": piece " + std::to_string(k) + ": " + st.message());
    };
    StatusOr<std::string> text = readPieceFile(piece_path);
    if (!text.isOk()) return pieceError(text.status());
    VtuReader reader(piece_path, *text);
    reader.in_parallel_ = true;
    StatusOr<pugi::xml_node> piece_root = reader.parse();
    if (!piece_root.isOk()) return pieceError(piece_root.status());
    const std::string piece_type = piece_root->attribute("type").as_string();
    if (piece_type != "UnstructuredGrid" && !isParallelType(piece_type))
      return pieceError(invalidData(piece_path + ": a VTKFile of type \"" + piece_type + "\", not UnstructuredGrid"));
    StatusOr<ImportResult> read = reader.readParsed(*piece_root, options);
    if (!read.isOk()) return pieceError(read.status());
    ImportResult r = std::move(*read);
    TetMesh& m = r.mesh;
    // Ghost cells, copies of cells that other pieces own, were dropped by finishVtkImport: they are
    // kept once, by their owner.
    ghosts += reader.duplicate_tets_;
    ghost_points += dropGhostOnlyPoints(m);
    dropGhostArrays(m);
    float64 |= m.coord_type == ScalarType::kFloat64;
    if (k == 0) {
      all = std::move(r);
      for (std::string& w : all.report.warnings) w = piece_path + ": " + w;
      continue;
    }
    const std::string where = path_ + ": piece " + std::to_string(k) + " (" + piece_path + ")";
    if (m.point_fields.size() != all.mesh.point_fields.size() || m.cell_fields.size() != all.mesh.cell_fields.size())
      return invalidData(where + ": its point and cell arrays differ from the first piece's");
    for (size_t f = 0; f < m.point_fields.size(); ++f)
      GTN_RETURN_IF_ERROR(appendField(all.mesh.point_fields[f], m.point_fields[f], where));
    for (size_t f = 0; f < m.cell_fields.size(); ++f)
      GTN_RETURN_IF_ERROR(appendField(all.mesh.cell_fields[f], m.cell_fields[f], where));
    const uint32_t base = static_cast<uint32_t>(all.mesh.numPoints());
    if (all.mesh.numPoints() + m.numPoints() >= UINT32_MAX) return unsupported(path_ + ": more than 2^32-1 points");
    for (Tet t : m.tets) {
      for (uint32_t& v : t) v += base;
      all.mesh.tets.push_back(t);
    }
    all.mesh.coords.insert(all.mesh.coords.end(), m.coords.begin(), m.coords.end());
    ImportReport& a = all.report;
    const ImportReport& b = r.report;
    a.flipped += b.flipped;
    a.zero_volume += b.zero_volume;
    a.dropped_cells += b.dropped_cells;
    a.welded_points += b.welded_points;
    a.collapsed_tets += b.collapsed_tets;
    a.steiner_points += b.steiner_points;
    for (const std::string& w : b.warnings) a.warnings.push_back(piece_path + ": " + w);
  }
  all.mesh.coord_type = float64 ? ScalarType::kFloat64 : ScalarType::kFloat32;
  reportPieces(sources.size(), ghosts, ghost_points, options.weld, &all.report);
  return all;
}

StatusOr<pugi::xml_node> VtuReader::parse() {
  // Raw appended data after '_' is not XML: hand pugixml only what precedes it, closed again.
  size_t xml_size = text_.size();
  std::string_view close_xml;
  const size_t appended = text_.find("<AppendedData");
  if (appended != std::string::npos) {
    const size_t tag_end = text_.find('>', appended);
    const size_t underscore = tag_end == std::string::npos ? std::string::npos : text_.find('_', tag_end);
    if (underscore == std::string::npos)
      return invalidData(path_ + ": byte offset " + std::to_string(appended) +
                         ": <AppendedData> without the '_' that starts its data");
    appended_begin_ = underscore + 1;
    const size_t close = text_.rfind("</AppendedData>");
    appended_end_ = close == std::string::npos || close < appended_begin_ ? text_.size() : close;
    xml_size = underscore;
    close_xml = "</AppendedData></VTKFile>";
  }
  // A copy pugixml parses in place, its pages mapped in one call (pugixml's own copy, which
  // load_buffer makes, maps them one at a time: inline arrays make that most of the file).
  xml_.clear();
  reservePopulated(xml_, xml_size + close_xml.size());
  xml_.assign(text_.data(), xml_size);
  xml_ += close_xml;
  const pugi::xml_parse_result parsed =
      doc_.load_buffer_inplace(xml_.data(), xml_.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!parsed)
    return invalidData(path_ + ": byte offset " + std::to_string(parsed.offset) + ": not well-formed XML (" +
                       parsed.description() + ")");
  const pugi::xml_node root = doc_.child("VTKFile");
  if (!root) return Status(StatusCode::kNotOurFile, path_ + ": no <VTKFile> element: not a VTK XML file");
  const std::string order = root.attribute("byte_order").as_string("LittleEndian");
  if (order != "LittleEndian" && order != "BigEndian")
    return invalidData(path_ + ": unknown byte_order \"" + order + "\"");
  big_endian_ = order == "BigEndian";
  const std::string header_type = root.attribute("header_type").as_string("UInt32");
  if (header_type != "UInt32" && header_type != "UInt64")
    return invalidData(path_ + ": unknown header_type \"" + header_type + "\"");
  header_bytes_ = header_type == "UInt64" ? 8 : 4;
  const std::string compressor = root.attribute("compressor").as_string();
  if (compressor.empty()) compressor_ = Compressor::kNone;
  else if (compressor == "vtkZLibDataCompressor") compressor_ = Compressor::kZlib;
  else if (compressor == "vtkLZ4DataCompressor") compressor_ = Compressor::kLz4;
  else if (compressor == "vtkLZMADataCompressor") compressor_ = Compressor::kLzma;
  else
    return unsupported(path_ + ": compressor \"" + compressor +
                       "\" is not supported (VTK's vtkZLibDataCompressor, vtkLZ4DataCompressor and "
                       "vtkLZMADataCompressor are)");
  compressed_ = compressor_ != Compressor::kNone;
  if (appended_end_ != 0) {
    const std::string encoding = root.child("AppendedData").attribute("encoding").as_string("raw");
    if (encoding != "raw" && encoding != "base64")
      return invalidData(path_ + ": unknown AppendedData encoding \"" + encoding + "\"");
    appended_base64_ = encoding == "base64";
  }
  return root;
}

StatusOr<ImportResult> VtuReader::read(const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(const pugi::xml_node root, parse());
  return readParsed(root, options);
}

StatusOr<ImportResult> VtuReader::readParsed(const pugi::xml_node& root, const ImportOptions& options) {
  const std::string type = root.attribute("type").as_string();
  const bool structured = type == "StructuredGrid" || type == "RectilinearGrid" || type == "ImageData";
  const bool parallel = isParallelType(type);
  if (parallel && in_parallel_) return invalidData(path_ + ": a piece of a parallel file is itself a parallel file");
  if (type == "PUnstructuredGrid") return readParallel(root, options);
  if (parallel) return readParallelStructured(root, type.substr(1), options);
  if (type == "vtkMultiBlockDataSet" || type == "vtkPartitionedDataSet" || type == "vtkPartitionedDataSetCollection" ||
      type == "vtkMultiPieceDataSet" || type == "Collection") {
    // .vtm, .vtpd, .vtpc, .pvd: lists of other files (blocks, partitions, time steps).
    std::string files;
    size_t named = 0;
    for (pugi::xpath_node n : root.select_nodes("//DataSet[@file]")) {
      if (named++ < 3) files += std::string(files.empty() ? "" : ", ") + n.node().attribute("file").value();
    }
    return unsupported(path_ + ": VTKFile type \"" + type + "\" is a collection of other files" +
                       (named ? " (" + files + (named > 3 ? ", ..." : "") + ")" : std::string()) +
                       ": convert one of them");
  }
  if (type != "UnstructuredGrid" && !structured)
    return unsupported(path_ + ": VTKFile type \"" + type +
                       "\" is not supported (it holds no volume cells: only UnstructuredGrid, StructuredGrid, "
                       "RectilinearGrid and ImageData do, and their parallel forms)");
  // The dataset's own arrays (TIME, CYCLE, ...) describe no point or cell: a warning names them.
  std::vector<std::string> dataset_arrays;
  for (pugi::xml_node a : root.child(type.c_str()).child("FieldData").children())
    if (a.type() == pugi::node_element) dataset_arrays.push_back(a.attribute("Name").as_string());
  if (!dataset_arrays.empty())
    result_.report.warnings.push_back("the dataset's FieldData arrays (" + joinNames(dataset_arrays) +
                                      ") are not kept: they belong to no point or cell");
  if (structured) return readStructured(root, type, options);
  const pugi::xml_node grid = root.child("UnstructuredGrid");
  if (!grid) return invalidData(path_ + ": no <UnstructuredGrid> element");
  size_t pieces = 0;
  for (pugi::xml_node piece : grid.children("Piece")) GTN_RETURN_IF_ERROR(readPiece(piece, pieces++));
  if (pieces == 0) return invalidData(path_ + ": <UnstructuredGrid> has no <Piece>");
  result_.mesh.coord_type = coords_float64_ ? ScalarType::kFloat64 : ScalarType::kFloat32;
  if (result_.mesh.numPoints() == 0) result_.mesh.coord_type = ScalarType::kFloat64;
  // Ghost cells (vtkGhostType DUPLICATECELL) are copies of cells another piece owns: dropped when
  // that piece is read too (a .pvtu, or several pieces in this file), kept with a warning otherwise.
  const bool several = pieces > 1;
  GTN_RETURN_IF_ERROR(finishVtkImport(path_, cells_, cell_fields_, options, &result_,
                                      in_parallel_ || several ? &duplicate_tets_ : nullptr));
  if (several) {
    const size_t ghost_points = dropGhostOnlyPoints(result_.mesh);
    dropGhostArrays(result_.mesh);
    reportPieces(pieces, duplicate_tets_, ghost_points, options.weld, &result_.report);
  } else if (!in_parallel_) {
    if (const uint8_t* marks = vtkGhostMarks(cell_fields_, cells_.types.size())) {
      size_t copies = 0;
      for (size_t c = 0; c < cells_.types.size(); ++c)
        copies += (marks[c] & kVtkDuplicateCell) && !(marks[c] & kVtkHiddenCell);
      if (copies > 0)
        result_.report.warnings.push_back(
            std::to_string(copies) +
            " cells are ghost copies of another piece's cells (vtkGhostType DUPLICATECELL); "
            "kept, as the file holds no other piece");
    }
  }
  return std::move(result_);
}

}  // namespace

StatusOr<ImportResult> importVtu(const std::string& path, const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(std::string text, readWholeFile(path));
  VtuReader reader(path, text);
  return reader.read(options);
}

}  // namespace gtn

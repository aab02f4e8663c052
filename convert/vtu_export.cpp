// .vtu export: VTK XML UnstructuredGrid, version 1.0, little-endian, UInt64 headers, inline base64
// ("binary") arrays, optionally zlib-compressed in 32 KiB blocks. Header and data are base64-encoded
// apart, as VTK itself writes them (and as both VTK and meshio read them).
//
// Metadata (TetMesh::metadata) is not written: VTK would keep string FieldData, but meshio 5 fails on
// String arrays, and a .vtu must stay readable by both.
#include <algorithm>
#include <cstdio>
#include <cstring>

#include "convert/export.h"
#include "convert/vtk_common.h"
#include "format/file_io.h"
#include "mesh/utf8.h"

namespace gtn {

namespace {

constexpr size_t kBlockSize = 32 * 1024;

// A name as XML 1.0 allows it in an attribute: UTF-8 (bytes that are not are read as Latin-1, as
// toUtf8 does), markup escaped, tabs and line breaks as character references, and the other control
// characters, which no XML 1.0 document may hold even as references, as %XX (VTK's legacy encoding).
std::string xmlEscape(const std::string& name) {
  const std::string s = toUtf8(name);
  std::string out;
  for (char c : s) {
    const unsigned char u = static_cast<unsigned char>(c);
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      // An XML parser turns a literal tab or line break in an attribute into a space.
      case '\t': out += "&#9;"; break;
      case '\n': out += "&#10;"; break;
      case '\r': out += "&#13;"; break;
      default:
        if (u < 0x20) {
          char buf[4];
          std::snprintf(buf, sizeof buf, "%%%02X", u);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out;
}

class VtuWriter {
 public:
  VtuWriter(std::FILE* f, bool compress, const std::string& path) : f_(f), compress_(compress), path_(path) {}

  Status array(const char* indent, const std::string& name, ScalarType type, uint32_t components, const uint8_t* data,
               size_t size) {
    put(std::string(indent) + "<DataArray type=\"" + vtkXmlTypeName(type) + "\" Name=\"" + xmlEscape(name) +
        "\" NumberOfComponents=\"" + std::to_string(components) + "\" format=\"binary\">\n" + indent + "  ");
    if (compress_) {
      std::vector<uint8_t> header, blocks;
      zlibCompressBlocks(data, size, kBlockSize, 8, &header, &blocks);
      put(base64Encode(header.data(), header.size()));
      encodeChunked(blocks.data(), blocks.size());
    } else {
      uint8_t header[8];
      const uint64_t n = size;
      std::memcpy(header, &n, 8);  // little-endian host
      put(base64Encode(header, 8));
      encodeChunked(data, size);
    }
    put(std::string("\n") + indent + "</DataArray>\n");
    if (std::ferror(f_)) return ioError(path_ + ": write failed");
    return Status::ok();
  }

  void put(const std::string& s) { std::fwrite(s.data(), 1, s.size(), f_); }

 private:
  // Base64 of consecutive 3-byte-aligned chunks concatenates to the base64 of the whole.
  void encodeChunked(const uint8_t* data, size_t size) {
    constexpr size_t kChunk = 3 * 65536;
    for (size_t at = 0; at < size; at += kChunk) put(base64Encode(data + at, std::min(kChunk, size - at)));
  }

  std::FILE* f_;
  bool compress_;
  const std::string& path_;
};

}  // namespace

Status exportVtu(const TetMesh& mesh, const std::string& path, const ExportOptions& options) {
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(path));
  return writeFileAtomically(path, [&](std::FILE* f) -> Status {
    VtuWriter w(f, options.compress, path);
    w.put(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\"" +
        std::string(options.compress ? " compressor=\"vtkZLibDataCompressor\"" : "") +
        ">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"" + std::to_string(mesh.numPoints()) +
        "\" NumberOfCells=\"" + std::to_string(mesh.numTets()) + "\">\n");
    const char* indent = "        ";
    w.put("      <PointData>\n");
    for (const Field& fd : mesh.point_fields)
      GTN_RETURN_IF_ERROR(w.array(indent, fd.name, fd.type, fd.components, fd.bytes.data(), fd.bytes.size()));
    w.put("      </PointData>\n      <CellData>\n");
    for (const Field& fd : mesh.cell_fields)
      GTN_RETURN_IF_ERROR(w.array(indent, fd.name, fd.type, fd.components, fd.bytes.data(), fd.bytes.size()));
    w.put("      </CellData>\n      <Points>\n");
    if (mesh.coord_type == ScalarType::kFloat32) {
      std::vector<float> xyz(mesh.coords.begin(), mesh.coords.end());
      GTN_RETURN_IF_ERROR(w.array(indent, "Points", ScalarType::kFloat32, 3,
                                  reinterpret_cast<const uint8_t*>(xyz.data()), xyz.size() * sizeof(float)));
    } else {
      GTN_RETURN_IF_ERROR(w.array(indent, "Points", ScalarType::kFloat64, 3,
                                  reinterpret_cast<const uint8_t*>(mesh.coords.data()),
                                  mesh.coords.size() * sizeof(double)));
    }
    w.put("      </Points>\n      <Cells>\n");
    {
      std::vector<int64_t> conn(4 * mesh.numTets());
      for (size_t t = 0; t < mesh.numTets(); ++t)
        for (int k = 0; k < 4; ++k) conn[4 * t + k] = mesh.tets[t][k];
      GTN_RETURN_IF_ERROR(w.array(indent, "connectivity", ScalarType::kInt64, 1,
                                  reinterpret_cast<const uint8_t*>(conn.data()), conn.size() * sizeof(int64_t)));
      std::vector<int64_t> offsets(mesh.numTets());
      for (size_t t = 0; t < offsets.size(); ++t) offsets[t] = static_cast<int64_t>(4 * (t + 1));
      GTN_RETURN_IF_ERROR(w.array(indent, "offsets", ScalarType::kInt64, 1,
                                  reinterpret_cast<const uint8_t*>(offsets.data()), offsets.size() * sizeof(int64_t)));
    }
    const std::vector<uint8_t> types(mesh.numTets(), kVtkTetra);
    GTN_RETURN_IF_ERROR(w.array(indent, "types", ScalarType::kUInt8, 1, types.data(), types.size()));
    w.put("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    if (std::ferror(f)) return ioError(path + ": write failed");
    return Status::ok();
  });
}

}  // namespace gtn

// Legacy .vtk export: an UNSTRUCTURED_GRID of tetrahedra in the BINARY (big-endian) dialect of file
// version 4.2, the one every VTK release, ParaView, VisIt and meshio read. Point and cell fields are
// FIELD arrays of their own type and component count; names are %-encoded as VTK's writer does.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>

#include "convert/export.h"
#include "convert/vtk_common.h"
#include "format/file_io.h"

namespace gtn {

namespace {

// VTK's vtkDataWriter::EncodeString: a name is one token, so spaces, control bytes, bytes beyond
// ASCII and '%' itself become %XX.
std::string encodeName(const std::string& name) {
  std::string out;
  for (unsigned char c : name) {
    if (c <= ' ' || c > '~' || c == '%') {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

class LegacyWriter {
 public:
  explicit LegacyWriter(std::FILE* f) : f_(f) {}
  void put(const std::string& s) { std::fwrite(s.data(), 1, s.size(), f_); }
  // `count` values of `value_size` bytes, little-endian in memory, written big-endian.
  void bigEndian(const uint8_t* data, size_t count, size_t value_size) {
    constexpr size_t kChunk = 1 << 16;
    std::vector<uint8_t> buf;
    for (size_t at = 0; at < count; at += kChunk) {
      const size_t n = std::min(kChunk, count - at);
      buf.assign(data + at * value_size, data + (at + n) * value_size);
      swapByteOrder(buf.data(), buf.size(), value_size);
      std::fwrite(buf.data(), 1, buf.size(), f_);
    }
  }
  void fields(const char* section, const std::vector<Field>& fields, size_t items) {
    if (fields.empty()) return;
    put(std::string(section) + " " + std::to_string(items) + "\nFIELD FieldData " + std::to_string(fields.size()) +
        "\n");
    for (size_t i = 0; i < fields.size(); ++i) {
      const Field& f = fields[i];
      const std::string name = f.name.empty() ? "field_" + std::to_string(i) : encodeName(f.name);
      put(name + " " + std::to_string(f.components) + " " + std::to_string(items) + " " + vtkLegacyTypeName(f.type) +
          "\n");
      bigEndian(f.bytes.data(), items * f.components, f.valueSize());
      put("\n");
    }
  }

 private:
  std::FILE* f_;
};

}  // namespace

Status exportVtkLegacy(const TetMesh& mesh, const std::string& path) {
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(path));
  // Version 4.2 cells are 32-bit: counts, point indices and the CELLS list size.
  constexpr uint64_t kMax = std::numeric_limits<int32_t>::max();
  if (mesh.numPoints() > kMax || 5 * uint64_t{mesh.numTets()} > kMax)
    return unsupported(path + ": " + std::to_string(mesh.numPoints()) + " points and " +
                       std::to_string(mesh.numTets()) +
                       " tetrahedra are more than a legacy .vtk file's 32-bit cell list holds; write .vtu instead");
  return writeFileAtomically(path, [&](std::FILE* f) -> Status {
    LegacyWriter w(f);
    w.put("# vtk DataFile Version 4.2\ntetrahedral mesh written by gtn " GTN_VERSION_STRING
          "\nBINARY\nDATASET UNSTRUCTURED_GRID\n");
    const size_t np = mesh.numPoints(), nt = mesh.numTets();
    if (mesh.coord_type == ScalarType::kFloat32) {
      w.put("POINTS " + std::to_string(np) + " float\n");
      const std::vector<float> xyz(mesh.coords.begin(), mesh.coords.end());
      w.bigEndian(reinterpret_cast<const uint8_t*>(xyz.data()), xyz.size(), sizeof(float));
    } else {
      w.put("POINTS " + std::to_string(np) + " double\n");
      w.bigEndian(reinterpret_cast<const uint8_t*>(mesh.coords.data()), mesh.coords.size(), sizeof(double));
    }
    w.put("\nCELLS " + std::to_string(nt) + " " + std::to_string(5 * nt) + "\n");
    {
      std::vector<int32_t> cells(5 * nt);
      for (size_t t = 0; t < nt; ++t) {
        cells[5 * t] = 4;
        for (int k = 0; k < 4; ++k) cells[5 * t + 1 + k] = static_cast<int32_t>(mesh.tets[t][k]);
      }
      w.bigEndian(reinterpret_cast<const uint8_t*>(cells.data()), cells.size(), sizeof(int32_t));
      w.put("\nCELL_TYPES " + std::to_string(nt) + "\n");
      std::fill(cells.begin(), cells.begin() + static_cast<long>(nt), int32_t{kVtkTetra});
      w.bigEndian(reinterpret_cast<const uint8_t*>(cells.data()), nt, sizeof(int32_t));
      w.put("\n");
    }
    w.fields("CELL_DATA", mesh.cell_fields, nt);
    w.fields("POINT_DATA", mesh.point_fields, np);
    if (std::ferror(f)) return ioError(path + ": write failed");
    return Status::ok();
  });
}

}  // namespace gtn

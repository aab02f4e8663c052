// Legacy VTK import: the paper's Spx (ASCII) checked against an independent parse, and files written
// here in ASCII and BINARY, classic and 5.1 layouts, with every attribute kind and data type.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>

#include "convert/import.h"
#include "mesh/mesh_stats.h"
#include "test_util.h"

namespace gtn {
namespace {

using test::dataPath;
using test::tempDir;
using test::writeFile;

TEST(VtkLegacy, SpxCountsAndBitExactValues) {
  const std::string path = dataPath("vtk/spx.vtk");
  auto r = importVtkLegacy(path, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  const MeshStats s = computeMeshStats(m);
  EXPECT_EQ(s.points, 2896u);
  EXPECT_EQ(s.tets, 12936u);
  EXPECT_EQ(s.faces, 27252u);
  EXPECT_EQ(s.boundary_faces, 2760u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(m.coord_type, ScalarType::kFloat32);

  // Independent parse: strtof over the POINTS and the scalars' tokens.
  const std::string text = test::readFile(path);
  std::istringstream pts(text.substr(text.find("POINTS 2896 float") + 17));
  for (size_t i = 0; i < 3 * 2896; ++i) {
    std::string tok;
    pts >> tok;
    ASSERT_EQ(m.coords[i], static_cast<double>(std::strtof(tok.c_str(), nullptr))) << "coordinate " << i;
  }
  ASSERT_EQ(m.point_fields.size(), 1u);
  const Field& f = m.point_fields[0];
  EXPECT_EQ(f.name, "scalars");
  EXPECT_EQ(f.type, ScalarType::kFloat32);
  EXPECT_EQ(f.components, 1u);
  std::istringstream sc(text.substr(text.find("LOOKUP_TABLE default") + 20));
  std::vector<float> expected(2896);
  for (float& v : expected) {
    std::string tok;
    sc >> tok;
    v = std::strtof(tok.c_str(), nullptr);
  }
  ASSERT_EQ(f.bytes.size(), expected.size() * 4);
  EXPECT_EQ(std::memcmp(f.bytes.data(), expected.data(), f.bytes.size()), 0);
  EXPECT_FLOAT_EQ(static_cast<float>(computeMeshStats(m).fields[0].max), 2.254f);
}

// A dataset written by this test in any of the legacy dialects.
struct Array {
  std::string header;  // the line(s) before the values, with %T for the type keyword
  const char* type_keyword;
  ScalarType type;
  uint32_t comps;
  std::vector<double> values;
};

void putBigEndian(std::string& out, ScalarType type, double v) {
  uint8_t b[8];
  size_t n = scalarSize(type);
  switch (type) {
    case ScalarType::kInt8: {
      int8_t x = int8_t(v);
      std::memcpy(b, &x, 1);
      break;
    }
    case ScalarType::kUInt8: {
      uint8_t x = uint8_t(v);
      std::memcpy(b, &x, 1);
      break;
    }
    case ScalarType::kInt16: {
      int16_t x = int16_t(v);
      std::memcpy(b, &x, 2);
      break;
    }
    case ScalarType::kUInt16: {
      uint16_t x = uint16_t(v);
      std::memcpy(b, &x, 2);
      break;
    }
    case ScalarType::kInt32: {
      int32_t x = int32_t(v);
      std::memcpy(b, &x, 4);
      break;
    }
    case ScalarType::kUInt32: {
      uint32_t x = uint32_t(v);
      std::memcpy(b, &x, 4);
      break;
    }
    case ScalarType::kInt64: {
      int64_t x = int64_t(v);
      std::memcpy(b, &x, 8);
      break;
    }
    case ScalarType::kUInt64: {
      uint64_t x = uint64_t(v);
      std::memcpy(b, &x, 8);
      break;
    }
    case ScalarType::kFloat32: {
      float x = float(v);
      std::memcpy(b, &x, 4);
      break;
    }
    case ScalarType::kFloat64: {
      std::memcpy(b, &v, 8);
      break;
    }
  }
  for (size_t i = 0; i < n; ++i) out += static_cast<char>(b[n - 1 - i]);
}

std::string block(bool binary, const Array& a) {
  std::string s = a.header;
  const size_t t = s.find("%T");
  if (t != std::string::npos) s.replace(t, 2, a.type_keyword);
  s += "\n";
  if (binary) {
    for (double v : a.values) putBigEndian(s, a.type, v);
    s += "\n";
  } else {
    char buf[64];
    for (size_t i = 0; i < a.values.size(); ++i) {
      const char sep = (i + 1) % 6 == 0 ? '\n' : ' ';
      if (isFloatType(a.type)) std::snprintf(buf, sizeof buf, "%.17g%c", a.values[i], sep);
      else if (a.type == ScalarType::kUInt64)
        std::snprintf(buf, sizeof buf, "%llu%c", static_cast<unsigned long long>(a.values[i]), sep);
      else std::snprintf(buf, sizeof buf, "%lld%c", static_cast<long long>(a.values[i]), sep);
      s += buf;
    }
    s += "\n";
  }
  return s;
}

std::vector<double> ramp(size_t n, double start, double step) {
  std::vector<double> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = start + step * static_cast<double>(i);
  return v;
}

// Two unit hexahedra side by side (12 points), with point and cell attributes of many types.
struct Dataset {
  std::vector<Array> point_arrays, cell_arrays;
  std::string text;
};

Dataset makeDataset(bool binary, bool v51) {
  Dataset d;
  std::string& s = d.text;
  s = std::string("# vtk DataFile Version ") + (v51 ? "5.1" : "3.0") + "\nwritten by the Gatun tests\n" +
      (binary ? "BINARY" : "ASCII") + "\nDATASET UNSTRUCTURED_GRID\n";
  std::vector<double> xyz;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) xyz.insert(xyz.end(), {i * 0.5, j * 0.5 + 0.1, k * 0.25});
  s += block(binary, {"POINTS 12 %T", "double", ScalarType::kFloat64, 3, xyz});
  auto id = [](int i, int j, int k) { return double((k * 2 + j) * 3 + i); };
  std::vector<double> conn;
  for (int i = 0; i < 2; ++i)
    conn.insert(conn.end(), {id(i, 0, 0), id(i + 1, 0, 0), id(i + 1, 1, 0), id(i, 1, 0), id(i, 0, 1), id(i + 1, 0, 1),
                             id(i + 1, 1, 1), id(i, 1, 1)});
  if (v51) {
    s += "CELLS 3 16\n";
    s += block(binary, {"OFFSETS %T", "vtktypeint64", ScalarType::kInt64, 1, {0, 8, 16}});
    s += block(binary, {"CONNECTIVITY %T", "vtktypeint64", ScalarType::kInt64, 1, conn});
  } else {
    std::vector<double> list = {8};
    list.insert(list.end(), conn.begin(), conn.begin() + 8);
    list.push_back(8);
    list.insert(list.end(), conn.begin() + 8, conn.end());
    s += block(binary, {"CELLS 2 18", "", ScalarType::kInt32, 1, list});
  }
  s += block(binary, {"CELL_TYPES 2", "", ScalarType::kInt32, 1, {12, 12}});
  d.point_arrays = {
      {"SCALARS temperature %T 2\nLOOKUP_TABLE default", "int", ScalarType::kInt32, 2, ramp(24, -100000, 7919)},
      {"SCALARS density %T\nLOOKUP_TABLE my_table", "float", ScalarType::kFloat32, 1, ramp(12, 0.125, 0.0625)},
      {"VECTORS velocity %T", "double", ScalarType::kFloat64, 3, ramp(36, -1.0 / 3, 0.1)},
      {"NORMALS normal %T", "float", ScalarType::kFloat32, 3, ramp(36, 0.5, -0.25)},
      {"TENSORS stress %T", "float", ScalarType::kFloat32, 9, ramp(108, 1.5, 0.5)},
      {"TENSORS6 strain %T", "double", ScalarType::kFloat64, 6, ramp(72, 1e-3, 1.0 / 7)},
      {"FIELD FieldData 6\nnode%20id 1 12 %T", "unsigned_short", ScalarType::kUInt16, 1, ramp(12, 60000, 100)},
      {"big 1 12 %T", "vtktypeint64", ScalarType::kInt64, 1, ramp(12, -4.0e15, 1.0e14)},
      {"ul 2 12 %T", "unsigned_long", ScalarType::kUInt64, 2, ramp(24, 1.0e18, 3.0e15)},
      {"c 1 12 %T", "char", ScalarType::kInt8, 1, ramp(12, -100, 17)},
      {"uc 1 12 %T", "unsigned_char", ScalarType::kUInt8, 1, ramp(12, 250, -20)},
      {"sh 3 12 %T", "short", ScalarType::kInt16, 3, ramp(36, -30000, 1700)},
  };
  d.cell_arrays = {
      {"SCALARS region %T 1\nLOOKUP_TABLE default", "unsigned_int", ScalarType::kUInt32, 1, {4000000000.0, 7}},
      {"FIELD FieldData 1\nweight 1 2 %T", "double", ScalarType::kFloat64, 1, {0.1, 0.2}},
  };
  s += "POINT_DATA 12\n";
  for (const Array& a : d.point_arrays) s += block(binary, a);
  s += "CELL_DATA 2\n";
  for (const Array& a : d.cell_arrays) s += block(binary, a);
  return d;
}

std::vector<uint8_t> littleEndian(const Array& a) {
  std::string be;
  for (double v : a.values) putBigEndian(be, a.type, v);
  const size_t n = scalarSize(a.type);
  std::vector<uint8_t> out(be.size());
  for (size_t i = 0; i < be.size(); i += n)
    for (size_t k = 0; k < n; ++k) out[i + k] = static_cast<uint8_t>(be[i + n - 1 - k]);
  return out;
}

std::string fieldName(const std::string& header) {
  std::istringstream in(header.substr(header.find("FIELD") == 0 ? header.find('\n') + 1 : 0));
  std::string w1, w2;
  in >> w1;
  if (w1 == "SCALARS" || w1 == "VECTORS" || w1 == "NORMALS" || w1 == "TENSORS" || w1 == "TENSORS6") in >> w2;
  else w2 = w1;
  return w2 == "node%20id" ? "node id" : w2;
}

TEST(VtkLegacy, EveryAttributeKindAndTypeInEveryDialect) {
  const std::string dir = tempDir("vtk_legacy_dialects");
  TetMesh reference;
  bool have_reference = false;
  for (bool binary : {false, true}) {
    for (bool v51 : {false, true}) {
      SCOPED_TRACE(std::string(binary ? "BINARY" : "ASCII") + (v51 ? " 5.1" : " 3.0"));
      const Dataset d = makeDataset(binary, v51);
      const std::string path = dir + "/two_hexes_" + (binary ? "bin" : "ascii") + (v51 ? "_51" : "") + ".vtk";
      writeFile(path, d.text);
      auto r = importMesh({path}, ImportOptions{});
      ASSERT_TRUE(r.isOk()) << r.status().message();
      const TetMesh& m = r->mesh;
      EXPECT_EQ(m.numPoints(), 12u);
      EXPECT_EQ(m.numTets(), 12u);
      EXPECT_EQ(m.coord_type, ScalarType::kFloat64);
      EXPECT_EQ(m.coords[3 * 5 + 1], 0.6);
      ASSERT_EQ(m.point_fields.size(), d.point_arrays.size());
      for (size_t i = 0; i < d.point_arrays.size(); ++i) {
        const Array& a = d.point_arrays[i];
        const Field& f = m.point_fields[i];
        EXPECT_EQ(f.name, fieldName(a.header));
        EXPECT_EQ(f.type, a.type) << f.name;
        EXPECT_EQ(f.components, a.comps) << f.name;
        EXPECT_EQ(f.bytes, littleEndian(a)) << f.name;
      }
      ASSERT_EQ(m.cell_fields.size(), 2u);
      EXPECT_EQ(m.cell_fields[0].name, "region");
      EXPECT_EQ(m.cell_fields[0].type, ScalarType::kUInt32);
      EXPECT_EQ(m.cell_fields[1].name, "weight");
      for (size_t t = 0; t < 12; ++t) {
        double cx = 0;
        for (uint32_t v : m.tets[t]) cx += m.point(v)[0] / 4;
        EXPECT_EQ(m.cell_fields[0].data<uint32_t>()[t], cx < 0.5 ? 4000000000u : 7u);
        EXPECT_EQ(m.cell_fields[1].data<double>()[t], cx < 0.5 ? 0.1 : 0.2);
      }
      const MeshStats s = computeMeshStats(m);
      EXPECT_EQ(s.boundary_faces, 20u);
      EXPECT_EQ(s.non_manifold_faces, 0u);
      EXPECT_DOUBLE_EQ(s.total_volume, 2 * 0.5 * 0.5 * 0.25);
      // Every dialect gives the same mesh, bit for bit.
      if (!have_reference) {
        reference = m;
        have_reference = true;
      } else {
        EXPECT_EQ(m.coords, reference.coords);
        EXPECT_EQ(m.tets, reference.tets);
        for (size_t i = 0; i < m.point_fields.size(); ++i)
          EXPECT_EQ(m.point_fields[i].bytes, reference.point_fields[i].bytes);
      }
    }
  }
}

void expectError(const std::string& path, const std::string& text, const std::string& part) {
  writeFile(path, text);
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_FALSE(r.isOk()) << "accepted: " << path;
  EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(part), std::string::npos) << r.status().message() << "\nlacks: " << part;
}

// What the reader passes over is said: METADATA blocks (component names, information keys) and
// LOOKUP_TABLE definitions (colour tables).
TEST(VtkLegacy, SkippedMetadataAndLookupTablesAreSaid) {
  const std::string dir = tempDir("vtk-legacy-skipped");
  writeFile(dir + "/m.vtk",
            "# vtk DataFile Version 5.1\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n"
            "0 0 0 1 0 0 0 1 0 0 0 1\nMETADATA\nINFORMATION 0\n\n"
            "CELLS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2 3\nCELL_TYPES 1\n10\n"
            "POINT_DATA 4\nSCALARS s float 1\nLOOKUP_TABLE colours\n0 1 2 3\n"
            "LOOKUP_TABLE colours 2\n0 0 0 1 1 1 1 1\n");
  auto r = importMesh({dir + "/m.vtk"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 1u);
  ASSERT_EQ(r->mesh.point_fields.size(), 1u);
  EXPECT_EQ(r->report.warnings,
            (std::vector<std::string>{
                "skipped 1 METADATA block (line 7): component names and information keys of arrays, not read",
                "skipped 1 LOOKUP_TABLE definition ('colours'): colour tables are not read"}));
}

// COMPONENT_NAMES in a METADATA block has one line per component of the array, empty for a component
// without a name (as vtkDataWriter writes it): that line does not end the block. Arrays follow it.
TEST(VtkLegacy, MetadataWithAnUnnamedComponent) {
  const std::string dir = tempDir("vtk-legacy-component-names");
  for (const char* mode : {"ASCII", "BINARY"}) {
    SCOPED_TRACE(mode);
    const bool binary = std::string(mode) == "BINARY";
    std::string vel = "1 2 3 4 5 6 7 8 9 10 11 12";
    if (binary) {
      vel.clear();
      for (int i = 1; i <= 12; ++i) {
        const float v = static_cast<float>(i);
        uint32_t u;
        std::memcpy(&u, &v, 4);
        for (int b = 3; b >= 0; --b) vel += static_cast<char>(u >> (8 * b));
      }
    }
    writeFile(dir + "/m.vtk",
              std::string("# vtk DataFile Version 5.1\nt\n") + mode +
                  "\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
                  "0 0 0 1 0 0 0 1 0 0 0 1\n"
                  "CELLS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2 3\nCELL_TYPES 1\n10\n"
                  "POINT_DATA 4\nFIELD FieldData 2\nvel 3 4 float\n" +
                  vel +
                  "\nMETADATA\nCOMPONENT_NAMES\nvx\n\nvz\nINFORMATION 1\nNAME UNITS_LABEL LOCATION vtkDataArray\n"
                  "DATA m/s\n\n"
                  "t 1 4 double\n0.5 1.5 2.5 3.5\n");
    if (binary) {
      // The binary dialect: the points and the last array as big-endian values too.
      std::string text = test::readFile(dir + "/m.vtk");
      auto be = [](const std::vector<double>& values) {
        std::string out;
        for (double v : values) {
          uint64_t u;
          std::memcpy(&u, &v, 8);
          for (int b = 7; b >= 0; --b) out += static_cast<char>(u >> (8 * b));
        }
        return out;
      };
      text.replace(text.find("0 0 0 1 0 0 0 1 0 0 0 1"), 23, be({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}));
      text.replace(text.find("0.5 1.5 2.5 3.5"), 15, be({0.5, 1.5, 2.5, 3.5}));
      text.replace(text.find("0 4\nCONNECTIVITY"), 3, std::string("\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\4", 16));
      text.replace(text.find("0 1 2 3\nCELL_TYPES"), 7,
                   std::string("\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\1\0\0\0\0\0\0\0\2\0\0\0\0\0\0\0\3", 32));
      text.replace(text.find("10\nPOINT_DATA"), 2, std::string("\0\0\0\x0a", 4));
      writeFile(dir + "/m.vtk", text);
    }
    auto r = importMesh({dir + "/m.vtk"}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->mesh.numTets(), 1u);
    ASSERT_EQ(r->mesh.point_fields.size(), 2u);
    const Field& v = r->mesh.point_fields[0];
    const Field& t = r->mesh.point_fields[1];
    EXPECT_EQ(v.name, "vel");
    ASSERT_EQ(v.components, 3u);
    EXPECT_EQ(v.get(3, 2), 12.0);
    EXPECT_EQ(t.name, "t");
    EXPECT_EQ(t.get(3, 0), 3.5);
  }
}

TEST(VtkLegacy, TruncatedBinaryDataFailsCleanlyAtEveryCut) {
  const std::string dir = tempDir("vtk_legacy_cut");
  const std::string text = makeDataset(true, false).text;
  const size_t points_at = text.find("POINTS");
  // Cut inside the binary POINTS block: the message says so.
  expectError(dir + "/cut_points.vtk", text.substr(0, points_at + 40), "file ends inside the binary data of POINTS");
  // Every other prefix: an error naming the file, never a crash, never success with partial data.
  for (size_t cut = 0; cut + 1 < text.size(); cut += 5) {
    const std::string path = dir + "/cut.vtk";
    writeFile(path, text.substr(0, cut));
    auto r = importVtkLegacy(path, ImportOptions{});
    if (r.isOk()) {
      // A cut between two whole attribute arrays leaves a valid, shorter file; never a partial mesh.
      EXPECT_GE(cut, text.find("POINT_DATA")) << "accepted a prefix of " << cut << " bytes";
      EXPECT_EQ(r->mesh.numTets(), 12u);
      continue;
    }
    EXPECT_EQ(r.status().message().rfind(path, 0), 0u) << r.status().message();
  }
}

TEST(VtkLegacy, RandomlyCorruptedFilesNeverCrash) {
  const std::string dir = tempDir("vtk_legacy_corrupt");
  const std::string path = dir + "/corrupt.vtk";
  std::mt19937 rng(777);
  for (bool binary : {true, false}) {
    const std::string source = makeDataset(binary, !binary).text;
    for (int it = 0; it < 150; ++it) {
      std::string text = source;
      const int changes = 1 + static_cast<int>(rng() % 4);
      for (int c = 0; c < changes; ++c) text[rng() % text.size()] = static_cast<char>(rng() % 256);
      writeFile(path, text);
      auto r = importVtkLegacy(path, ImportOptions{});
      if (!r.isOk()) {
        EXPECT_EQ(r.status().message().rfind(path, 0), 0u) << r.status().message();
      }
    }
  }
}

TEST(VtkLegacy, RejectsOtherDatasetsCellTypesAndBadIndices) {
  const std::string dir = tempDir("vtk_legacy_bad");
  expectError(dir + "/poly.vtk", "# vtk DataFile Version 3.0\nsurface\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n",
              "DATASET POLYDATA is not supported (it holds no volume cells");
  const std::string head =
      "# vtk DataFile Version 3.0\ntri\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n"
      "0 0 0 1 0 0 0 1 0 0 0 1\n";
  expectError(dir + "/convex.vtk", head + "CELLS 2 10\n4 0 1 2 3\n4 0 1 2 3\nCELL_TYPES 2\n41 10\n",
              "1 cell of type 41 (VTK_CONVEX_POINT_SET)");
  expectError(dir + "/half.vtk", head + "CELLS 1 5\n4 0 1 2 3\n", "CELLS without a CELL_TYPES section");
  // The dataset's own FIELD arrays (VTK writes TIME there) are read past with a warning that names them.
  writeFile(dir + "/time.vtk",
            "# vtk DataFile Version 3.0\ntime\nASCII\nDATASET UNSTRUCTURED_GRID\nFIELD FieldData 2\n"
            "TIME 1 1 double\n1.5\nCYCLE 1 1 int\n7\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\n"
            "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n");
  auto timed = importMesh({dir + "/time.vtk"}, ImportOptions{});
  ASSERT_TRUE(timed.isOk()) << timed.status().message();
  EXPECT_EQ(timed->mesh.numTets(), 1u);
  EXPECT_EQ(timed->report.warnings,
            std::vector<std::string>{
                "line 5: the dataset's FIELD arrays ('TIME', 'CYCLE') are not kept: they belong to no point or cell"});
  // No cells at all (VTK's writer then leaves out CELLS and CELL_TYPES): an empty mesh, as from a .vtu.
  writeFile(dir + "/none.vtk",
            "# vtk DataFile Version 5.1\nnone\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 float\n0 0 0 1 0 0\n");
  auto none = importMesh({dir + "/none.vtk"}, ImportOptions{});
  ASSERT_TRUE(none.isOk()) << none.status().message();
  EXPECT_EQ(none->mesh.numPoints(), 2u);
  EXPECT_EQ(none->mesh.numTets(), 0u);
  expectError(dir + "/tri.vtk", head + "CELLS 2 8\n3 0 1 2\n3 0 2 3\nCELL_TYPES 2\n5 5\n",
              "no volume cells, only 2 cells of type 5 (VTK_TRIANGLE)");
  expectError(dir + "/range.vtk", head + "CELLS 1 5\n4 0 1 2 4\nCELL_TYPES 1\n10\n",
              "cell 0 refers to point 4 but there are 4 points");
  expectError(dir + "/short.vtk", head + "CELLS 1 5\n4 0 1 2\n", "file ends");
  expectError(dir + "/word.vtk", head + "CELLS 1 5\n4 0 1 x 3\nCELL_TYPES 1\n10\n", "is not a int32");
  // Bytes of a damaged file are not echoed raw (they would not be UTF-8): shown as '?'.
  expectError(dir + "/byte.vtk", head + "CELLS 1 5\n4 0 1 \xff 3\nCELL_TYPES 1\n10\n", "is not a int32: '?'");
  expectError(dir + "/keyword.vtk", head + "CELLS 1 5\n4 0 1 2 3\nCELL_TYP\xc9S 1\n10\n",
              "unexpected keyword 'CELL_TYP?S'");
  expectError(dir + "/pd.vtk", head + "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 5\n",
              "POINT_DATA 5 does not match the 4 points");
}

// The 3D structured datasets: their hexahedral cells (i fastest, as CELL_DATA lists them) are split
// like PLOT3D's, their point and cell data kept. A curvilinear STRUCTURED_GRID (ASCII), a
// RECTILINEAR_GRID (BINARY, float axes) and a STRUCTURED_POINTS image with a bit array, in both
// encodings.
TEST(VtkLegacy, StructuredDatasetsBecomeSplitHexahedra) {
  const std::string dir = tempDir("vtk_legacy_structured");
  for (const int split : {5, 6}) {
    ImportOptions options;
    options.split = split;
    {
      // 3 x 3 x 2 points, sheared in x by z: 4 cells of volume 1 each.
      std::string s =
          "# vtk DataFile Version 3.0\ncurvilinear\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS 3 3 2\n"
          "POINTS 18 double\n";
      for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 3; ++j)
          for (int i = 0; i < 3; ++i)
            s += std::to_string(i + 0.5 * k) + " " + std::to_string(j) + " " + std::to_string(k) + "\n";
      s += "CELL_DATA 4\nSCALARS zone int 1\nLOOKUP_TABLE default\n10 11 12 13\n";
      s += "POINT_DATA 18\nSCALARS t float\nLOOKUP_TABLE default\n";
      for (int v = 0; v < 18; ++v) s += std::to_string(v) + ".5\n";
      writeFile(dir + "/sg.vtk", s);
      auto r = importMesh({dir + "/sg.vtk"}, options);
      ASSERT_TRUE(r.isOk()) << r.status().message();
      const TetMesh& m = r->mesh;
      EXPECT_EQ(m.numPoints(), 18u);
      EXPECT_EQ(m.numTets(), 4u * split);
      EXPECT_EQ(m.coord_type, ScalarType::kFloat64);
      EXPECT_DOUBLE_EQ(m.point(7)[0], 1.0);   // (i, j, k) = (1, 2, 0)
      EXPECT_DOUBLE_EQ(m.point(10)[0], 1.5);  // (1, 0, 1)
      const MeshStats st = computeMeshStats(m);
      EXPECT_NEAR(st.total_volume, 4.0, 1e-12);
      EXPECT_EQ(st.inverted, 0u);
      EXPECT_EQ(st.non_manifold_faces, 0u);
      EXPECT_EQ(st.boundary_faces, 2u * (2 * 4 + 4 * 2));  // top and bottom 4 quads, 4 sides of 2
      ASSERT_EQ(m.point_fields.size(), 1u);
      EXPECT_EQ(m.point_fields[0].data<float>()[17], 17.5f);
      ASSERT_EQ(m.cell_fields.size(), 1u);
      // Each tetrahedron has its cell's zone: the cell (0, 1, 0) is zone 12 and lies in x < 1, y > 1.
      const int32_t* zone = m.cell_fields[0].data<int32_t>();
      for (size_t t = 0; t < m.numTets(); ++t) {
        double c[3] = {0, 0, 0};
        for (uint32_t v : m.tets[t])
          for (int a = 0; a < 3; ++a) c[a] += m.point(v)[a] / 4;
        const int i = c[0] - 0.5 * c[2] > 1 ? 1 : 0, j = c[1] > 1 ? 1 : 0;
        EXPECT_EQ(zone[t], 10 + i + 2 * j) << "tetrahedron " << t;
      }
    }
    {
      // Rectilinear, BINARY: axes of 4, 2 and 3 float coordinates, unevenly spaced.
      std::string s = "# vtk DataFile Version 3.0\nrectilinear\nBINARY\nDATASET RECTILINEAR_GRID\nDIMENSIONS 4 2 3\n";
      s += "X_COORDINATES 4 float\n";
      for (double v : {0.0, 0.5, 2.0, 2.25}) putBigEndian(s, ScalarType::kFloat32, v);
      s += "\nY_COORDINATES 2 float\n";
      for (double v : {-1.0, 1.0}) putBigEndian(s, ScalarType::kFloat32, v);
      s += "\nZ_COORDINATES 3 float\n";
      for (double v : {0.0, 0.125, 1.0}) putBigEndian(s, ScalarType::kFloat32, v);
      s += "\nPOINT_DATA 24\nSCALARS id short\nLOOKUP_TABLE default\n";
      for (int v = 0; v < 24; ++v) putBigEndian(s, ScalarType::kInt16, v);
      s += "\n";
      writeFile(dir + "/rg.vtk", s);
      auto r = importMesh({dir + "/rg.vtk"}, options);
      ASSERT_TRUE(r.isOk()) << r.status().message();
      const TetMesh& m = r->mesh;
      EXPECT_EQ(m.numPoints(), 24u);
      EXPECT_EQ(m.numTets(), 3u * 1 * 2 * split);
      EXPECT_EQ(m.coord_type, ScalarType::kFloat32);
      EXPECT_DOUBLE_EQ(m.point(4 * 1 + 8 * 2 + 3)[0], 2.25);
      EXPECT_DOUBLE_EQ(m.point(4 * 1 + 8 * 2 + 3)[1], 1.0);
      EXPECT_DOUBLE_EQ(m.point(4 * 1 + 8 * 2 + 3)[2], 1.0);
      EXPECT_NEAR(computeMeshStats(m).total_volume, 2.25 * 2.0 * 1.0, 1e-12);
      EXPECT_EQ(m.point_fields[0].data<int16_t>()[23], 23);
    }
    for (const bool binary : {false, true}) {
      // An image: origin (1, 2, 3), spacing (0.5, 0.25, 2), 3 x 2 x 2 points, a bit array of 12.
      std::string s = "# vtk DataFile Version 2.0\nimage\n" + std::string(binary ? "BINARY" : "ASCII") +
                      "\nDATASET STRUCTURED_POINTS\nDIMENSIONS 3 2 2\nORIGIN 1 2 3\nSPACING 0.5 0.25 2\n"
                      "POINT_DATA 12\nSCALARS mask bit\nLOOKUP_TABLE default\n";
      const int bits[12] = {1, 0, 1, 1, 0, 0, 1, 0, 0, 0, 0, 1};
      if (binary) {
        s += static_cast<char>(0xB2);  // 1011 0010
        s += static_cast<char>(0x10);  // 0001 ....
        s += "\n";
      } else {
        for (int b : bits) s += std::to_string(b) + " ";
        s += "\n";
      }
      writeFile(dir + "/sp.vtk", s);
      auto r = importMesh({dir + "/sp.vtk"}, options);
      ASSERT_TRUE(r.isOk()) << r.status().message();
      const TetMesh& m = r->mesh;
      EXPECT_EQ(m.numTets(), 2u * split);
      EXPECT_DOUBLE_EQ(m.point(11)[0], 2.0);
      EXPECT_DOUBLE_EQ(m.point(11)[1], 2.25);
      EXPECT_DOUBLE_EQ(m.point(11)[2], 5.0);
      EXPECT_NEAR(computeMeshStats(m).total_volume, 1.0 * 0.25 * 2.0, 1e-12);
      ASSERT_EQ(m.point_fields.size(), 1u);
      ASSERT_EQ(m.point_fields[0].type, ScalarType::kUInt8);
      for (int v = 0; v < 12; ++v) EXPECT_EQ(m.point_fields[0].data<uint8_t>()[v], bits[v]) << binary << " " << v;
    }
  }
}

TEST(VtkLegacy, StructuredDatasetsRejectWhatTheyCannotHold) {
  const std::string dir = tempDir("vtk_legacy_structured_bad");
  const std::string sg = "# vtk DataFile Version 3.0\ng\nASCII\nDATASET STRUCTURED_GRID\n";
  expectError(dir + "/flat.vtk", sg + "DIMENSIONS 4 3 1\nPOINTS 12 float\n",
              "DIMENSIONS 4 3 1: a structured dataset with fewer than 2 points along an axis has no volume cells");
  expectError(dir + "/count.vtk", sg + "DIMENSIONS 2 2 2\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 1 1 0\n",
              "POINTS 4 does not match DIMENSIONS (2 x 2 x 2 = 8 points)");
  expectError(dir + "/nodims.vtk", sg + "POINTS 1 float\n0 0 0\n", "STRUCTURED_GRID without DIMENSIONS");
  expectError(dir + "/early.vtk", sg + "POINT_DATA 8\n", "POINT_DATA before DIMENSIONS");
  const std::string sp = "# vtk DataFile Version 3.0\ni\nASCII\nDATASET STRUCTURED_POINTS\n";
  // A few bytes cannot describe data for a billion implicit points.
  expectError(dir + "/huge.vtk", sp + "DIMENSIONS 1000 1000 1000\n", "declare more points than a file of");
  expectError(dir + "/cd.vtk", sp + "DIMENSIONS 3 3 3\nCELL_DATA 27\n", "CELL_DATA 27 does not match the 8 cells");
  const std::string rg = "# vtk DataFile Version 3.0\nr\nASCII\nDATASET RECTILINEAR_GRID\nDIMENSIONS 2 2 2\n";
  expectError(dir + "/noz.vtk", rg + "X_COORDINATES 2 float\n0 1\nY_COORDINATES 2 float\n0 1\n",
              "RECTILINEAR_GRID without Z_COORDINATES");
  expectError(dir + "/axis.vtk", rg + "X_COORDINATES 3 float\n0 1 2\n", "X_COORDINATES 3 does not match DIMENSIONS");
  // Axes before DIMENSIONS are checked when the grid is built.
  expectError(dir + "/late.vtk",
              "# vtk DataFile Version 3.0\nr\nASCII\nDATASET RECTILINEAR_GRID\nX_COORDINATES 3 float\n0 1 2\n"
              "Y_COORDINATES 2 float\n0 1\nZ_COORDINATES 2 float\n0 1\nDIMENSIONS 2 2 2\n",
              "X_COORDINATES has 3 values but DIMENSIONS 2 along this axis");
}

TEST(VtkLegacy, QuadraticTetraKeepsCornersAndCountsMidEdgePoints) {
  const std::string dir = tempDir("vtk_legacy_quadratic");
  const std::string path = dir + "/q.vtk";
  writeFile(path,
            "# vtk DataFile Version 3.0\nq\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 10 double\n"
            "0 0 0 1 0 0 0 1 0 0 0 1 .5 0 0 .5 .5 0 0 .5 0 0 0 .5 .5 0 .5 0 .5 .5\n"
            "CELLS 1 11\n10 0 1 2 3 4 5 6 7 8 9\nCELL_TYPES 1\n24\n");
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 1u);
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("1 quadratic tetrahedra"), std::string::npos);
  EXPECT_EQ(computeMeshStats(r->mesh).unreferenced_points, 6u);
}

// The shape of what MMG (and Gmsh, through meshio) writes: BINARY, a METADATA block after POINTS,
// feature edges and boundary triangles listed with the tetrahedra, and a cell attribute over all of
// them. The lower-dimensional cells are skipped; the attribute follows the tetrahedra.
TEST(VtkLegacy, BinaryMixedCellsWithMetadataKeepTheTetrahedra) {
  const std::string dir = tempDir("vtk_legacy_mixed");
  std::string s = "# vtk DataFile Version 4.2\nvtk output\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n";
  const double xyz[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  for (double v : xyz) putBigEndian(s, ScalarType::kFloat32, v);
  s += "\nMETADATA\nINFORMATION 2\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0 1.73205 \n"
       "NAME L2_NORM_FINITE_RANGE LOCATION vtkDataArray\nDATA 2 0 1.73205 \n\n";
  // An edge, a triangle, a tetrahedron, a triangle, a tetrahedron.
  s += "CELLS 5 21\n";
  for (int v : {2, 0, 1, 3, 0, 1, 2, 4, 0, 1, 2, 3, 3, 1, 2, 3, 4, 1, 2, 3, 4}) putBigEndian(s, ScalarType::kInt32, v);
  s += "\nCELL_TYPES 5\n";
  for (int t : {3, 5, 10, 5, 10}) putBigEndian(s, ScalarType::kInt32, t);
  s += "\nCELL_DATA 5\nSCALARS medit:ref int 1\nLOOKUP_TABLE default\n";
  for (int r : {7, 8, 1, 9, 2}) putBigEndian(s, ScalarType::kInt32, r);
  s += "\n";
  writeFile(dir + "/mmg.vtk", s);
  auto r = importMesh({dir + "/mmg.vtk"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numPoints(), 5u);
  ASSERT_EQ(r->mesh.numTets(), 2u);
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r->mesh.cell_fields[0].name, "medit:ref");
  EXPECT_EQ(r->mesh.cell_fields[0].data<int32_t>()[0], 1);
  EXPECT_EQ(r->mesh.cell_fields[0].data<int32_t>()[1], 2);
  ASSERT_EQ(r->report.warnings.size(), 2u);
  EXPECT_EQ(r->report.warnings[0].rfind("skipped 1 METADATA block (line ", 0), 0u) << r->report.warnings[0];
  EXPECT_NE(r->report.warnings[1].find("skipped 3 cells of lower dimension (1 cell of type 3 (VTK_LINE), 2 cells of "
                                       "type 5 (VTK_TRIANGLE))"),
            std::string::npos)
      << r->report.warnings[1];
}

// What VTK writes for data that came from Exodus: dataset FIELD data with char and string arrays,
// GLOBAL_IDS and PEDIGREE_IDS attributes, and a FIELD array of strings among the point data.
TEST(VtkLegacy, IdsAndStringArraysAsVtkWritesThem) {
  const std::string dir = tempDir("vtk_legacy_ids");
  const std::string text =
      "# vtk DataFile Version 3.0\nvtk output\nASCII\nDATASET UNSTRUCTURED_GRID\n"
      "FIELD FieldData 2\nQA_Records 2 1 char\n65 66\nInfo%20Records 1 3 string\nfirst%20line\n\nthird\n"
      "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1e-50\n"
      "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n"
      "CELL_DATA 1\nPEDIGREE_IDS PedigreeElementId int\n271\nGLOBAL_IDS GlobalElementId vtkIdType\n5\n"
      "POINT_DATA 4\nGLOBAL_IDS GlobalNodeId int\n11 12 13 14\n"
      "FIELD FieldData 3\nNames 1 4 string\na\nb\n\nd\nNULL_ARRAY\nTemp 1 4 double\n0.5 1.5 2.5 3.5\n"
      "PEDIGREE_IDS NodeNames string\nw\nx\ny\nz\n";
  writeFile(dir + "/ids.vtk", text);
  auto r = importMesh({dir + "/ids.vtk"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  ASSERT_EQ(m.numTets(), 1u);
  // A float too small for a float32 reads as strtof reads it: zero, not an error.
  EXPECT_EQ(m.coords[11], 0.0);
  ASSERT_EQ(m.point_fields.size(), 2u);
  EXPECT_EQ(m.point_fields[0].name, "GlobalNodeId");
  EXPECT_EQ(m.point_fields[0].type, ScalarType::kInt32);
  EXPECT_EQ(m.point_fields[0].data<int32_t>()[3], 14);
  EXPECT_EQ(m.point_fields[1].name, "Temp");
  EXPECT_EQ(m.point_fields[1].data<double>()[2], 2.5);
  ASSERT_EQ(m.cell_fields.size(), 2u);
  EXPECT_EQ(m.cell_fields[0].name, "PedigreeElementId");
  EXPECT_EQ(m.cell_fields[0].data<int32_t>()[0], 271);
  EXPECT_EQ(m.cell_fields[1].name, "GlobalElementId");
  EXPECT_EQ(m.cell_fields[1].type, ScalarType::kInt32);  // VTK's reader and writer: vtkIdType as int
  ASSERT_EQ(r->report.warnings.size(), 3u);
  EXPECT_EQ(r->report.warnings[0],
            "line 5: the dataset's FIELD arrays ('QA_Records', 'Info Records') are not kept: "
            "they belong to no point or cell");
  EXPECT_NE(r->report.warnings[1].find("skipped FIELD array Names (string)"), std::string::npos)
      << r->report.warnings[1];
  EXPECT_NE(r->report.warnings[2].find("skipped PEDIGREE_IDS NodeNames (string)"), std::string::npos)
      << r->report.warnings[2];

  // More cells than the cell list could hold fails before anything is allocated for them.
  std::string many = text;
  many.replace(many.find("CELLS 1 5"), 9, "CELLS 4294967296 5");
  writeFile(dir + "/many.vtk", many);
  auto mc = importMesh({dir + "/many.vtk"}, ImportOptions{});
  ASSERT_FALSE(mc.isOk());
  EXPECT_NE(mc.status().message().find("many.vtk:14: CELLS: 4294967296 cells cannot fit in a list of 5 numbers"),
            std::string::npos)
      << mc.status().message();

  // A string array cut short names the file, the line and the array.
  writeFile(dir + "/cut.vtk", text.substr(0, text.find("\nd\nNULL_ARRAY")));
  auto cut = importMesh({dir + "/cut.vtk"}, ImportOptions{});
  ASSERT_FALSE(cut.isOk());
  EXPECT_NE(cut.status().message().find("cut.vtk:"), std::string::npos) << cut.status().message();
  EXPECT_NE(cut.status().message().find("strings of FIELD array Names"), std::string::npos) << cut.status().message();
}

// The same in BINARY, as vtkDataWriter writes strings there: each a big-endian length header whose
// first byte's two high bits give its size (3: 1 byte, 2: 2, 1: 4, 0: 8) and then the bytes, which
// may hold anything, newlines included.
std::string binaryString(const std::string& text, int header_bytes) {
  std::string out;
  const uint64_t n = text.size();
  const unsigned tag = header_bytes == 1 ? 3 : header_bytes == 2 ? 2 : header_bytes == 4 ? 1 : 0;
  for (int b = header_bytes - 1; b >= 0; --b) {
    unsigned char c = static_cast<unsigned char>(n >> (8 * b));
    if (b == header_bytes - 1 && header_bytes < 8) c = static_cast<unsigned char>(c | tag << 6);
    out.push_back(static_cast<char>(c));
  }
  return out + text;
}

std::string bigEndianFloats(std::initializer_list<float> values) {
  std::string out;
  for (float v : values) putBigEndian(out, ScalarType::kFloat32, v);
  return out;
}

std::string bigEndianInts(std::initializer_list<int32_t> values) {
  std::string out;
  for (int32_t v : values) putBigEndian(out, ScalarType::kInt32, v);
  return out;
}

TEST(VtkLegacy, BinaryStringArraysAreSkippedByTheirLengths) {
  const std::string dir = tempDir("vtk_legacy_binary_strings");
  const std::string names = binaryString("a", 1) + binaryString("two\nlines", 2) + binaryString("", 4) +
                            binaryString(std::string(70, 'x'), 8);
  const std::string pedigree = binaryString("w", 1) + binaryString("x y", 1) + binaryString("\xC0\xFF", 2) +
                               binaryString(std::string(300, 'z'), 2);
  const std::string text =
      "# vtk DataFile Version 3.0\nvtk output\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
      "FIELD FieldData 1\nInfo%20Records 1 2 string\n" +
      binaryString("first", 1) + binaryString("second", 1) + "\n" + "POINTS 4 float\n" +
      bigEndianFloats({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}) + "\n" + "CELLS 1 5\n" + bigEndianInts({4, 0, 1, 2, 3}) +
      "\nCELL_TYPES 1\n" + bigEndianInts({10}) + "\n" + "POINT_DATA 4\nFIELD FieldData 2\nNames 1 4 string\n" + names +
      "\nTemp 1 4 float\n" + bigEndianFloats({0.5, 1.5, 2.5, 3.5}) + "\nPEDIGREE_IDS NodeNames string\n" + pedigree +
      "\n" + "SCALARS after float 1\nLOOKUP_TABLE default\n" + bigEndianFloats({-1, -2, -3, -4}) + "\n";
  writeFile(dir + "/strings.vtk", text);
  auto r = importMesh({dir + "/strings.vtk"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  ASSERT_EQ(m.numTets(), 1u);
  // The arrays after each string array are read from the right bytes.
  ASSERT_EQ(m.point_fields.size(), 2u);
  EXPECT_EQ(m.point_fields[0].name, "Temp");
  EXPECT_EQ(m.point_fields[0].data<float>()[3], 3.5f);
  EXPECT_EQ(m.point_fields[1].name, "after");
  EXPECT_EQ(m.point_fields[1].data<float>()[0], -1.0f);
  EXPECT_EQ(m.point_fields[1].data<float>()[3], -4.0f);
  ASSERT_EQ(r->report.warnings.size(), 3u);
  EXPECT_EQ(r->report.warnings[0].find("line 5: the dataset's FIELD arrays ('Info Records')"), 0u);
  EXPECT_NE(r->report.warnings[1].find("skipped FIELD array Names (string)"), std::string::npos);
  EXPECT_NE(r->report.warnings[2].find("skipped PEDIGREE_IDS NodeNames (string)"), std::string::npos);

  // A length that runs past the end, and a file cut inside a length header, name the byte offset.
  const size_t names_at = text.find(names);
  std::string bad = text;
  bad[names_at] = static_cast<char>(0xC0 | 63);  // "a" claims 63 bytes
  bad.resize(names_at + 40);
  writeFile(dir + "/long.vtk", bad);
  auto l = importMesh({dir + "/long.vtk"}, ImportOptions{});
  ASSERT_FALSE(l.isOk());
  EXPECT_NE(l.status().message().find("long.vtk: byte offset " + std::to_string(names_at) +
                                      ": string 1 of FIELD array Names is 63 bytes long, past the end of the file"),
            std::string::npos)
      << l.status().message();
  const size_t long_at = names_at + names.size() - 70 - 8;
  writeFile(dir + "/cut.vtk", text.substr(0, long_at + 3));
  auto c = importMesh({dir + "/cut.vtk"}, ImportOptions{});
  ASSERT_FALSE(c.isOk());
  EXPECT_NE(c.status().message().find("cut.vtk: byte offset " + std::to_string(long_at) +
                                      ": file ends inside the length of string 4 of FIELD array Names"),
            std::string::npos)
      << c.status().message();
}

// vtkDataWriter writes a vtkIdType array as 32-bit ints (its reader reads them so), in BINARY too; a
// METADATA block may follow it. Bits are packed eight to a byte, the first in the high bit; a
// vtkSignedCharArray is "signed_char".
TEST(VtkLegacy, IdTypeArraysAreThirtyTwoBitsAndBitsArePacked) {
  const std::string dir = tempDir("vtk_legacy_idtype");
  auto be64 = [](std::initializer_list<int64_t> values) {
    std::string out;
    for (int64_t v : values)
      for (int b = 7; b >= 0; --b) out.push_back(static_cast<char>((static_cast<uint64_t>(v) >> (8 * b)) & 0xFF));
    return out;
  };
  const std::string text =
      "# vtk DataFile Version 5.1\nvtk output\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
      "POINTS 4 float\n" +
      bigEndianFloats({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}) + "\nCELLS 2 4\nOFFSETS vtktypeint64\n" + be64({0, 4}) +
      "\nCONNECTIVITY vtktypeint64\n" + be64({0, 1, 2, 3}) + "\nCELL_TYPES 1\n" + bigEndianInts({10}) +
      "\n\nPOINT_DATA 4\nFIELD FieldData 5\nflags 1 4 bit\n\x50\nMETADATA\nINFORMATION 0\n\n"
      "ids 1 4 vtkIdType\n" +
      bigEndianInts({7, -1, 9, 100000}) +
      "\nMETADATA\nINFORMATION 0\n\n"
      "Temp 1 4 float\n" +
      bigEndianFloats({0.5, 1.5, 2.5, 3.5}) + "\nsc 1 4 signed_char\n\xFF\x02\xFD\x04\nw 1 4 vtktypeuint16\n" +
      std::string("\x01\x00\x00\x02\xFF\xFF\x00\x04\n", 9);
  writeFile(dir + "/ids.vtk", text);
  auto r = importMesh({dir + "/ids.vtk"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  ASSERT_EQ(m.numTets(), 1u);
  ASSERT_EQ(m.point_fields.size(), 5u);
  EXPECT_EQ(m.point_fields[0].name, "flags");
  EXPECT_EQ(m.point_fields[0].bytes, (std::vector<uint8_t>{0, 1, 0, 1}));
  EXPECT_EQ(m.point_fields[1].name, "ids");
  EXPECT_EQ(m.point_fields[1].type, ScalarType::kInt32);
  EXPECT_EQ(m.point_fields[1].data<int32_t>()[1], -1);
  EXPECT_EQ(m.point_fields[1].data<int32_t>()[3], 100000);
  EXPECT_EQ(m.point_fields[2].name, "Temp");
  EXPECT_EQ(m.point_fields[2].data<float>()[3], 3.5f);
  EXPECT_EQ(m.point_fields[3].name, "sc");  // vtkSignedCharArray
  // A name in Latin-1 ("caf%E9" as VTK %-encodes it) becomes UTF-8, the .gtn format's strings.
  std::string latin = text;
  latin.replace(latin.find("\nTemp 1 4"), 9, "\ncaf%E9 1 4");
  writeFile(dir + "/latin.vtk", latin);
  auto l = importMesh({dir + "/latin.vtk"}, ImportOptions{});
  ASSERT_TRUE(l.isOk()) << l.status().message();
  EXPECT_EQ(l->mesh.point_fields[2].name, "caf\xC3\xA9");
  EXPECT_EQ(m.point_fields[3].type, ScalarType::kInt8);
  EXPECT_EQ(m.point_fields[3].data<int8_t>()[2], -3);
  EXPECT_EQ(m.point_fields[4].type, ScalarType::kUInt16);  // vtktypeuint16, as meshio writes it
  EXPECT_EQ(m.point_fields[4].data<uint16_t>()[0], 256u);
  EXPECT_EQ(m.point_fields[4].data<uint16_t>()[2], 65535u);
}

// COLOR_SCALARS: bytes in BINARY files, floats in [0, 1] in ASCII ones, which VTK's reader turns into
// the same bytes (255 v + 0.5, truncated).
TEST(VtkLegacy, ColorScalarsAreBytesInBothDialects) {
  const std::string dir = tempDir("vtk_legacy_colors");
  const std::string head = "# vtk DataFile Version 4.2\nc\n";
  const std::string mesh_ascii =
      "ASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\n"
      "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n";
  writeFile(dir + "/a.vtk",
            head + mesh_ascii + "POINT_DATA 4\nCOLOR_SCALARS rgb 3\n0 0.5 1 0.2 0.4 0.6 0.001 0.999 0.25 1 1 1\n");
  const std::string mesh_binary = "BINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n" +
                                  bigEndianFloats({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}) + "\nCELLS 1 5\n" +
                                  bigEndianInts({4, 0, 1, 2, 3}) + "\nCELL_TYPES 1\n" + bigEndianInts({10}) + "\n";
  const uint8_t rgb[12] = {0, 128, 255, 51, 102, 153, 0, 255, 64, 255, 255, 255};
  writeFile(dir + "/b.vtk", head + mesh_binary + "POINT_DATA 4\nCOLOR_SCALARS rgb 3\n" +
                                std::string(reinterpret_cast<const char*>(rgb), 12) + "\n");
  for (const char* name : {"a.vtk", "b.vtk"}) {
    auto r = importMesh({dir + "/" + name}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    ASSERT_EQ(r->mesh.point_fields.size(), 1u);
    const Field& f = r->mesh.point_fields[0];
    EXPECT_EQ(f.type, ScalarType::kUInt8) << name;
    EXPECT_EQ(f.components, 3u);
    EXPECT_EQ(f.bytes, std::vector<uint8_t>(rgb, rgb + 12)) << name;
  }
}

}  // namespace
}  // namespace gtn

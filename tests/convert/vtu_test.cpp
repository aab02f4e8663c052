// VTK XML (.vtu) import and export: the real datasets against an independent decoder written here,
// round trips bit for bit, files read back by VTK's own reader and by meshio, files written by VTK
// and meshio in every encoding read here, and malformed files rejected with the file's name.
#include <gtest/gtest.h>
#include <lz4.h>
#include <lzma.h>
#include <sys/stat.h>
#include <zlib.h>

#include <unistd.h>
#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "convert/export.h"
#include "convert/import.h"
#include "convert/vtk_common.h"
#include "mesh/mesh_stats.h"
#include "test_util.h"
#include "validate/mesh_checks.h"

namespace gtn {
namespace {

using test::dataPath;
using test::readFile;
using test::runShell;
using test::tempDir;
using test::writeFile;

// ---- An independent minimal decoder for appended .vtu arrays (raw or base64, zlib or not). ----

std::vector<uint8_t> fromBase64(const std::string& s) {
  static const std::string chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<uint8_t> out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    if (c == '=') break;
    const size_t v = chars.find(c);
    if (v == std::string::npos) continue;
    acc = (acc << 6) | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<uint8_t>(acc >> bits));
    }
  }
  return out;
}

struct Oracle {
  std::string text;
  size_t data_start = 0;
  bool base64 = false, compressed = false;
  int header = 4;

  explicit Oracle(const std::string& path) : text(readFile(path)) {
    const size_t a = text.find("<AppendedData");
    base64 = text.find("encoding=\"base64\"", a) != std::string::npos &&
             text.find("encoding=\"base64\"", a) < text.find('>', a);
    data_start = text.find('_', text.find('>', a)) + 1;
    compressed = text.find("vtkZLibDataCompressor") < a;
    header = text.find("header_type=\"UInt64\"") < a ? 8 : 4;
  }
  uint64_t word(const std::vector<uint8_t>& b, size_t i) const {
    uint64_t v = 0;
    std::memcpy(&v, b.data() + i * header, header);
    return v;
  }
  // Bytes of the array whose DataArray tag carries `key` (e.g. Name="Stress").
  std::vector<uint8_t> array(const std::string& key) const {
    const size_t tag = text.find(key);
    EXPECT_NE(tag, std::string::npos) << key;
    const size_t off_at = text.find("offset=\"", tag) + 8;
    const size_t offset = std::stoull(text.substr(off_at, 20));
    std::vector<uint8_t> head, body;
    if (base64) {
      // Compressed base64 arrays: header and blocks encoded apart (that is how these files are).
      const std::vector<uint8_t> first = fromBase64(text.substr(data_start + offset, 4 * header));
      const size_t nblocks = compressed ? word(first, 0) : 0;
      const size_t header_bytes = compressed ? (3 + nblocks) * header : header;
      const size_t header_chars = (header_bytes + 2) / 3 * 4;
      head = fromBase64(text.substr(data_start + offset, header_chars));
      size_t payload = 0;
      if (compressed)
        for (size_t b = 0; b < nblocks; ++b) payload += word(head, 3 + b);
      else payload = word(head, 0);
      body = fromBase64(text.substr(data_start + offset + header_chars, (payload + 2) / 3 * 4));
    } else {
      const uint8_t* p = reinterpret_cast<const uint8_t*>(text.data()) + data_start + offset;
      const size_t nblocks = compressed ? [&] { uint64_t v = 0; std::memcpy(&v, p, header); return v; }() : 0;
      const size_t header_bytes = compressed ? (3 + nblocks) * header : header;
      head.assign(p, p + header_bytes);
      size_t payload = 0;
      if (compressed)
        for (size_t b = 0; b < nblocks; ++b) payload += word(head, 3 + b);
      else payload = word(head, 0);
      body.assign(p + header_bytes, p + header_bytes + payload);
    }
    if (!compressed) return body;
    std::vector<uint8_t> out;
    size_t at = 0;
    for (size_t b = 0; b < word(head, 0); ++b) {
      const size_t usize = (b + 1 == word(head, 0) && word(head, 2)) ? word(head, 2) : word(head, 1);
      std::vector<uint8_t> block(usize);
      uLongf got = usize;
      EXPECT_EQ(uncompress(block.data(), &got, body.data() + at, word(head, 3 + b)), Z_OK);
      at += word(head, 3 + b);
      out.insert(out.end(), block.begin(), block.end());
    }
    return out;
  }
};

template <class T>
std::vector<T> as(const std::vector<uint8_t>& b) {
  std::vector<T> v(b.size() / sizeof(T));
  std::memcpy(v.data(), b.data(), v.size() * sizeof(T));
  return v;
}

ImportResult load(const std::string& path, int split = 6) {
  ImportOptions o;
  o.split = split;
  auto r = importMesh({path}, o);
  EXPECT_TRUE(r.isOk()) << r.status().message();
  return r.isOk() ? std::move(r).value() : ImportResult{};
}

// ---- The real datasets. ----

TEST(Vtu, LvGuccioneEveryArrayBitExact) {
  const std::string path = dataPath("vtu/lv_guccione.vtu");
  ImportResult r = load(path);
  const TetMesh& m = r.mesh;
  EXPECT_EQ(m.numPoints(), 9385u);
  EXPECT_EQ(m.numTets(), 43072u);
  EXPECT_EQ(r.report.flipped, 43072u);
  EXPECT_EQ(m.coord_type, ScalarType::kFloat32);
  const Oracle oracle(path);
  const std::vector<float> xyz = as<float>(oracle.array("Name=\"Points\""));
  ASSERT_EQ(xyz.size(), m.coords.size());
  for (size_t i = 0; i < xyz.size(); ++i) ASSERT_EQ(m.coords[i], static_cast<double>(xyz[i])) << i;
  const std::vector<int64_t> conn = as<int64_t>(oracle.array("Name=\"connectivity\""));
  ASSERT_EQ(conn.size(), 4 * m.numTets());
  for (size_t t = 0; t < m.numTets(); ++t) {
    // Every tet was flipped by swapping its last two vertices.
    EXPECT_EQ(m.tets[t][0], conn[4 * t]);
    EXPECT_EQ(m.tets[t][1], conn[4 * t + 1]);
    EXPECT_EQ(m.tets[t][2], conn[4 * t + 3]);
    EXPECT_EQ(m.tets[t][3], conn[4 * t + 2]);
  }
  const std::vector<std::pair<std::string, uint32_t>> expected = {
      {"Displacement", 3}, {"VonMises_stress", 1}, {"Stress", 6},   {"Cauchy_stress", 6}, {"Strain", 6},
      {"Jacobian", 1},     {"Def_grad", 9},        {"Velocity", 3}, {"Pressure", 1},      {"Acceleration", 3}};
  ASSERT_EQ(m.point_fields.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    const Field& f = m.point_fields[i];
    EXPECT_EQ(f.name, expected[i].first);
    EXPECT_EQ(f.components, expected[i].second);
    EXPECT_EQ(f.type, ScalarType::kFloat64);
    EXPECT_EQ(f.bytes, oracle.array("Name=\"" + f.name + "\"")) << f.name;
  }
  ASSERT_EQ(m.cell_fields.size(), 2u);
  EXPECT_EQ(m.cell_fields[0].name, "E_VonMises");
  EXPECT_EQ(m.cell_fields[0].bytes, oracle.array("Name=\"E_VonMises\""));
  EXPECT_EQ(m.cell_fields[1].name, "E_Jacobian");
  EXPECT_EQ(m.cell_fields[1].bytes, oracle.array("Name=\"E_Jacobian\""));
  const MeshStats s = computeMeshStats(m);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
}

TEST(Vtu, RaptorAndOssiclesCounts) {
  ImportResult raptor = load(dataPath("vtu/raptorTetra_19409.vtu"));
  MeshStats s = computeMeshStats(raptor.mesh);
  EXPECT_EQ(s.points, 5992u);
  EXPECT_EQ(s.tets, 19409u);
  EXPECT_EQ(s.unreferenced_points, 2u);
  EXPECT_EQ(s.inverted, 0u);
  ImportResult ossicles = load(dataPath("vtu/Ossicles.vtu"));
  s = computeMeshStats(ossicles.mesh);
  EXPECT_EQ(s.points, 1733u);
  EXPECT_EQ(s.tets, 5058u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
  EXPECT_EQ(ossicles.mesh.coord_type, ScalarType::kFloat32);
}

TEST(Vtu, FireHexahedraSplitConformingly) {
  const std::string path = dataPath("vtu/fire_ug.vtu");
  const Oracle oracle(path);
  const std::vector<int32_t> conn = as<int32_t>(oracle.array("Name=\"connectivity\""));
  const std::vector<uint8_t> types = oracle.array("Name=\"types\"");
  ASSERT_EQ(types.size(), 10462u);
  ASSERT_EQ(conn.size(), 8u * 10462);
  for (uint8_t t : types) ASSERT_EQ(t, 12);
  // Boundary quadrilaterals of the hexahedral mesh: faces used by one hexahedron only.
  static const int kFaces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  std::map<std::array<int32_t, 4>, int> quads;
  for (size_t h = 0; h < types.size(); ++h)
    for (const auto& f : kFaces) {
      std::array<int32_t, 4> q = {conn[8 * h + f[0]], conn[8 * h + f[1]], conn[8 * h + f[2]], conn[8 * h + f[3]]};
      std::sort(q.begin(), q.end());
      ++quads[q];
    }
  size_t boundary_quads = 0;
  for (const auto& [q, n] : quads) boundary_quads += n == 1;
  EXPECT_EQ(boundary_quads, 3546u);
  for (int split : {6, 5}) {
    ImportResult r = load(path, split);
    const MeshStats s = computeMeshStats(r.mesh);
    EXPECT_EQ(s.points, 12323u);
    EXPECT_GE(s.tets, 5u * 10462);
    EXPECT_LE(s.tets, 6u * 10462);
    if (split == 6) {
      EXPECT_EQ(s.tets, 6u * 10462);
    }
    EXPECT_EQ(s.non_manifold_faces, 0u) << split;
    EXPECT_EQ(s.inverted, 0u);
    EXPECT_EQ(s.zero_volume, 0u);
    EXPECT_EQ(s.boundary_faces, 2 * boundary_quads) << split;
    EXPECT_EQ(r.report.steiner_points, 0u);
    ASSERT_EQ(r.mesh.point_fields.size(), 6u);
    EXPECT_EQ(r.mesh.point_fields[1].name, "uvw");
    EXPECT_EQ(r.mesh.point_fields[1].components, 3u);
    EXPECT_EQ(r.mesh.point_fields[0].bytes, oracle.array("Name=\"t\""));
    EXPECT_EQ(r.mesh.point_fields[5].bytes, oracle.array("Name=\"mfrac\""));
  }
}

// ---- Round trips. ----

void expectSameMesh(const TetMesh& a, const TetMesh& b) {
  EXPECT_EQ(a.coord_type, b.coord_type);
  ASSERT_EQ(a.coords.size(), b.coords.size());
  EXPECT_EQ(std::memcmp(a.coords.data(), b.coords.data(), a.coords.size() * sizeof(double)), 0);
  EXPECT_EQ(a.tets, b.tets);
  ASSERT_EQ(a.point_fields.size(), b.point_fields.size());
  for (size_t i = 0; i < a.point_fields.size(); ++i) {
    EXPECT_EQ(a.point_fields[i].name, b.point_fields[i].name);
    EXPECT_EQ(a.point_fields[i].type, b.point_fields[i].type) << a.point_fields[i].name;
    EXPECT_EQ(a.point_fields[i].components, b.point_fields[i].components) << a.point_fields[i].name;
    EXPECT_EQ(a.point_fields[i].bytes, b.point_fields[i].bytes) << a.point_fields[i].name;
  }
  ASSERT_EQ(a.cell_fields.size(), b.cell_fields.size());
  for (size_t i = 0; i < a.cell_fields.size(); ++i) {
    EXPECT_EQ(a.cell_fields[i].name, b.cell_fields[i].name);
    EXPECT_EQ(a.cell_fields[i].type, b.cell_fields[i].type);
    EXPECT_EQ(a.cell_fields[i].components, b.cell_fields[i].components);
    EXPECT_EQ(a.cell_fields[i].bytes, b.cell_fields[i].bytes) << a.cell_fields[i].name;
  }
}

// A small mesh with float32 coordinates and fields of every type, NaN and extreme values included.
TetMesh makeTypedMesh() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  const int n = 3;
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        m.coords.insert(m.coords.end(),
                        {double(float(i * 0.1f)), double(float(j * 0.3f)), double(float(k * 0.7f + 0.01f))});
  auto id = [&](int i, int j, int k) { return static_cast<uint32_t>((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        // Six tetrahedra around the 0-6 diagonal, positively oriented for this cell shape.
        const uint32_t h[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        static const int kSix[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                       {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
        for (const auto& t : kSix) m.tets.push_back({h[t[0]], h[t[1]], h[t[2]], h[t[3]]});
      }
  const size_t np = m.numPoints(), nt = m.numTets();
  for (int t = 0; t < kNumScalarTypes; ++t) {
    const ScalarType type = static_cast<ScalarType>(t);
    const uint32_t comps = static_cast<uint32_t>(t % 3 + 1);
    Field f(std::string("f_") + scalarTypeName(type), comps, type, np);
    for (size_t b = 0; b < f.bytes.size(); ++b) f.bytes[b] = static_cast<uint8_t>((b * 131 + t * 17) ^ (b >> 3));
    if (type == ScalarType::kFloat32) {
      for (size_t i = 0; i < np * comps; ++i) f.data<float>()[i] = static_cast<float>(i) * 0.37f - 5.0f;
      f.data<float>()[3] = std::numeric_limits<float>::quiet_NaN();
    }
    if (type == ScalarType::kFloat64)
      for (size_t i = 0; i < np * comps; ++i) f.data<double>()[i] = static_cast<double>(i) / 3.0 - 1e300 * (i == 7);
    m.point_fields.push_back(std::move(f));
  }
  Field region("region & <id>", 1, ScalarType::kInt16, nt);
  for (size_t t = 0; t < nt; ++t) region.set<int16_t>(t, 0, static_cast<int16_t>(t % 5 - 2));
  m.cell_fields.push_back(std::move(region));
  Field q("quality", 2, ScalarType::kFloat64, nt);
  for (size_t t = 0; t < nt; ++t) q.set<double>(t, 0, 1.0 / (t + 1)), q.set<double>(t, 1, -double(t));
  m.cell_fields.push_back(std::move(q));
  return m;
}

TEST(Vtu, RoundTripsBitForBit) {
  const std::string dir = tempDir("vtu_roundtrip");
  std::vector<std::pair<std::string, TetMesh>> meshes;
  meshes.emplace_back("spx", load(dataPath("vtk/spx.vtk")).mesh);
  meshes.emplace_back("lv", load(dataPath("vtu/lv_guccione.vtu")).mesh);
  meshes.emplace_back("typed", makeTypedMesh());
  for (const auto& [name, mesh] : meshes) {
    ASSERT_TRUE(mesh.checkConsistency(name).isOk());
    for (bool compress : {false, true}) {
      SCOPED_TRACE(name + (compress ? " compressed" : " plain"));
      const std::string out = dir + "/" + name + (compress ? "_z" : "") + ".vtu";
      ExportOptions eo;
      eo.compress = compress;
      const Status st = exportVtu(mesh, out, eo);
      ASSERT_TRUE(st.isOk()) << st.message();
      const std::string text = readFile(out);
      EXPECT_NE(text.find("header_type=\"UInt64\""), std::string::npos);
      EXPECT_EQ(text.find("vtkZLibDataCompressor") != std::string::npos, compress);
      ImportResult back = load(out);
      EXPECT_EQ(back.report.flipped, 0u);
      expectSameMesh(back.mesh, mesh);
    }
    // Legacy .vtk (BINARY, version 4.2) too: names with spaces are %-encoded and read back.
    SCOPED_TRACE(name + " legacy");
    const std::string legacy = dir + "/" + name + ".vtk";
    const Status st = exportVtkLegacy(mesh, legacy);
    ASSERT_TRUE(st.isOk()) << st.message();
    EXPECT_EQ(readFile(legacy).rfind("# vtk DataFile Version 4.2\n", 0), 0u);
    ImportResult back = load(legacy);
    EXPECT_EQ(back.report.flipped, 0u);
    expectSameMesh(back.mesh, mesh);
  }
  EXPECT_NE(readFile(dir + "/typed.vtk").find("region%20&%20<id> 1 162 short\n"), std::string::npos);
  // Compression pays on real data.
  EXPECT_LT(readFile(dir + "/lv_z.vtu").size(), readFile(dir + "/lv.vtu").size());
  // Tabs and line breaks in a name are character references: an XML parser turns them into spaces
  // in an attribute otherwise (VTK's own writer loses them so).
  TetMesh odd = makeTypedMesh();
  odd.cell_fields[0].name = "a\tb\nc\rd";
  ASSERT_TRUE(exportVtu(odd, dir + "/odd.vtu", ExportOptions{}).isOk());
  EXPECT_NE(readFile(dir + "/odd.vtu").find("Name=\"a&#9;b&#10;c&#13;d\""), std::string::npos);
  expectSameMesh(load(dir + "/odd.vtu").mesh, odd);
  // Other control characters may not appear in XML 1.0 at all, not even as references: %XX, as VTK's
  // legacy writer encodes them; a byte that is not UTF-8 is read as Latin-1.
  odd.cell_fields[0].name = std::string("ctrl\x01\x1F\"\\name\xE9");
  ASSERT_TRUE(exportVtu(odd, dir + "/ctrl.vtu", ExportOptions{}).isOk());
  const std::string ctrl = readFile(dir + "/ctrl.vtu");
  EXPECT_NE(ctrl.find("Name=\"ctrl%01%1F&quot;\\name\xC3\xA9\""), std::string::npos);
  EXPECT_EQ(ctrl.find('\x01'), std::string::npos);
  EXPECT_EQ(load(dir + "/ctrl.vtu").mesh.numTets(), odd.numTets());
}

// ---- Real clients: VTK's reader and meshio (Debian python3-paraview, python3-meshio). ----

bool pythonClientsAvailable(std::string* why) {
  const char* probe = "/usr/bin/python3 -c 'import vtkmodules.vtkIOXML, meshio' 2>&1";
  if (runShell(probe).exit_code == 0) return true;
  *why =
      "/usr/bin/python3 cannot import vtk and meshio (scripts/setup.sh installs python3-paraview and python3-meshio)";
  return false;
}

const char* kClientScript = R"PY(
import sys, json, zlib
import numpy as np
def crc(a):
    a = np.ascontiguousarray(a)
    return zlib.crc32(a.astype(a.dtype.newbyteorder("=")).tobytes())  # meshio keeps a legacy file's big-endian
def desc(a):
    a = np.asarray(a)
    return {"components": 1 if a.ndim == 1 else int(a.shape[1]), "type": a.dtype.name, "crc": crc(a),
            "items": int(a.shape[0])}
path = sys.argv[2]
if sys.argv[1] == "vtk":
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    from vtkmodules.vtkIOLegacy import vtkUnstructuredGridReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    r = vtkUnstructuredGridReader() if path.endswith(".vtk") else vtkXMLUnstructuredGridReader()
    r.SetFileName(path); r.Update()
    g = r.GetOutput()
    pd, cd = g.GetPointData(), g.GetCellData()
    out = {"points": g.GetNumberOfPoints(), "cells": g.GetNumberOfCells(),
           "coords": desc(vtk_to_numpy(g.GetPoints().GetData())),
           "conn_crc": crc(vtk_to_numpy(g.GetCells().GetConnectivityArray()).astype(np.int64)),
           "types": sorted(set(int(t) for t in vtk_to_numpy(g.GetCellTypesArray()))),
           "point_data": {pd.GetArrayName(i): desc(vtk_to_numpy(pd.GetArray(i))) for i in range(pd.GetNumberOfArrays())},
           "cell_data": {cd.GetArrayName(i): desc(vtk_to_numpy(cd.GetArray(i))) for i in range(cd.GetNumberOfArrays())}}
elif sys.argv[1] == "meshio":
    import meshio
    m = meshio.read(path)
    tets = [c.data for c in m.cells if c.type == "tetra"]
    out = {"points": len(m.points), "cells": sum(len(c.data) for c in m.cells), "coords": desc(m.points),
           "conn_crc": crc(np.concatenate(tets).astype(np.int64)), "types": sorted(set(c.type for c in m.cells)),
           "point_data": {k: desc(v) for k, v in m.point_data.items()},
           "cell_data": {k: desc(np.concatenate(v)) for k, v in m.cell_data.items()}}
else:
    # Rewrites argv[2] with VTK's own writer in every encoding, into the folder argv[3].
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter
    r = vtkXMLUnstructuredGridReader(); r.SetFileName(path); r.Update()
    names = []
    for mode in ["ascii", "binary", "raw", "base64"]:
        for comp in ["none", "zlib", "lz4", "lzma"]:
            for header in [32, 64]:
                for order in ["le", "be"]:
                    if mode == "ascii" and (comp != "none" or header != 32 or order != "le"): continue
                    w = vtkXMLUnstructuredGridWriter(); w.SetInputData(r.GetOutput())
                    name = "%s/vtk_%s_%s_%d_%s.vtu" % (sys.argv[3], mode, comp, header, order)
                    w.SetFileName(name)
                    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
                     "raw": w.SetDataModeToAppended, "base64": w.SetDataModeToAppended}[mode]()
                    w.SetEncodeAppendedData(1 if mode == "base64" else 0)
                    {"none": w.SetCompressorTypeToNone, "zlib": w.SetCompressorTypeToZLib,
                     "lz4": w.SetCompressorTypeToLZ4, "lzma": w.SetCompressorTypeToLZMA}[comp]()
                    w.SetHeaderTypeToUInt32() if header == 32 else w.SetHeaderTypeToUInt64()
                    w.SetByteOrderToLittleEndian() if order == "le" else w.SetByteOrderToBigEndian()
                    if w.Write() != 1: sys.exit("write failed: " + name)
                    names.append(name)
    import meshio
    m = meshio.read(path)
    for opts in [("ascii", False, None), ("raw", True, None), ("zlib", True, "zlib"), ("lzma", True, "lzma")]:
        name = "%s/meshio_%s.vtu" % (sys.argv[3], opts[0])
        meshio.write(name, m, binary=opts[1], compression=opts[2])
        names.append(name)
    out = {"files": names}
print(json.dumps(out))
)PY";

nlohmann::json runClient(const std::string& dir, const std::string& mode, const std::string& path,
                         const std::string& extra = "") {
  const std::string script = dir + "/client.py";
  if (!test::fileExists(script)) writeFile(script, kClientScript);
  const auto r = runShell("/usr/bin/python3 " + script + " " + mode + " '" + path + "' " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  try {
    return nlohmann::json::parse(r.out);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "no JSON from the " << mode << " client: " << r.out << r.err;
    return {};
  }
}

void expectFieldSeen(const nlohmann::json& seen, const Field& f, size_t items) {
  ASSERT_TRUE(seen.contains(f.name)) << f.name;
  const auto& d = seen[f.name];
  EXPECT_EQ(d["components"], f.components) << f.name;
  EXPECT_EQ(d["type"], scalarTypeName(f.type)) << f.name;
  EXPECT_EQ(d["items"], items) << f.name;
  EXPECT_EQ(d["crc"], crc32(0, f.bytes.data(), static_cast<uInt>(f.bytes.size()))) << f.name;
}

TEST(Vtu, ExportedFilesReadByVtkAndMeshio) {
  std::string why;
  if (!pythonClientsAvailable(&why)) GTEST_FAIL() << why;
  const std::string dir = tempDir("vtu_clients");
  std::vector<std::pair<std::string, TetMesh>> meshes;
  meshes.emplace_back("lv", load(dataPath("vtu/lv_guccione.vtu")).mesh);
  meshes.emplace_back("typed", makeTypedMesh());
  for (const auto& [name, mesh] : meshes) {
    std::vector<int64_t> conn;
    for (const Tet& t : mesh.tets) conn.insert(conn.end(), t.begin(), t.end());
    const uLong conn_crc = crc32(0, reinterpret_cast<const Bytef*>(conn.data()), static_cast<uInt>(conn.size() * 8));
    std::vector<uint8_t> xyz;
    if (mesh.coord_type == ScalarType::kFloat32) {
      std::vector<float> f(mesh.coords.begin(), mesh.coords.end());
      xyz.assign(reinterpret_cast<uint8_t*>(f.data()), reinterpret_cast<uint8_t*>(f.data() + f.size()));
    } else {
      xyz.assign(reinterpret_cast<const uint8_t*>(mesh.coords.data()),
                 reinterpret_cast<const uint8_t*>(mesh.coords.data() + mesh.coords.size()));
    }
    // .vtu plain and compressed, and legacy .vtk.
    for (int form = 0; form < 3; ++form) {
      const std::string out = dir + "/" + name + (form == 1 ? "_z" : "") + (form == 2 ? ".vtk" : ".vtu");
      ExportOptions eo;
      eo.compress = form == 1;
      ASSERT_TRUE(exportMesh(mesh, out, eo).isOk());
      for (const char* client : {"vtk", "meshio"}) {
        SCOPED_TRACE(out + " read by " + client);
        // meshio 5 reads version 4.2 files with 'long' for 64-bit integers, which is 32-bit in
        // VTK on Windows; the file uses VTK's own 'vtktypeint64', which meshio knows in 5.1 files only.
        const bool int64_fields = std::any_of(mesh.point_fields.begin(), mesh.point_fields.end(), [](const Field& f) {
          return f.type == ScalarType::kInt64 || f.type == ScalarType::kUInt64;
        });
        if (form == 2 && std::string(client) == "meshio" && int64_fields) continue;
        const nlohmann::json j = runClient(dir, client, out);
        if (j.is_null()) continue;
        EXPECT_EQ(j["points"], mesh.numPoints());
        EXPECT_EQ(j["cells"], mesh.numTets());
        EXPECT_EQ(j["conn_crc"], conn_crc);
        EXPECT_EQ(j["coords"]["type"], scalarTypeName(mesh.coord_type));
        EXPECT_EQ(j["coords"]["crc"], crc32(0, xyz.data(), static_cast<uInt>(xyz.size())));
        EXPECT_EQ(j["types"].size(), 1u);
        EXPECT_EQ(j["point_data"].size(), mesh.point_fields.size());
        for (const Field& f : mesh.point_fields) expectFieldSeen(j["point_data"], f, mesh.numPoints());
        EXPECT_EQ(j["cell_data"].size(), mesh.cell_fields.size());
        for (const Field& f : mesh.cell_fields) expectFieldSeen(j["cell_data"], f, mesh.numTets());
      }
    }
  }
}

TEST(Vtu, FilesWrittenByVtkAndMeshioInEveryEncoding) {
  std::string why;
  if (!pythonClientsAvailable(&why)) GTEST_FAIL() << why;
  const std::string dir = tempDir("vtu_writers");
  const TetMesh mesh = makeTypedMesh();
  const std::string source = dir + "/typed.vtu";
  ASSERT_TRUE(exportVtu(mesh, source, ExportOptions{}).isOk());
  const nlohmann::json j = runClient(dir, "write", source, dir);
  ASSERT_TRUE(j.contains("files"));
  size_t read = 0;
  for (const std::string file : j["files"]) {
    SCOPED_TRACE(file);
    auto r = importMesh({file}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    ++read;
    const bool from_meshio = file.find("meshio_") != std::string::npos;
    const bool ascii = file.find("_ascii") != std::string::npos;
    TetMesh expected = mesh;
    if (from_meshio) {
      // meshio writes points as float64 and drops no array; otherwise its files are the same mesh.
      expected.coord_type = r->mesh.coord_type;
    }
    if (ascii) {
      // ASCII writers print floats with fewer digits than a round trip needs (and NaN their own way):
      // check the structure and the integer arrays, which text carries exactly.
      EXPECT_EQ(r->mesh.tets, expected.tets);
      ASSERT_EQ(r->mesh.point_fields.size(), expected.point_fields.size());
      for (size_t i = 0; i < expected.point_fields.size(); ++i) {
        EXPECT_EQ(r->mesh.point_fields[i].name, expected.point_fields[i].name);
        EXPECT_EQ(r->mesh.point_fields[i].type, expected.point_fields[i].type);
        if (!isFloatType(expected.point_fields[i].type)) {
          EXPECT_EQ(r->mesh.point_fields[i].bytes, expected.point_fields[i].bytes) << expected.point_fields[i].name;
        }
      }
      continue;
    }
    expectSameMesh(r->mesh, expected);
  }
  // VTK: ascii + 3 binary modes x 4 compressors (none, zlib, LZ4, LZMA) x 2 headers x 2 orders; meshio: 4.
  EXPECT_EQ(read, 1u + 3 * 4 * 2 * 2 + 4);
}

// ---- Hand-written files: several pieces; malformed inputs. ----

const char* kTwoPieces = R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="4" NumberOfCells="1">
      <PointData><DataArray type="Int32" Name="id" format="ascii">10 11 12 13</DataArray></PointData>
      <CellData><DataArray type="Float32" Name="w" format="ascii">0.5</DataArray></CellData>
      <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">4</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10</DataArray>
      </Cells>
    </Piece>
    <Piece NumberOfPoints="4" NumberOfCells="1">
      <PointData><DataArray type="Int32" Name="id" format="ascii">20 21 22 23</DataArray></PointData>
      <CellData><DataArray type="Float32" Name="w" format="ascii">0.25</DataArray></CellData>
      <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">2 0 0 3 0 0 2 1 0 2 0 1</DataArray></Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">CONN</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">4</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">TYPE</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
)";

std::string twoPieces(const std::string& conn, const std::string& type) {
  std::string s = kTwoPieces;
  s.replace(s.find("CONN"), 4, conn);
  s.replace(s.find("TYPE"), 4, type);
  return s;
}

TEST(Vtu, SeveralPiecesAreConcatenated) {
  const std::string path = tempDir("vtu_pieces") + "/two.vtu";
  writeFile(path, twoPieces("0 1 2 3", "10"));
  ImportResult r = load(path);
  ASSERT_EQ(r.mesh.numPoints(), 8u);
  ASSERT_EQ(r.mesh.numTets(), 2u);
  EXPECT_EQ(r.mesh.tets[1], (Tet{4, 5, 6, 7}));
  ASSERT_EQ(r.mesh.point_fields.size(), 1u);
  EXPECT_EQ(r.mesh.point_fields[0].type, ScalarType::kInt32);
  EXPECT_EQ(r.mesh.point_fields[0].data<int32_t>()[5], 21);
  ASSERT_EQ(r.mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r.mesh.cell_fields[0].data<float>()[1], 0.25f);

  // Empty pieces, as VTK writes them when there are more pieces than cells: their arrays (named as
  // VTK likes, here ImageScalars) hold nothing and are not matched, first or between.
  const std::string empty =
      R"(<Piece NumberOfPoints="0" NumberOfCells="0"><PointData><DataArray type="Float32" Name="ImageScalars" format="ascii"></DataArray></PointData>)"
      R"(<CellData></CellData><Points><DataArray type="Float32" NumberOfComponents="3" format="ascii"></DataArray></Points>)"
      R"(<Cells><DataArray type="Int64" Name="connectivity" format="ascii"></DataArray><DataArray type="Int64" Name="offsets" format="ascii"></DataArray>)"
      R"(<DataArray type="UInt8" Name="types" format="ascii"></DataArray></Cells></Piece>)"
      "\n";
  std::string gaps = twoPieces("0 1 2 3", "10");
  const size_t second = gaps.find("<Piece", gaps.find("<Piece") + 1);
  gaps.insert(second, empty);
  gaps.insert(gaps.find("<Piece"), empty);
  const std::string gaps_path = tempDir("vtu_empty_pieces") + "/gaps.vtu";
  writeFile(gaps_path, gaps);
  ImportResult g = load(gaps_path);
  ASSERT_EQ(g.mesh.numPoints(), 8u);
  ASSERT_EQ(g.mesh.numTets(), 2u);
  ASSERT_EQ(g.mesh.point_fields.size(), 1u);
  EXPECT_EQ(g.mesh.point_fields[0].data<int32_t>()[5], 21);
  ASSERT_EQ(g.mesh.cell_fields.size(), 1u);
  EXPECT_EQ(
      r.report.warnings,
      std::vector<std::string>{"2 pieces read; the points they share are kept once per piece (--weld merges them)"});

  // What is not mesh data goes with a warning, once: VTK's string arrays (<Array type="String">, in
  // every piece) and the dataset's own FieldData.
  std::string text = twoPieces("0 1 2 3", "10");
  for (size_t at = text.find("<PointData>"); at != std::string::npos; at = text.find("<PointData>", at + 1))
    text.insert(at + 11, R"(<Array type="String" Name="label" format="ascii">97 0 98 0 99 0 100 0</Array>)");
  text.insert(
      text.find("<Piece"),
      R"(<FieldData><DataArray type="Float64" Name="TIME" NumberOfTuples="1" format="ascii">1.5</DataArray></FieldData>)");
  const std::string text_path = tempDir("vtu_text_arrays") + "/text.vtu";
  writeFile(text_path, text);
  ImportResult t = load(text_path);
  EXPECT_EQ(t.mesh.point_fields.size(), 1u);
  const std::vector<std::string> want = {
      "the dataset's FieldData arrays ('TIME') are not kept: they belong to no point or cell",
      "skipped <Array> 'label' (String) of PointData: only numeric DataArrays are mesh data",
      "2 pieces read; the points they share are kept once per piece (--weld merges them)"};
  EXPECT_EQ(t.report.warnings, want);
}

void expectError(const std::string& path, const std::string& part) {
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_FALSE(r.isOk()) << "accepted " << path;
  EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(part), std::string::npos) << r.status().message() << "\nlacks: " << part;
}

// The structured XML files: a curvilinear StructuredGrid (.vts, with point and cell data), a
// RectilinearGrid (.vtr) and an ImageData (.vti) whose extent does not start at 0. Their hexahedra are
// split like PLOT3D's; cell values follow VTK's cell order (i fastest).
TEST(Vtu, StructuredFilesBecomeSplitHexahedra) {
  const std::string dir = tempDir("vtu_structured");
  writeFile(dir + "/g.vts", R"(<?xml version="1.0"?>
<VTKFile type="StructuredGrid" version="0.1" byte_order="LittleEndian">
<StructuredGrid WholeExtent="0 2 0 1 0 1"><Piece Extent="0 2 0 1 0 1">
<PointData><DataArray type="Float32" Name="t" format="ascii">0 1 2 3 4 5 6 7 8 9 10 11.5</DataArray></PointData>
<CellData><DataArray type="Int32" Name="zone" format="ascii">5 6</DataArray></CellData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">
0 0 0  1 0 0  2 0 0  0 1 0  1 1 0  2 1 0  0.5 0 1  1.5 0 1  2.5 0 1  0.5 1 1  1.5 1 1  2.5 1 1</DataArray></Points>
</Piece></StructuredGrid></VTKFile>
)");
  writeFile(dir + "/g.vtr", R"(<?xml version="1.0"?>
<VTKFile type="RectilinearGrid" version="0.1" byte_order="LittleEndian">
<RectilinearGrid WholeExtent="0 2 0 1 0 1"><Piece Extent="0 2 0 1 0 1"><Coordinates>
<DataArray type="Float32" format="ascii">0 1 3</DataArray>
<DataArray type="Float32" format="ascii">0 2</DataArray>
<DataArray type="Float32" format="ascii">0 0.5</DataArray>
</Coordinates></Piece></RectilinearGrid></VTKFile>
)");
  writeFile(dir + "/g.vti", R"(<?xml version="1.0"?>
<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian">
<ImageData WholeExtent="1 3 0 1 0 1" Origin="10 0 0" Spacing="0.5 1 2"><Piece Extent="1 3 0 1 0 1">
<PointData><DataArray type="UInt8" Name="m" format="ascii">0 1 1 0 0 1 1 1 0 0 0 1</DataArray></PointData>
</Piece></ImageData></VTKFile>
)");
  for (const int split : {5, 6}) {
    ImportOptions options;
    options.split = split;
    auto g = importMesh({dir + "/g.vts"}, options);
    ASSERT_TRUE(g.isOk()) << g.status().message();
    EXPECT_EQ(g->mesh.numPoints(), 12u);
    EXPECT_EQ(g->mesh.numTets(), 2u * split);
    EXPECT_EQ(g->mesh.coord_type, ScalarType::kFloat64);
    EXPECT_DOUBLE_EQ(g->mesh.point(11)[0], 2.5);
    const MeshStats gs = computeMeshStats(g->mesh);
    EXPECT_NEAR(gs.total_volume, 2.0, 1e-12);  // two sheared unit cubes
    EXPECT_EQ(gs.inverted, 0u);
    EXPECT_EQ(gs.non_manifold_faces, 0u);
    EXPECT_EQ(g->mesh.point_fields[0].data<float>()[11], 11.5f);
    ASSERT_EQ(g->mesh.cell_fields.size(), 1u);
    for (size_t t = 0; t < g->mesh.numTets(); ++t) {
      double cx = 0;  // the centroid's x, unsheared
      for (uint32_t v : g->mesh.tets[t]) cx += (g->mesh.point(v)[0] - 0.5 * g->mesh.point(v)[2]) / 4;
      EXPECT_EQ(g->mesh.cell_fields[0].data<int32_t>()[t], cx < 1 ? 5 : 6) << t;
    }

    auto r = importMesh({dir + "/g.vtr"}, options);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->mesh.coord_type, ScalarType::kFloat32);
    EXPECT_DOUBLE_EQ(r->mesh.point(11)[0], 3.0);
    EXPECT_DOUBLE_EQ(r->mesh.point(11)[1], 2.0);
    EXPECT_DOUBLE_EQ(r->mesh.point(11)[2], 0.5);
    EXPECT_NEAR(computeMeshStats(r->mesh).total_volume, 3.0 * 2.0 * 0.5, 1e-12);

    auto i = importMesh({dir + "/g.vti"}, options);
    ASSERT_TRUE(i.isOk()) << i.status().message();
    EXPECT_DOUBLE_EQ(i->mesh.point(0)[0], 10.5);  // extent starts at i = 1
    EXPECT_DOUBLE_EQ(i->mesh.point(11)[0], 11.5);
    EXPECT_DOUBLE_EQ(i->mesh.point(11)[2], 2.0);
    EXPECT_NEAR(computeMeshStats(i->mesh).total_volume, 1.0 * 1.0 * 2.0, 1e-12);
    EXPECT_EQ(i->mesh.point_fields[0].data<uint8_t>()[11], 1);
  }
  // A Direction turns the index axes: here x' = -y, y' = x (a quarter turn about z).
  {
    std::string turned = readFile(dir + "/g.vti");
    turned.replace(turned.find("Spacing="), 8, "Direction=\"0 -1 0 1 0 0 0 0 1\" Spacing=");
    writeFile(dir + "/turned.vti", turned);
    auto t = importMesh({dir + "/turned.vti"}, ImportOptions{});
    ASSERT_TRUE(t.isOk()) << t.status().message();
    // Point 11 is index (3, 1, 1): d = (1.5, 1, 2), turned (-1, 1.5, 2), plus the origin (10, 0, 0).
    EXPECT_DOUBLE_EQ(t->mesh.point(11)[0], 9.0);
    EXPECT_DOUBLE_EQ(t->mesh.point(11)[1], 1.5);
    EXPECT_DOUBLE_EQ(t->mesh.point(11)[2], 2.0);
    EXPECT_NEAR(computeMeshStats(t->mesh).total_volume, 2.0, 1e-12);
  }

  // What they cannot hold: several pieces, a flat extent, more implicit points than the file could
  // carry data for, a rectilinear grid with two axes, a dataset of no volume.
  const std::string vti = readFile(dir + "/g.vti");
  auto expectFails = [&](const std::string& name, std::string text, const std::string& from, const std::string& to,
                         const std::string& part) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    writeFile(dir + "/" + name, text);
    expectError(dir + "/" + name, part);
  };
  expectFails("two.vti", vti, "</Piece>", "</Piece><Piece Extent=\"1 3 0 1 0 1\"></Piece>",
              "Piece 1: does not carry the same point and cell arrays as Piece 0");
  expectFails("outside.vti", vti, "<Piece Extent=\"1 3 0 1 0 1\"", "<Piece Extent=\"1 4 0 1 0 1\"",
              "Extent \"1 4 0 1 0 1\" is not a 3D block within the WholeExtent");
  expectFails("part.vti", vti, "<Piece Extent=\"1 3 0 1 0 1\"", "<Piece Extent=\"1 2 0 1 0 1\"",
              "Piece 0 PointData 'm': has more than the 8 values expected");
  // The image with both extents (whole and piece) replaced.
  auto withExtent = [&](const std::string& name, const std::string& extent, const std::string& part) {
    std::string text = vti;
    for (const std::string key : {"WholeExtent=", " Extent="}) {
      const size_t at = text.find(key + "\"1 3 0 1 0 1\"");
      ASSERT_NE(at, std::string::npos) << key;
      text.replace(at + key.size(), 13, "\"" + extent + "\"");
    }
    writeFile(dir + "/" + name, text);
    expectError(dir + "/" + name, part);
  };
  withExtent("huge2.vti", "0 2000 0 2000 0 2000", "more than a file of");
  withExtent("wide.vti", "-9000000000000000000 9000000000000000000 0 1 0 1", "bad WholeExtent");
  withExtent("flat2.vti", "1 3 0 1 0 0", "fewer than 2 points along an axis");
  expectFails("axes.vtr", readFile(dir + "/g.vtr"), "<DataArray type=\"Float32\" format=\"ascii\">0 0.5</DataArray>",
              "", "<Coordinates> needs three DataArrays");
  expectFails("poly.vtp", readFile(dir + "/g.vtr"), "type=\"RectilinearGrid\"", "type=\"PolyData\"",
              "VTKFile type \"PolyData\" is not supported (it holds no volume cells");
}

// Structured XML files of several pieces (VTK's writers with SetNumberOfPieces): each piece a block of
// the whole extent, neighbours sharing a layer of points. The grids of StructuredFilesBecomeSplitHexahedra
// cut in two along i read as the files of one piece.
TEST(Vtu, StructuredFilesOfSeveralPieces) {
  const std::string dir = tempDir("vtu_structured_pieces");
  const std::string head = R"(<?xml version="1.0"?>
<VTKFile type="TYPE" version="0.1" byte_order="LittleEndian">
<TYPE WholeExtent="WHOLE"ATTRS>
)";
  auto file = [&](const std::string& type, const std::string& whole, const std::string& attrs,
                  const std::string& pieces) {
    std::string text = head;
    for (size_t at; (at = text.find("TYPE")) != std::string::npos;) text.replace(at, 4, type);
    text.replace(text.find("WHOLE"), 5, whole);
    text.replace(text.find("ATTRS"), 5, attrs);
    return text + pieces + "</" + type + "></VTKFile>\n";
  };
  auto vtsPiece = [](const std::string& extent, const std::string& t, const std::string& zone, const std::string& xyz) {
    return "<Piece Extent=\"" + extent + "\"><PointData><DataArray type=\"Float32\" Name=\"t\" format=\"ascii\">" + t +
           "</DataArray></PointData><CellData><DataArray type=\"Int32\" Name=\"zone\" format=\"ascii\">" + zone +
           "</DataArray></CellData><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">" +
           xyz + "</DataArray></Points></Piece>\n";
  };
  const std::string a_xyz = "0 0 0  1 0 0  0 1 0  1 1 0  0.5 0 1  1.5 0 1  0.5 1 1  1.5 1 1";
  const std::string b_xyz = "1 0 0  2 0 0  1 1 0  2 1 0  1.5 0 1  2.5 0 1  1.5 1 1  2.5 1 1";
  const std::string piece_a = vtsPiece("0 1 0 1 0 1", "0 1 3 4 6 7 9 10", "5", a_xyz);
  const std::string piece_b = vtsPiece("1 2 0 1 0 1", "1 2 4 5 7 8 10 11.5", "6", b_xyz);
  const std::string whole_vts =
      vtsPiece("0 2 0 1 0 1", "0 1 2 3 4 5 6 7 8 9 10 11.5", "5 6",
               "0 0 0  1 0 0  2 0 0  0 1 0  1 1 0  2 1 0  0.5 0 1  1.5 0 1  2.5 0 1  0.5 1 1  "
               "1.5 1 1  2.5 1 1");
  auto rect = [](const std::string& extent, const std::string& x) {
    return "<Piece Extent=\"" + extent + "\"><Coordinates><DataArray type=\"Float32\" format=\"ascii\">" + x +
           "</DataArray><DataArray type=\"Float32\" format=\"ascii\">0 2</DataArray>"
           "<DataArray type=\"Float32\" format=\"ascii\">0 0.5</DataArray></Coordinates></Piece>\n";
  };
  auto image = [](const std::string& extent, const std::string& m) {
    return "<Piece Extent=\"" + extent + "\"><PointData><DataArray type=\"UInt8\" Name=\"m\" format=\"ascii\">" + m +
           "</DataArray></PointData></Piece>\n";
  };
  const std::string spacing = " Origin=\"10 0 0\" Spacing=\"0.5 1 2\"";
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {file("StructuredGrid", "0 2 0 1 0 1", "", whole_vts),
       file("StructuredGrid", "0 2 0 1 0 1", "", piece_b + piece_a)},
      {file("RectilinearGrid", "0 2 0 1 0 1", "", rect("0 2 0 1 0 1", "0 1 3")),
       file("RectilinearGrid", "0 2 0 1 0 1", "", rect("0 1 0 1 0 1", "0 1") + rect("1 2 0 1 0 1", "1 3"))},
      {file("ImageData", "1 3 0 1 0 1", spacing, image("1 3 0 1 0 1", "0 1 1 0 0 1 1 1 0 0 0 1")),
       file("ImageData", "1 3 0 1 0 1", spacing,
            image("1 2 0 1 0 1", "0 1 0 0 1 1 0 0") + image("2 3 0 1 0 1", "1 1 0 1 1 0 0 1"))}};
  const char* ext[3] = {"vts", "vtr", "vti"};
  for (int f = 0; f < 3; ++f) {
    SCOPED_TRACE(ext[f]);
    writeFile(dir + "/one." + ext[f], pairs[f].first);
    writeFile(dir + "/two." + ext[f], pairs[f].second);
    auto one = importMesh({dir + "/one." + ext[f]}, ImportOptions{});
    auto two = importMesh({dir + "/two." + ext[f]}, ImportOptions{});
    ASSERT_TRUE(one.isOk()) << one.status().message();
    ASSERT_TRUE(two.isOk()) << two.status().message();
    EXPECT_EQ(two->mesh.numTets(), 12u);
    expectSameMesh(two->mesh, one->mesh);
  }
  // Pieces that do not cover the whole extent, or do not agree.
  auto vts = [&](const std::string& name, const std::string& pieces) {
    writeFile(dir + "/" + name, file("StructuredGrid", "0 2 0 1 0 1", "", pieces));
    return dir + "/" + name;
  };
  expectError(vts("short.vts", piece_a), "its pieces hold 8 points, fewer than the 12 of the WholeExtent");
  expectError(vts("twice.vts", piece_a + piece_a), "its pieces leave out points of the WholeExtent");
  expectError(vts("outside.vts", piece_a + vtsPiece("1 3 0 1 0 1", "1 2 4 5 7 8 10 11", "6", b_xyz)),
              "Piece 1: Extent \"1 3 0 1 0 1\" is not a 3D block within the WholeExtent");
  std::string other = piece_b;
  other.replace(other.find("Name=\"t\""), 8, "Name=\"u\"");
  expectError(vts("arrays.vts", piece_a + other), "Piece 1: does not carry the same point and cell arrays as Piece 0");

  // The same pieces in files of their own (each file's WholeExtent its piece's), named by a parallel
  // file (.pvts, .pvtr, .pvti) as VTK's parallel writers make them: the same grid.
  struct Split {
    std::string type, whole, attrs, extent[2], piece[2];
  };
  const Split splits[3] = {{"StructuredGrid", "0 2 0 1 0 1", "", {"0 1 0 1 0 1", "1 2 0 1 0 1"}, {piece_a, piece_b}},
                           {"RectilinearGrid",
                            "0 2 0 1 0 1",
                            "",
                            {"0 1 0 1 0 1", "1 2 0 1 0 1"},
                            {rect("0 1 0 1 0 1", "0 1"), rect("1 2 0 1 0 1", "1 3")}},
                           {"ImageData",
                            "1 3 0 1 0 1",
                            spacing,
                            {"1 2 0 1 0 1", "2 3 0 1 0 1"},
                            {image("1 2 0 1 0 1", "0 1 0 0 1 1 0 0"), image("2 3 0 1 0 1", "1 1 0 1 1 0 0 1")}}};
  auto parallel = [&](const Split& sp, const std::string& name, const std::string& sources) {
    std::string text = "<?xml version=\"1.0\"?>\n<VTKFile type=\"P" + sp.type + "\" version=\"0.1\">\n<P" + sp.type +
                       " WholeExtent=\"" + sp.whole + "\" GhostLevel=\"0\"" + sp.attrs + ">\n" + sources + "</P" +
                       sp.type + "></VTKFile>\n";
    writeFile(dir + "/" + name, text);
    return dir + "/" + name;
  };
  auto source = [](const std::string& extent, const std::string& file) {
    return "<Piece Extent=\"" + extent + "\" Source=\"" + file + "\"/>\n";
  };
  const char* pext[3] = {"pvts", "pvtr", "pvti"};
  for (int f = 0; f < 3; ++f) {
    SCOPED_TRACE(pext[f]);
    const Split& sp = splits[f];
    std::string sources;
    for (int k = 0; k < 2; ++k) {
      const std::string name = "part" + std::to_string(k) + "." + ext[f];
      // A piece file repeats Origin and Spacing; VTK's writers put Direction there only.
      writeFile(dir + "/" + name, file(sp.type, sp.extent[k], sp.attrs, sp.piece[k]));
      sources += source(sp.extent[k], name);
    }
    auto one = importMesh({dir + "/one." + ext[f]}, ImportOptions{});
    auto par = importMesh({parallel(sp, std::string("all.") + pext[f], sources)}, ImportOptions{});
    ASSERT_TRUE(one.isOk()) << one.status().message();
    ASSERT_TRUE(par.isOk()) << par.status().message();
    EXPECT_EQ(par->mesh.numTets(), 12u);
    expectSameMesh(par->mesh, one->mesh);
  }
  // Ghost marks, which pieces disagree on, are dropped; the data is the same.
  {
    auto ghost = [](std::string piece, const std::string& marks) {
      piece.insert(piece.find("</PointData>"),
                   "<DataArray type=\"UInt8\" Name=\"vtkGhostType\" format=\"ascii\">" + marks + "</DataArray>");
      return piece;
    };
    writeFile(dir + "/g0.vts", file("StructuredGrid", "0 1 0 1 0 1", "", ghost(piece_a, "0 0 0 0 0 0 0 0")));
    writeFile(dir + "/g1.vts", file("StructuredGrid", "1 2 0 1 0 1", "", ghost(piece_b, "1 0 1 0 1 0 1 0")));
    auto par = importMesh(
        {parallel(splits[0], "ghost.pvts", source("0 1 0 1 0 1", "g0.vts") + source("1 2 0 1 0 1", "g1.vts"))},
        ImportOptions{});
    auto one = importMesh({dir + "/one.vts"}, ImportOptions{});
    ASSERT_TRUE(par.isOk()) << par.status().message();
    ASSERT_TRUE(one.isOk()) << one.status().message();
    expectSameMesh(par->mesh, one->mesh);
    ASSERT_EQ(par->report.warnings.size(), 1u);
    EXPECT_NE(par->report.warnings[0].find("vtkGhostType"), std::string::npos);
    // Blanking bits are the grid's: a point hidden in its piece hides its cell (HIDDENPOINT = 2).
    writeFile(dir + "/g1.vts", file("StructuredGrid", "1 2 0 1 0 1", "", ghost(piece_b, "1 3 1 0 1 0 1 0")));
    auto blank = importMesh({dir + "/ghost.pvts"}, ImportOptions{});
    ASSERT_TRUE(blank.isOk()) << blank.status().message();
    EXPECT_EQ(blank->mesh.numTets(), 6u);
    EXPECT_EQ(blank->report.dropped_cells, 1u);
    for (const Field& f : blank->mesh.point_fields) EXPECT_NE(f.name, "vtkGhostType");
  }
  // A missing piece, a piece of another type, a piece that is itself parallel, a piece outside the
  // whole extent, pieces that leave a gap, pieces whose arrays differ.
  const Split& sg = splits[0];
  expectError(parallel(sg, "missing.pvts", source("0 1 0 1 0 1", "part0.vts") + source("1 2 0 1 0 1", "nowhere.vts")),
              "missing.pvts: piece 1:");
  expectError(parallel(sg, "type.pvts", source("0 1 0 1 0 1", "part0.vts") + source("1 2 0 1 0 1", "part1.vtr")),
              "piece 1: " + dir + "/part1.vtr: a VTKFile of type \"RectilinearGrid\", not StructuredGrid");
  expectError(parallel(sg, "nested.pvts", source("0 1 0 1 0 1", "part0.vts") + source("1 2 0 1 0 1", "nested.pvts")),
              "a piece of a parallel file is itself a parallel file");
  writeFile(dir + "/wide.vts",
            file("StructuredGrid", "1 3 0 1 0 1", "",
                 vtsPiece("1 3 0 1 0 1", "1 2 4 5 7 8 10 11 1 1 1 1", "6 6", b_xyz + " 3 0 0  3 1 0  3 0 1  3 1 1")));
  expectError(
      parallel(sg, "wide.pvts", source("0 1 0 1 0 1", "part0.vts") + source("1 3 0 1 0 1", "wide.vts")),
      "piece 1: " + dir + "/wide.vts: Piece 0: Extent \"1 3 0 1 0 1\" is not a 3D block within the WholeExtent");
  expectError(parallel(sg, "gap.pvts", source("0 1 0 1 0 1", "part0.vts") + source("0 1 0 1 0 1", "part0.vts")),
              "gap.pvts: <PStructuredGrid>: its pieces leave out points of the WholeExtent");
  writeFile(dir + "/other.vts", file("StructuredGrid", "1 2 0 1 0 1", "", other));
  expectError(parallel(sg, "arrays.pvts", source("0 1 0 1 0 1", "part0.vts") + source("1 2 0 1 0 1", "other.vts")),
              "arrays.pvts: piece 1: " + dir +
                  "/other.vts: Piece 0: does not carry the same point and cell arrays as " + dir +
                  "/part0.vts: Piece 0");
  expectError(parallel(sg, "none.pvts", ""), "none.pvts: <PStructuredGrid> names no <Piece> file");
}

// Polyhedra as VTK (up to 9.3) and meshio write them: faces and faceoffsets beside the cells, face
// indices local to the piece. Two pieces, each a unit cube as a polyhedron under a pyramid.
TEST(Vtu, PolyhedraInSeveralPieces) {
  const std::string dir = tempDir("vtu_polyhedra");
  // The cube of a piece spans x in [x0, x0 + 1]; its pyramid's apex is at height 1.5.
  auto make = [](double x0, int part) {
    const double xyz[9][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},      {0, 0, 1},
                              {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0.5, 0.5, 1.5}};
    std::string points;
    for (const auto& p : xyz)
      points += std::to_string(x0 + p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "  ";
    return R"(<Piece NumberOfPoints="9" NumberOfCells="2">
<CellData><DataArray type="Int32" Name="part" format="ascii">)" +
           std::to_string(part) + " " + std::to_string(part) + R"(</DataArray></CellData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">)" +
           points + R"(</DataArray></Points>
<Cells>
<DataArray type="Int32" Name="connectivity" format="ascii">4 5 6 7 8  0 1 2 3 4 5 6 7</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">5 13</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">14 42</DataArray>
<DataArray type="Int64" Name="faces" format="ascii">6 4 3 0 4 7 4 1 2 6 5 4 0 1 5 4 4 2 3 7 6 4 3 2 1 0 4 4 5 6 7</DataArray>
<DataArray type="Int64" Name="faceoffsets" format="ascii">-1 31</DataArray>
</Cells></Piece>
)";
  };
  const std::string text = std::string(R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian"><UnstructuredGrid>
)") + make(0, 1) + make(3, 2) +
                           "</UnstructuredGrid></VTKFile>\n";
  writeFile(dir + "/poly.vtu", text);
  auto r = importMesh({dir + "/poly.vtu"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numPoints(), 18u);
  EXPECT_EQ(r->mesh.numTets(), 2u * (2 + 6));
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_EQ(s.non_manifold_faces, 0u);
  EXPECT_EQ(s.boundary_faces, 2u * (5 * 2 + 4));
  EXPECT_NEAR(s.total_volume, 2 * (1.0 + 0.5 / 3), 1e-6);
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
  size_t second = 0;
  for (size_t t = 0; t < r->mesh.numTets(); ++t) second += r->mesh.cell_fields[0].data<int32_t>()[t] == 2;
  EXPECT_EQ(second, 8u);
}

// Polyhedra as VTK 9.4 writes them: polyhedron_offsets and polyhedron_to_faces name each polyhedron's
// faces in a face table (face_offsets, face_connectivity), so neighbours share a face. Two stacked
// unit cubes as polyhedra sharing their middle face, under a pyramid, in two pieces; the same mesh in
// the earlier layout gives the same tetrahedra.
TEST(Vtu, PolyhedraInVtk94Tables) {
  const std::string dir = tempDir("vtu_polyhedra94");
  const int quads[11][4] = {{0, 3, 2, 1},   {4, 5, 6, 7}, {0, 1, 5, 4},  {1, 2, 6, 5},   {2, 3, 7, 6}, {3, 0, 4, 7},
                            {8, 9, 10, 11}, {4, 5, 9, 8}, {5, 6, 10, 9}, {6, 7, 11, 10}, {7, 4, 8, 11}};
  const int cube_faces[2][6] = {{0, 1, 2, 3, 4, 5}, {1, 6, 7, 8, 9, 10}};
  // tables: "94" (VTK 9.4; `binary` puts the face table in base64 with one unused face at its end),
  // "old" (faces/faceoffsets).
  auto piece = [&](double x0, const std::string& tables, bool binary) {
    std::string points;
    for (int layer = 0; layer < 3; ++layer)
      for (const auto& q : {std::pair{0, 0}, std::pair{1, 0}, std::pair{1, 1}, std::pair{0, 1}})
        points += std::to_string(x0 + q.first) + " " + std::to_string(q.second) + " " + std::to_string(layer) + "  ";
    points += std::to_string(x0 + 0.5) + " 0.5 2.5";
    std::string text = R"(<Piece NumberOfPoints="13" NumberOfCells="3">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">)" +
                       points + R"(</DataArray></Points>
<Cells>
<DataArray type="Int32" Name="connectivity" format="ascii">8 9 10 11 12  0 1 2 3 4 5 6 7  4 5 6 7 8 9 10 11</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">5 13 21</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">14 42 42</DataArray>
)";
    auto join = [](const std::vector<int64_t>& v) {
      std::string out;
      for (int64_t x : v) out += std::to_string(x) + " ";
      return out;
    };
    auto array = [&](const char* name, std::vector<int64_t> v, bool base64) {
      if (!base64)
        return std::string("<DataArray type=\"Int64\" Name=\"") + name + "\" format=\"ascii\">" + join(v) +
               "</DataArray>\n";
      std::vector<uint8_t> bytes(4 + 8 * v.size());
      const uint32_t size = static_cast<uint32_t>(8 * v.size());
      std::memcpy(bytes.data(), &size, 4);
      std::memcpy(bytes.data() + 4, v.data(), 8 * v.size());
      return std::string("<DataArray type=\"Int64\" Name=\"") + name + "\" format=\"binary\">" +
             base64Encode(bytes.data(), bytes.size()) + "</DataArray>\n";
    };
    if (tables == "94") {
      std::vector<int64_t> to_faces, face_ends, face_points;
      for (const auto& c : cube_faces) to_faces.insert(to_faces.end(), c, c + 6);
      for (const auto& q : quads) {
        face_points.insert(face_points.end(), q, q + 4);
        face_ends.push_back(static_cast<int64_t>(face_points.size()));
      }
      if (binary) {  // a face no polyhedron names
        face_points.insert(face_points.end(), {0, 1, 12});
        face_ends.push_back(static_cast<int64_t>(face_points.size()));
      }
      text += array("polyhedron_offsets", {0, 6, 12}, false) + array("polyhedron_to_faces", to_faces, false) +
              array("face_offsets", face_ends, binary) + array("face_connectivity", face_points, binary);
    } else {
      std::vector<int64_t> stream, ends{-1};
      for (const auto& c : cube_faces) {
        stream.push_back(6);
        for (int f : c) {
          stream.push_back(4);
          stream.insert(stream.end(), quads[f], quads[f] + 4);
        }
        ends.push_back(static_cast<int64_t>(stream.size()));
      }
      text += array("faces", stream, false) + array("faceoffsets", ends, false);
    }
    return text + "</Cells></Piece>\n";
  };
  auto file = [&](const std::string& name, const std::string& tables, bool binary, const std::string& body_edit = "") {
    std::string text = std::string(R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="2.3" byte_order="LittleEndian" header_type="UInt32"><UnstructuredGrid>
)") + piece(0, tables, binary) +
                       piece(3, tables, binary) + "</UnstructuredGrid></VTKFile>\n";
    if (!body_edit.empty()) {
      const size_t bar = body_edit.find('|');
      const std::string from = body_edit.substr(0, bar), to = body_edit.substr(bar + 1);
      const size_t at = text.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      if (at != std::string::npos) text.replace(at, from.size(), to);
    }
    writeFile(dir + "/" + name, text);
    return dir + "/" + name;
  };
  auto old = importMesh({file("old.vtu", "old", false)}, ImportOptions{});
  ASSERT_TRUE(old.isOk()) << old.status().message();
  for (bool binary : {false, true}) {
    auto r = importMesh({file("new.vtu", "94", binary)}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->mesh.numTets(), 2u * (2 + 6 + 6));
    const MeshStats s = computeMeshStats(r->mesh);
    EXPECT_EQ(s.non_manifold_faces, 0u);
    EXPECT_EQ(s.boundary_faces, 2u * (5 * 2 + 4 * 2 + 4));  // the shared faces are interior
    EXPECT_NEAR(s.total_volume, 2 * (2.0 + 0.5 / 3), 1e-12);
    expectSameMesh(r->mesh, old->mesh);
  }

  // What is wrong with the tables, named.
  expectError(file("lack.vtu", "94", false, "Name=\"face_offsets\"|Name=\"face_offsetz\""),
              "VTK 9.4's polyhedron tables lack face_offsets");
  expectError(file("pyramid_faces.vtu", "94", false, ">0 6 12 <|>1 7 12 <"),
              "cell 0 (VTK_PYRAMID) is not a polyhedron but has 1 faces");
  expectError(file("decrease.vtu", "94", false, ">0 6 12 <|>0 7 6 <"), "polyhedron_offsets: decrease at entry 2");
  expectError(file("face.vtu", "94", false, ">0 1 2 3 4 5 1 6 |>0 1 2 3 4 5 1 99 "), "face_offsets");
  expectError(file("point.vtu", "94", false, ">0 3 2 1 |>0 3 2 13 "), "refers to point 13 but the piece has 13 points");
  // A face named again and again: more than two polyhedra cannot share it.
  expectError(file("shared.vtu", "94", false, ">0 1 2 3 4 5 1 6 7 8 9 10 |>1 1 1 1 1 1 1 1 1 1 1 1 "),
              "more than two polyhedra");
  expectError(file("both.vtu", "94", false,
                   "</Cells>|<DataArray type=\"Int64\" Name=\"faces\" format=\"ascii\">0</DataArray></Cells>"),
              "both polyhedron layouts");
}

// Our zlib-compressed export (inline base64, header and blocks encoded apart, UInt64 header) with
// every block compressed again by `codec` ("lz4" or "lzma", as VTK's compressors do it: each block
// on its own, LZ4's block format or an .xz stream). `spoil` corrupts the first block of each array.
std::string recompressed(const std::string& zlib_text, const std::string& codec, bool spoil = false) {
  std::string text = zlib_text;
  const std::string from = "vtkZLibDataCompressor";
  text.replace(text.find(from), from.size(), codec == "lz4" ? "vtkLZ4DataCompressor" : "vtkLZMADataCompressor");
  auto word = [](const std::vector<uint8_t>& b, size_t i) {
    uint64_t v = 0;
    std::memcpy(&v, b.data() + 8 * i, 8);
    return v;
  };
  const std::string tag = "format=\"binary\">";
  for (size_t at = text.find(tag); at != std::string::npos; at = text.find(tag, at)) {
    at += tag.size();
    while (std::isspace(static_cast<unsigned char>(text[at]))) ++at;
    const size_t end = text.find('<', at);
    const std::string b64 = text.substr(at, end - at);
    const std::vector<uint8_t> first = fromBase64(b64.substr(0, 32));
    const size_t nblocks = word(first, 0), head_bytes = (3 + nblocks) * 8, head_chars = (head_bytes + 2) / 3 * 4;
    std::vector<uint8_t> head = fromBase64(b64.substr(0, head_chars));
    const std::vector<uint8_t> body = fromBase64(b64.substr(head_chars));
    std::vector<uint8_t> blocks;
    size_t in = 0;
    for (size_t b = 0; b < nblocks; ++b) {
      const size_t usize = (b + 1 == nblocks && word(head, 2)) ? word(head, 2) : word(head, 1);
      std::vector<uint8_t> raw(usize), packed(usize + usize / 2 + 1024);
      uLongf got = usize;
      EXPECT_EQ(uncompress(raw.data(), &got, body.data() + in, word(head, 3 + b)), Z_OK);
      in += word(head, 3 + b);
      size_t n = 0;
      if (codec == "lz4") {
        n = static_cast<size_t>(LZ4_compress_default(reinterpret_cast<const char*>(raw.data()),
                                                     reinterpret_cast<char*>(packed.data()), static_cast<int>(usize),
                                                     static_cast<int>(packed.size())));
      } else {
        EXPECT_EQ(
            lzma_easy_buffer_encode(6, LZMA_CHECK_CRC32, nullptr, raw.data(), usize, packed.data(), &n, packed.size()),
            LZMA_OK);
      }
      EXPECT_GT(n, 0u);
      if (spoil && b == 0)
        for (size_t i = n / 3; i < n / 3 + 8 && i < n; ++i) packed[i] ^= 0x5A;
      const uint64_t c = n;
      std::memcpy(head.data() + 8 * (3 + b), &c, 8);
      blocks.insert(blocks.end(), packed.begin(), packed.begin() + n);
    }
    const std::string out = base64Encode(head.data(), head.size()) + base64Encode(blocks.data(), blocks.size());
    text.replace(at, end - at, out);
    at += out.size();
  }
  return text;
}

// ParaView offers VTK's three compressors; files compressed by LZ4 or LZMA read as the zlib one does
// (FilesWrittenByVtkAndMeshioInEveryEncoding reads VTK's own, where VTK is installed; this
// test needs no Python, and spoils blocks).
TEST(Vtu, Lz4AndLzmaCompressedFilesReadLikeZlib) {
  const std::string dir = tempDir("vtu_codecs");
  const TetMesh mesh = makeTypedMesh();
  ExportOptions z;
  z.compress = true;
  ASSERT_TRUE(exportVtu(mesh, dir + "/z.vtu", z).isOk());
  const std::string zlib_text = readFile(dir + "/z.vtu");
  auto base = importMesh({dir + "/z.vtu"}, ImportOptions{});
  ASSERT_TRUE(base.isOk()) << base.status().message();
  for (const std::string codec : {"lz4", "lzma"}) {
    SCOPED_TRACE(codec);
    writeFile(dir + "/" + codec + ".vtu", recompressed(zlib_text, codec));
    auto r = importMesh({dir + "/" + codec + ".vtu"}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    expectSameMesh(r->mesh, base->mesh);
    writeFile(dir + "/bad_" + codec + ".vtu", recompressed(zlib_text, codec, true));
    expectError(dir + "/bad_" + codec + ".vtu", (codec == "lz4" ? "LZ4" : "LZMA") + std::string(" block 0 is corrupt"));
  }
  std::string other = zlib_text;
  other.replace(other.find("vtkZLibDataCompressor"), 21, "vtkZstdDataCompressor");
  writeFile(dir + "/other.vtu", other);
  expectError(dir + "/other.vtu", "compressor \"vtkZstdDataCompressor\" is not supported");
}

// A parallel file (.pvtu) names its pieces' .vtu files. Two unit cubes, one per piece; the first
// piece also carries a ghost copy of the second's cube (vtkGhostType 1), which is dropped.
TEST(Vtu, ParallelFilesReadTheirPieces) {
  const std::string dir = tempDir("vtu_parallel");
  auto cube = [](double x0) {
    std::string pts;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i)
          pts += std::to_string(x0 + i) + " " + std::to_string(j) + " " + std::to_string(k) + " ";
    return pts;
  };
  // Hexahedron corners of the 8 points above starting at `b` (VTK order).
  auto hex = [](int b) {
    std::string s;
    for (int v : {0, 1, 3, 2, 4, 5, 7, 6}) s += std::to_string(b + v) + " ";
    return s;
  };
  auto piece = [&](const std::string& points, int n_points, const std::string& conn, int n_cells,
                   const std::string& ghost, const std::string& ids, const char* ids_type) {
    std::string offsets, types;
    for (int c = 1; c <= n_cells; ++c) offsets += std::to_string(8 * c) + " ", types += "12 ";
    return R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian"><UnstructuredGrid>
<Piece NumberOfPoints=")" +
           std::to_string(n_points) + "\" NumberOfCells=\"" + std::to_string(n_cells) + R"(">
<CellData><DataArray type="UInt8" Name="vtkGhostType" format="ascii">)" +
           ghost + R"(</DataArray>
<DataArray type=")" +
           ids_type + R"(" Name="id" format="ascii">)" + ids + R"(</DataArray></CellData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">)" +
           points + R"(</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">)" +
           conn + R"(</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">)" +
           offsets + R"(</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">)" +
           types + R"(</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
)";
  };
  writeFile(dir + "/p_0.vtu", piece(cube(0) + cube(1), 16, hex(0) + hex(8), 2, "0 1", "0 1", "Int32"));
  writeFile(dir + "/p_1.vtu", piece(cube(1), 8, hex(0), 1, "0", "1", "Int32"));
  writeFile(dir + "/p_1i16.vtu", piece(cube(1), 8, hex(0), 1, "0", "1", "Int16"));
  const std::string pvtu = R"(<?xml version="1.0"?>
<VTKFile type="PUnstructuredGrid" version="1.0" byte_order="LittleEndian"><PUnstructuredGrid GhostLevel="1">
<PCellData><PDataArray type="UInt8" Name="vtkGhostType"/><PDataArray type="Int32" Name="id"/></PCellData>
<PPoints><PDataArray type="Float64" NumberOfComponents="3"/></PPoints>
<Piece Source="p_0.vtu"/>
<Piece Source="SECOND"/>
</PUnstructuredGrid></VTKFile>
)";
  auto withSecond = [&](const std::string& name, const std::string& second) {
    std::string text = pvtu;
    text.replace(text.find("SECOND"), 6, second);
    writeFile(dir + "/" + name, text);
    return dir + "/" + name;
  };
  auto r = importMesh({withSecond("p.pvtu", "p_1.vtu")}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numPoints(), 24u);  // the ghost cube's points stay, unused
  EXPECT_EQ(r->mesh.numTets(), 12u);
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_NEAR(s.total_volume, 2.0, 1e-12);
  EXPECT_EQ(s.unreferenced_points, 8u);
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);  // vtkGhostType is not data
  EXPECT_EQ(r->mesh.cell_fields[0].name, "id");
  std::vector<int32_t> ids(r->mesh.cell_fields[0].data<int32_t>(), r->mesh.cell_fields[0].data<int32_t>() + 12);
  EXPECT_EQ(std::count(ids.begin(), ids.end(), 0), 6);
  EXPECT_EQ(std::count(ids.begin(), ids.end(), 1), 6);
  // Every tetrahedron of the second cube has x >= 1 and id 1.
  for (size_t t = 0; t < 12; ++t) {
    double x = 0;
    for (uint32_t v : r->mesh.tets[t]) x += r->mesh.point(v)[0] / 4;
    EXPECT_EQ(x > 1, ids[t] == 1) << t;
  }
  const auto& w = r->report.warnings;
  EXPECT_TRUE(
      std::any_of(w.begin(), w.end(), [](const std::string& m) { return m.find("6 tetrahedra of ghost") == 0; }));

  // Welded, the pieces make one conforming block of two cubes: 12 points, the shared square inside.
  ImportOptions weld;
  weld.weld = true;
  auto welded = importMesh({dir + "/p.pvtu"}, weld);
  ASSERT_TRUE(welded.isOk()) << welded.status().message();
  EXPECT_EQ(welded->mesh.numPoints(), 12u);
  EXPECT_EQ(welded->report.welded_points, 12u);
  ASSERT_EQ(welded->mesh.numTets(), 12u);
  const MeshStats ws = computeMeshStats(welded->mesh);
  EXPECT_EQ(ws.boundary_faces, 20u);
  EXPECT_EQ(ws.non_manifold_faces, 0u);
  EXPECT_EQ(ws.unreferenced_points, 0u);
  EXPECT_NEAR(ws.total_volume, 2.0, 1e-12);
  EXPECT_EQ(welded->mesh.cell_fields[0].bytes, r->mesh.cell_fields[0].bytes);

  // Where the piece marks the ghost cube's points too (vtkGhostType DUPLICATEPOINT in its point
  // data, as VTK writes a ghost level), those that no cell left uses go with the ghost cell.
  {
    std::string marked = piece(cube(0) + cube(1), 16, hex(0) + hex(8), 2, "0 1", "0 1", "Int32");
    marked.insert(marked.find("<CellData>"),
                  "<PointData><DataArray type=\"UInt8\" Name=\"vtkGhostType\" format=\"ascii\">0 1 0 1 0 1 0 1 "
                  "1 1 1 1 1 1 1 1</DataArray></PointData>\n");
    writeFile(dir + "/m_0.vtu", marked);
    std::string text = pvtu;
    text.replace(text.find("p_0.vtu"), 7, "m_0.vtu");
    text.replace(text.find("SECOND"), 6, "p_1.vtu");
    writeFile(dir + "/m.pvtu", text);
    auto m = importMesh({dir + "/m.pvtu"}, ImportOptions{});
    ASSERT_TRUE(m.isOk()) << m.status().message();
    // The first cube's points at x = 1 are marked too (the second piece owns them) but its cell
    // uses them: they stay.
    EXPECT_EQ(m->mesh.numPoints(), 16u);
    EXPECT_EQ(computeMeshStats(m->mesh).unreferenced_points, 0u);
    EXPECT_NEAR(computeMeshStats(m->mesh).total_volume, 2.0, 1e-12);
    for (const Field& f : m->mesh.point_fields) EXPECT_NE(f.name, "vtkGhostType");
    const auto& mw = m->report.warnings;
    EXPECT_TRUE(std::any_of(mw.begin(), mw.end(), [](const std::string& x) {
      return x.find("8 points of ghost cells alone (vtkGhostType duplicates of other pieces' points) dropped") !=
             std::string::npos;
    })) << ::testing::PrintToString(mw);
  }

  expectError(withSecond("missing.pvtu", "p_9.vtu"), "p_9.vtu");
  expectError(withSecond("types.pvtu", "p_1i16.vtu"), "its array 'id' (1 int16) does not match");
  expectError(withSecond("self.pvtu", "self.pvtu"), "a piece of a parallel file is itself a parallel file");
  // A piece of another kind, and a FIFO (reading it would wait for a writer forever).
  writeFile(dir + "/img.vti", R"(<?xml version="1.0"?>
<VTKFile type="ImageData" version="0.1"><ImageData WholeExtent="0 1 0 1 0 1"><Piece Extent="0 1 0 1 0 1"/></ImageData></VTKFile>
)");
  expectError(withSecond("kind.pvtu", "img.vti"),
              "piece 1: " + dir + "/img.vti: a VTKFile of type \"ImageData\", not UnstructuredGrid");
  ASSERT_EQ(mkfifo((dir + "/fifo.vtu").c_str(), 0600), 0);
  expectError(withSecond("fifo.pvtu", "fifo.vtu"), "piece 1: " + dir + "/fifo.vtu: not a regular file");

  // The same two pieces as two <Piece> elements of one .vtu (vtkXMLUnstructuredGridWriter with
  // several pieces and a ghost level): the ghost copy is dropped there too.
  std::string both = piece(cube(0) + cube(1), 16, hex(0) + hex(8), 2, "0 1", "0 1", "Int32");
  const std::string second = piece(cube(1), 8, hex(0), 1, "0", "1", "Int32");
  const size_t second_piece = second.find("<Piece");
  both.insert(both.find("</UnstructuredGrid>"),
              second.substr(second_piece, second.find("</UnstructuredGrid>") - second_piece));
  writeFile(dir + "/both.vtu", both);
  auto one = importMesh({dir + "/both.vtu"}, ImportOptions{});
  ASSERT_TRUE(one.isOk()) << one.status().message();
  EXPECT_EQ(one->mesh.numTets(), 12u);
  EXPECT_NEAR(computeMeshStats(one->mesh).total_volume, 2.0, 1e-12);
  ASSERT_EQ(one->mesh.cell_fields.size(), 1u);
  const auto& ow = one->report.warnings;
  EXPECT_TRUE(
      std::any_of(ow.begin(), ow.end(), [](const std::string& m) { return m.find("6 tetrahedra of ghost") == 0; }));
  EXPECT_TRUE(std::any_of(ow.begin(), ow.end(), [](const std::string& m) { return m.find("2 pieces read") == 0; }));
  // A piece alone keeps its ghost copy (no other piece owns it here), and says so.
  auto alone = importMesh({dir + "/p_0.vtu"}, ImportOptions{});
  ASSERT_TRUE(alone.isOk()) << alone.status().message();
  EXPECT_EQ(alone->mesh.numTets(), 12u);
  ASSERT_EQ(alone->report.warnings.size(), 1u);
  EXPECT_EQ(alone->report.warnings[0].find("1 cells are ghost copies of another piece's cells"), 0u)
      << alone->report.warnings[0];
}

// A <Piece> of one hexahedron, its corners (VTK order) at `corners`, stored in the order `order` (the
// stored point k is corner order[k]).
std::string hexPiece(const std::vector<std::array<double, 3>>& corners, const std::array<int, 8>& order) {
  std::string points, conn;
  std::array<int, 8> stored_at{};
  for (int k = 0; k < 8; ++k) {
    stored_at[order[k]] = k;
    for (double v : corners[order[k]]) points += std::to_string(v) + " ";
  }
  for (int c = 0; c < 8; ++c) conn += std::to_string(stored_at[c]) + " ";
  return R"(<Piece NumberOfPoints="8" NumberOfCells="1">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">)" +
         points + R"(</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">)" +
         conn + R"(</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">8</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">12</DataArray></Cells>
</Piece>
)";
}

// Two hexahedra side by side in two pieces of a .vtu, the second numbering its points in another
// order: welded, the face rule sees the points they share as one, so both cut their common face
// along the same diagonal and it is inside the mesh, not a non-conforming interface.
TEST(Vtu, WeldedPiecesCutTheFacesTheyShareAlike) {
  const std::string dir = tempDir("vtu_weld_seam");
  auto cube = [](double x0) {
    std::vector<std::array<double, 3>> c;
    for (const auto& [dx, dy, dz] : std::vector<std::array<double, 3>>{
             {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}})
      c.push_back({x0 + dx, dy, dz});
    return c;
  };
  // In the second piece the shared face's corner (1, 1, 0) comes first: the face's smallest index
  // sits elsewhere than in the first piece, at (1, 0, 0).
  writeFile(dir + "/p.vtu", R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian"><UnstructuredGrid>
)" + hexPiece(cube(0), {0, 1, 2, 3, 4, 5, 6, 7}) +
                                hexPiece(cube(1), {3, 0, 1, 2, 4, 5, 6, 7}) + "</UnstructuredGrid></VTKFile>\n");
  for (int split : {5, 6}) {
    SCOPED_TRACE(split);
    ImportOptions weld;
    weld.weld = true;
    weld.split = split;
    auto r = importMesh({dir + "/p.vtu"}, weld);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->report.welded_points, 4u);
    EXPECT_EQ(r->report.collapsed_tets, 0u);
    const MeshStats s = computeMeshStats(r->mesh);
    EXPECT_EQ(s.points, 12u);
    EXPECT_EQ(s.boundary_faces, 20u);
    EXPECT_EQ(s.non_manifold_faces, 0u);
    EXPECT_NEAR(s.total_volume, 2.0, 1e-12);
    ValidationReport report;
    checkMesh(r->mesh, "/mesh", report);
    EXPECT_FALSE(report.hasErrors()) << report.toText("p.vtu");
    EXPECT_EQ(report.count(IssueCode::kNonconformingInterface), 0u) << report.toText("p.vtu");
  }
}

// --weld on a VTK file: the second tetrahedron has two bit-identical corners, so welding flattens
// it; it goes with its cell value, and the first keeps its own.
TEST(Vtu, WeldDropsCollapsedTetrahedraWithTheirCellValues) {
  const std::string dir = tempDir("vtu_weld");
  writeFile(dir + "/w.vtu", R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian"><UnstructuredGrid>
<Piece NumberOfPoints="8" NumberOfCells="3">
<PointData><DataArray type="Int32" Name="id" format="ascii">0 1 2 3 4 5 6 7</DataArray></PointData>
<CellData><DataArray type="Float64" Name="w" format="ascii">0.5 0.25 0.125</DataArray></CellData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1  5 0 0 6 0 0 5 1 0 5 0 0</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3  4 5 6 7  1 2 3 7</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">4 8 12</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">10 10 10</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
)");
  auto plain = importMesh({dir + "/w.vtu"}, ImportOptions{});
  ASSERT_TRUE(plain.isOk()) << plain.status().message();
  EXPECT_EQ(plain->mesh.numTets(), 3u);
  EXPECT_EQ(plain->report.zero_volume, 1u);  // corners 4 and 7 coincide
  ImportOptions weld;
  weld.weld = true;
  auto r = importMesh({dir + "/w.vtu"}, weld);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->report.welded_points, 1u);
  EXPECT_EQ(r->report.collapsed_tets, 1u);
  EXPECT_EQ(r->report.zero_volume, 0u);  // the flat tetrahedron is gone
  EXPECT_EQ(r->mesh.numPoints(), 7u);
  ASSERT_EQ(r->mesh.numTets(), 2u);
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r->mesh.cell_fields[0].itemCount(), 2u);
  EXPECT_EQ(r->mesh.cell_fields[0].data<double>()[0], 0.5);
  EXPECT_EQ(r->mesh.cell_fields[0].data<double>()[1], 0.125);
  // The third tetrahedron's corner 7 became point 4 (the first of the two), point values kept.
  EXPECT_EQ(r->mesh.point_fields[0].data<int32_t>()[4], 4);
  EXPECT_EQ(r->mesh.point_fields[0].data<int32_t>()[6], 6);
}

// --weld merges points at the same position whatever their values: where the pieces of a .pvtu give
// a shared point other values (a field discontinuous across a seam), the first point's are kept, and
// the import says so, per field, with the count; values that agree say nothing. Under --weld the
// "kept once per piece" remark is not made.
TEST(Vtu, WeldSaysWhenWeldedPointsHadOtherValues) {
  const std::string dir = tempDir("vtu_weld_values");
  auto piece = [](const std::string& points, const std::string& t, const std::string& id) {
    return R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian"><UnstructuredGrid>
<Piece NumberOfPoints="4" NumberOfCells="1">
<PointData><DataArray type="Float64" Name="T" format="ascii">)" +
           t + R"(</DataArray><DataArray type="Int32" Name="id" format="ascii">)" + id +
           R"(</DataArray></PointData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">)" +
           points + R"(</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">4</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">10</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
)";
  };
  // Two tetrahedra on either side of the triangle (1,0,0), (0,1,0), (0,0,1).
  writeFile(dir + "/a.vtu", piece("0 0 0 1 0 0 0 1 0 0 0 1", "1 2 3 4", "7 7 7 7"));
  writeFile(dir + "/b.vtu", piece("1 1 1 1 0 0 0 0 1 0 1 0", "5 20 40 30", "7 7 7 7"));
  writeFile(dir + "/d.pvtu", R"(<?xml version="1.0"?>
<VTKFile type="PUnstructuredGrid" version="1.0" byte_order="LittleEndian"><PUnstructuredGrid GhostLevel="0">
<PPointData><PDataArray type="Float64" Name="T"/><PDataArray type="Int32" Name="id"/></PPointData>
<PPoints><PDataArray type="Float64" NumberOfComponents="3"/></PPoints>
<Piece Source="a.vtu"/><Piece Source="b.vtu"/>
</PUnstructuredGrid></VTKFile>
)");
  ImportOptions weld;
  weld.weld = true;
  auto r = importMesh({dir + "/d.pvtu"}, weld);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->report.welded_points, 3u);
  EXPECT_EQ(r->mesh.numPoints(), 5u);
  const auto& w = r->report.warnings;
  auto said = [&](const std::string& text) {
    return std::any_of(w.begin(), w.end(), [&](const std::string& m) { return m.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(said("--weld merged points whose values differ ('T' at 3 of the welded points)"))
      << ::testing::PrintToString(w);
  EXPECT_FALSE(said("'id'")) << ::testing::PrintToString(w);
  EXPECT_FALSE(said("kept once per piece")) << ::testing::PrintToString(w);
  // The first piece's values are the ones kept.
  const Field* t = r->mesh.findPointField("T");
  ASSERT_NE(t, nullptr);
  std::vector<double> kept(t->data<double>(), t->data<double>() + 5);
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(kept, (std::vector<double>{1, 2, 3, 4, 5}));
  auto plain = importMesh({dir + "/d.pvtu"}, ImportOptions{});
  ASSERT_TRUE(plain.isOk());
  EXPECT_TRUE(std::any_of(plain->report.warnings.begin(), plain->report.warnings.end(),
                          [](const std::string& m) { return m.find("kept once per piece") != std::string::npos; }));
}

TEST(Vtu, MalformedFilesFailWithTheFileNamed) {
  const std::string dir = tempDir("vtu_bad");
  writeFile(dir + "/type.vtu", twoPieces("0 1 2 3", "66"));
  expectError(dir + "/type.vtu", "1 cell of type 66 (unknown)");
  writeFile(dir + "/poly.vtu", twoPieces("0 1 2 3", "42"));
  expectError(dir + "/poly.vtu", "VTK_POLYHEDRON cells without the faces and faceoffsets arrays");
  writeFile(dir + "/range.vtu", twoPieces("0 1 2 4", "10"));
  expectError(dir + "/range.vtu", "refers to point 4 but the piece has 4 points");
  // Counts and offsets that are not numbers (pugixml alone would read "abc" as 0).
  std::string words = twoPieces("0 1 2 3", "10");
  words.replace(words.find("NumberOfPoints=\"4\""), 18, "NumberOfPoints=\"abc\"");
  writeFile(dir + "/words.vtu", words);
  expectError(dir + "/words.vtu", "Piece 0: missing or bad NumberOfPoints/NumberOfCells");
  // A collection of files (.vtm, .pvd) names them.
  writeFile(dir + "/blocks.vtm", R"(<?xml version="1.0"?>
<VTKFile type="vtkMultiBlockDataSet" version="1.0"><vtkMultiBlockDataSet>
<DataSet index="0" file="blocks/blocks_0.vtu"/><DataSet index="1" file="blocks/blocks_1.vti"/>
</vtkMultiBlockDataSet></VTKFile>
)");
  expectError(dir + "/blocks.vtm",
              "is a collection of other files (blocks/blocks_0.vtu, blocks/blocks_1.vti): convert one");

  const TetMesh mesh = makeTypedMesh();
  ASSERT_TRUE(exportVtu(mesh, dir + "/plain.vtu", ExportOptions{}).isOk());
  ExportOptions z;
  z.compress = true;
  ASSERT_TRUE(exportVtu(mesh, dir + "/z.vtu", z).isOk());
  const std::string plain = readFile(dir + "/plain.vtu"), packed = readFile(dir + "/z.vtu");

  // Truncated base64: the Points array loses its last 40 characters.
  std::string cut = plain;
  const size_t pts_end = cut.find("</DataArray>", cut.find("Name=\"Points\""));
  cut.erase(pts_end - 41, 40);
  writeFile(dir + "/short_b64.vtu", cut);
  expectError(dir + "/short_b64.vtu", "Points: base64 data is cut short");
  // A corrupt zlib block: bytes inside the Points blocks changed (after the separately encoded header).
  std::string bad = packed;
  const size_t data_at = bad.find('\n', bad.find("Name=\"Points\"")) + 1 + 200;
  for (size_t i = 0; i < 30; ++i) bad[data_at + 32 + i] = bad[data_at + 32 + i] == 'A' ? 'B' : 'A';
  writeFile(dir + "/bad_zlib.vtu", bad);
  expectError(dir + "/bad_zlib.vtu", "zlib block 0 is corrupt");
  // Not base64 at all.
  std::string junk = plain;
  junk[pts_end - 10] = '*';
  writeFile(dir + "/junk.vtu", junk);
  expectError(dir + "/junk.vtu", "bad base64");
  // The XML cut in the middle.
  writeFile(dir + "/half.vtu", plain.substr(0, plain.size() / 2));
  expectError(dir + "/half.vtu", "not well-formed XML");
  // Raw appended data cut short (the XML part is intact).
  const std::string lv = readFile(dataPath("vtu/lv_guccione.vtu"));
  writeFile(dir + "/lv_cut.vtu", lv.substr(0, lv.size() - 100000));
  expectError(dir + "/lv_cut.vtu", "Piece 0");
  // Not a VTK file, and a VTK file of another kind.
  writeFile(dir + "/other.vtu", "<?xml version=\"1.0\"?><VTKFile type=\"PolyData\"></VTKFile>");
  expectError(dir + "/other.vtu", "VTKFile type \"PolyData\" is not supported");

  // Every prefix of a small compressed file fails cleanly (or, past the last array, still reads).
  for (const std::string* whole : {&packed, &plain}) {
    const size_t last = whole->rfind("</DataArray>");
    for (size_t n = 0; n < whole->size(); n += 97) {
      const std::string path = dir + "/prefix.vtu";
      writeFile(path, whole->substr(0, n));
      auto r = importVtu(path, ImportOptions{});
      if (r.isOk()) {
        EXPECT_GT(n, last) << "a prefix of " << n << " bytes was accepted";
      } else {
        EXPECT_EQ(r.status().message().rfind(path, 0), 0u) << r.status().message();
      }
    }
  }
}

TEST(Vtu, RandomlyCorruptedFilesNeverCrash) {
  // Bytes changed at random in files of every encoding: each import ends in a result or an error
  // naming the file (run under GTN_SANITIZE to catch what a plain build would not).
  const std::string dir = tempDir("vtu_corrupt");
  const TetMesh mesh = makeTypedMesh();
  ExportOptions z;
  z.compress = true;
  ASSERT_TRUE(exportVtu(mesh, dir + "/plain.vtu", ExportOptions{}).isOk());
  ASSERT_TRUE(exportVtu(mesh, dir + "/z.vtu", z).isOk());
  const std::vector<std::string> sources = {readFile(dir + "/plain.vtu"), readFile(dir + "/z.vtu"),
                                            readFile(dataPath("vtu/fire_ug.vtu"))};
  std::mt19937 rng(12345);
  const std::string path = dir + "/corrupt.vtu";
  size_t failed = 0, runs = 0;
  for (size_t s = 0; s < sources.size(); ++s) {
    const int iterations = s == 2 ? 10 : 150;
    for (int it = 0; it < iterations; ++it, ++runs) {
      std::string text = sources[s];
      const int changes = 1 + static_cast<int>(rng() % 4);
      for (int c = 0; c < changes; ++c) text[rng() % text.size()] = static_cast<char>(rng() % 256);
      writeFile(path, text);
      auto r = importVtu(path, ImportOptions{});
      if (!r.isOk()) {
        ++failed;
        EXPECT_EQ(r.status().message().rfind(path, 0), 0u) << r.status().message();
      }
    }
  }
  EXPECT_GT(failed, runs / 4);  // most corruptions are caught (the rest hit field values or whitespace)
}

TEST(Vtu, CliConvertsAndReportsCutFiles) {
  const std::string dir = tempDir("vtu_cli");
  const auto conv = test::runGtn("convert '" + dataPath("vtk/spx.vtk") + "' -o '" + dir + "/spx.vtu'");
  ASSERT_EQ(conv.exit_code, 0) << conv.err;
  ImportResult r = load(dir + "/spx.vtu");
  EXPECT_EQ(r.mesh.numTets(), 12936u);
  const std::string text = readFile(dir + "/spx.vtu");
  writeFile(dir + "/cut.vtu", text.substr(0, text.size() * 2 / 3));
  const auto info = test::runGtn("info '" + dir + "/cut.vtu'");
  EXPECT_TRUE(info.exit_code == 1 || info.exit_code == 3) << info.exit_code;
  EXPECT_NE(info.err.find(dir + "/cut.vtu"), std::string::npos) << info.err;
  EXPECT_EQ(std::count(info.err.begin(), info.err.end(), '\n'), 1) << info.err;
  EXPECT_TRUE(info.out.empty()) << info.out;
}

// vtkBitArray in VTK XML: type="Bit", one 0/1 per token in ASCII, packed eight to a byte (the first
// value in the high bit) in binary and appended data; read as UInt8.
TEST(Vtu, BitArraysReadAsBytes) {
  const std::string dir = tempDir("vtu_bits");
  auto file = [](const std::string& bits_array) {
    return std::string(R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" header_type="UInt32">
<UnstructuredGrid><Piece NumberOfPoints="5" NumberOfCells="2">
<PointData>)") +
           bits_array + R"(</PointData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1 1 1 1</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 1 2 3 4</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">4 8</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">10 10</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
)";
  };
  // 1 0 1 1 0 packed: 0xB0; the UInt32 size 1 and the byte, base64-encoded apart as VTK does.
  const uint8_t header[4] = {1, 0, 0, 0}, packed[1] = {0xB0};
  const std::string forms[2] = {R"(<DataArray type="Bit" Name="f" format="ascii">1 0 1 1 0</DataArray>)",
                                R"(<DataArray type="Bit" Name="f" format="binary">)" + base64Encode(header, 4) +
                                    base64Encode(packed, 1) + "</DataArray>"};
  for (const std::string& form : forms) {
    writeFile(dir + "/bits.vtu", file(form));
    auto r = importMesh({dir + "/bits.vtu"}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    ASSERT_EQ(r->mesh.point_fields.size(), 1u);
    EXPECT_EQ(r->mesh.point_fields[0].type, ScalarType::kUInt8);
    EXPECT_EQ(r->mesh.point_fields[0].bytes, (std::vector<uint8_t>{1, 0, 1, 1, 0})) << form;
  }
  writeFile(dir + "/two.vtu", file(R"(<DataArray type="Bit" Name="f" format="ascii">1 0 2 1 0</DataArray>)"));
  expectError(dir + "/two.vtu", "value 2 '2' is not a bit (0 or 1)");
  // Control bytes and bytes beyond ASCII in a bad value are shown as '?', not echoed raw.
  writeFile(dir + "/byte.vtu", file("<DataArray type=\"Bit\" Name=\"f\" format=\"ascii\">1 0 \x7f 1 0</DataArray>"));
  expectError(dir + "/byte.vtu", "value 2 '?' is not a bit (0 or 1)");
  const uint8_t header2[4] = {2, 0, 0, 0}, two_bytes[2] = {0xB0, 0};
  writeFile(dir + "/long.vtu", file(R"(<DataArray type="Bit" Name="f" format="binary">)" + base64Encode(header2, 4) +
                                    base64Encode(two_bytes, 2) + "</DataArray>"));
  expectError(dir + "/long.vtu", "holds 2 bytes, expected 1 (5 bits)");
}

// Inline binary arrays whose UInt32 header and data are base64-encoded together, as some writers
// do: a 1- or 2-byte array (the types of a one-cell mesh, a one-byte cell field) ends its first two
// quartets in one '=' or none, where VTK's encoding apart ends the header's in two. Both read alike,
// and so do arrays encoded apart.
TEST(Vtu, OneAndTwoByteArraysEncodedWithTheirHeader) {
  const std::string dir = tempDir("vtu_combined_b64");
  auto together = [](const std::vector<uint8_t>& data) {
    std::vector<uint8_t> all = {static_cast<uint8_t>(data.size()), 0, 0, 0};
    all.insert(all.end(), data.begin(), data.end());
    return base64Encode(all.data(), all.size());
  };
  auto apart = [](const std::vector<uint8_t>& data) {
    const uint8_t head[4] = {static_cast<uint8_t>(data.size()), 0, 0, 0};
    return base64Encode(head, 4) + base64Encode(data.data(), data.size());
  };
  for (auto encode : {+together, +apart}) {
    for (const std::vector<uint8_t>& labels : {std::vector<uint8_t>{7}, std::vector<uint8_t>{7, 9}}) {
      const size_t cells = labels.size();
      const std::vector<uint8_t> types(cells, 10);
      std::string conn = "0 1 2 3", offsets = "4";
      if (cells == 2) {
        conn += " 1 2 3 4";
        offsets += " 8";
      }
      const std::string text = std::string(R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" header_type="UInt32">
<UnstructuredGrid><Piece NumberOfPoints="5" NumberOfCells=")") +
                               std::to_string(cells) + R"(">
<CellData><DataArray type="UInt8" Name="label" format="binary">)" +
                               encode(labels) + R"(</DataArray></CellData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1 1 1 1</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">)" +
                               conn + R"(</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">)" +
                               offsets + R"(</DataArray>
<DataArray type="UInt8" Name="types" format="binary">)" +
                               encode(types) + R"(</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
)";
      const std::string path = dir + "/cells" + std::to_string(cells) + ".vtu";
      writeFile(path, text);
      auto r = importMesh({path}, ImportOptions{});
      ASSERT_TRUE(r.isOk()) << r.status().message() << "\n" << text;
      EXPECT_EQ(r->mesh.numTets(), cells);
      ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
      EXPECT_EQ(r->mesh.cell_fields[0].bytes, labels);
    }
  }
}

// VTK's Lagrange wedge (73) turns its first triangle towards the second one, its linear wedge (13)
// away from it: a positive cell of either kind splits into positive tetrahedra, none reported flipped.
TEST(Vtu, LagrangeAndLinearWedgesKeepTheirOrientation) {
  const std::string path = tempDir("vtu_wedges") + "/wedges.vtu";
  writeFile(path, R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" header_type="UInt32">
<UnstructuredGrid><Piece NumberOfPoints="12" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">
0 0 0  1 0 0  0 1 0  0 0 1  1 0 1  0 1 1
5 0 0  5 1 0  6 0 0  5 0 1  5 1 1  6 0 1</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 4 5 6 7 8 9 10 11</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">6 12</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">73 13</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
)");
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 6u);
  EXPECT_EQ(r->report.flipped, 0u);
}

// VTK 5 to 8 wrote string arrays as <DataArray type="String"> (VTK 9 as <Array>): skipped with a
// warning, in CellData as in PointData, not a failure of the whole file.
TEST(Vtu, StringDataArraysAreSkipped) {
  const std::string dir = tempDir("vtu_string_dataarray");
  const std::string path = dir + "/strings.vtu";
  writeFile(path, R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" header_type="UInt32">
<UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">
<PointData><DataArray type="String" Name="tag" format="ascii">97 0 98 0 99 0 100 0</DataArray>
<DataArray type="Float32" Name="t" format="ascii">1 2 3 4</DataArray></PointData>
<CellData><DataArray type="String" Name="mat" format="ascii">115 116 101 101 108 0</DataArray>
<DataArray type="Int32" Name="region" format="ascii">5</DataArray></CellData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">4</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">10</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
)");
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(r->mesh.point_fields.size(), 1u);
  EXPECT_EQ(r->mesh.point_fields[0].name, "t");
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r->mesh.cell_fields[0].name, "region");
  EXPECT_EQ(r->mesh.cell_fields[0].data<int32_t>()[0], 5);
  const std::vector<std::string> want = {
      "skipped <DataArray> 'tag' (String) of PointData: only numeric DataArrays are mesh data",
      "skipped <DataArray> 'mat' (String) of CellData: only numeric DataArrays are mesh data"};
  EXPECT_EQ(r->report.warnings, want);
}

// VTK's blanking of structured grids (BlankCell, BlankPoint): cells marked HIDDENCELL, or with a
// corner marked HIDDENPOINT, are holes and are dropped, as PLOT3D IBLANK holes are.
TEST(Vtu, BlankedStructuredCellsAreDropped) {
  const std::string dir = tempDir("vtu_blanking");
  // A 3 x 3 x 2 grid of points: 4 cells. Cell 0 hidden; point 8 (i = 2, j = 2, k = 0) hidden, a corner
  // of cell 3 only.
  std::string xyz;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) xyz += std::to_string(i) + " " + std::to_string(j) + " " + std::to_string(k) + " ";
  const std::string text = R"(<?xml version="1.0"?>
<VTKFile type="StructuredGrid" version="0.1"><StructuredGrid WholeExtent="0 2 0 2 0 1"><Piece Extent="0 2 0 2 0 1">
<PointData><DataArray type="UInt8" Name="vtkGhostType" format="ascii">0 0 0 0 0 0 0 0 2 0 0 0 0 0 0 0 0 0</DataArray></PointData>
<CellData><DataArray type="UInt8" Name="vtkGhostType" format="ascii">32 0 0 0</DataArray>
<DataArray type="Int32" Name="zone" format="ascii">10 11 12 13</DataArray></CellData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">)" +
                           xyz + R"(</DataArray></Points>
</Piece></StructuredGrid></VTKFile>
)";
  writeFile(dir + "/b.vts", text);
  auto r = importMesh({dir + "/b.vts"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 12u);  // cells 1 and 2, six tetrahedra each
  EXPECT_EQ(r->report.dropped_cells, 2u);
  const Field* zone = nullptr;
  for (const Field& f : r->mesh.cell_fields)
    if (f.name == "zone") zone = &f;
  ASSERT_NE(zone, nullptr);
  EXPECT_EQ(zone->get(0, 0), 11);
  EXPECT_EQ(zone->get(11, 0), 12);
  EXPECT_NEAR(computeMeshStats(r->mesh).total_volume, 2.0, 1e-12);
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("2 cells blanked by VTK"), std::string::npos) << r->report.warnings[0];
}

}  // namespace
}  // namespace gtn

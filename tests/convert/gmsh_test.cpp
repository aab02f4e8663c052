// gmsh .msh import: files written by the gmsh program in every variant (MSH 2.2 and 4.1, ASCII and
// binary), checked against meshio's reading of the same files; second-order and mixed meshes; data
// sections; byte order; sparse tags; damaged files.
#include <gtest/gtest.h>
#include <zlib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "convert/import.h"
#include "test_util.h"

namespace gtn {
namespace {

using test::allWarnings;
using test::findField;
using test::hasWarning;
using test::runGtn;
using test::runShell;
using test::tempDir;
using test::writeFile;

bool gmshAvailable(std::string* why) {
  if (runShell("gmsh -version").exit_code == 0) return true;
  *why = "the gmsh program is not installed (Debian package gmsh)";
  return false;
}

// Two boxes side by side (two physical volumes) and a physical surface, so that the file holds
// triangles too. Meshed by gmsh with `options`.
std::string makeGmshFile(const std::string& dir, const std::string& name, const std::string& options) {
  const std::string geo = dir + "/boxes.geo";
  writeFile(geo,
            "SetFactory(\"OpenCASCADE\");\n"
            "Box(1) = {0, 0, 0, 1, 1, 1};\n"
            "Box(2) = {1, 0, 0, 0.8, 1, 1};\n"
            "BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }\n"
            "Mesh.MeshSizeMax = 0.35;\n"
            "Physical Volume(\"left\", 11) = {1};\n"
            "Physical Volume(\"right\", 12) = {2};\n"
            "Physical Surface(\"bottom\", 5) = {Surface In BoundingBox{-1, -1, -0.1, 3, 2, 0.1}};\n");
  const std::string out = dir + "/" + name;
  const auto r = runShell("gmsh -3 " + options + " '" + geo + "' -o '" + out + "'");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  return out;
}

// gmsh writes a view with its mesh: a 2.2 ASCII file with $NodeData (two time steps of "temp", the
// last x + 2y, and a 3-component "vel" = (x, y, z)) merged and saved again by gmsh in `version`, binary or not.
std::string makeGmshDataFile(const std::string& dir, const std::string& mesh_file, const std::string& version,
                             bool binary) {
  const std::string text = test::readFile(mesh_file);
  const size_t a = text.find("$Nodes\n") + 7, b = text.find("$EndNodes");
  std::istringstream in(text.substr(a, b - a));
  size_t n;
  in >> n;
  std::ostringstream step0, step1, vel;
  for (size_t i = 0; i < n; ++i) {
    long tag;
    double x, y, z;
    in >> tag >> x >> y >> z;
    char buf[200];
    std::snprintf(buf, sizeof buf, "%ld %.17g\n", tag, -x);
    step0 << buf;
    std::snprintf(buf, sizeof buf, "%ld %.17g\n", tag, x + 2 * y);
    step1 << buf;
    std::snprintf(buf, sizeof buf, "%ld %.17g %.17g %.17g\n", tag, x, y, z);
    vel << buf;
  }
  auto section = [&](const std::string& name, int step, int comps, const std::string& rows) {
    return "$NodeData\n1\n\"" + name + "\"\n1\n" + std::to_string(step) + ".0\n3\n" + std::to_string(step) + "\n" +
           std::to_string(comps) + "\n" + std::to_string(n) + "\n" + rows + "$EndNodeData\n";
  };
  const std::string with_data = dir + "/with_data.msh";
  writeFile(with_data, text + section("temp", 0, 1, step0.str()) + section("temp", 1, 1, step1.str()) +
                           section("vel", 0, 3, vel.str()));
  const std::string out = dir + "/data" + version + (binary ? "b" : "") + ".msh";
  const std::string geo = dir + "/save.geo";
  writeFile(geo, "Merge \"" + with_data + "\";\nPostProcessing.SaveMesh = 1;\nMesh.Binary = " + (binary ? "1" : "0") +
                     ";\nMesh.MshFileVersion = " + version + ";\nSave View[0] \"" + out + "\";\n");
  const auto r = runShell("gmsh -0 '" + geo + "' -o /dev/null");
  EXPECT_TRUE(test::fileExists(out)) << r.out << r.err;
  return out;
}

// What meshio reads from a .msh file: counts and CRC-32s of the points, of the tetrahedra's corners
// (each tetrahedron's 4 corners sorted, as orientation may differ), of the tags and of the point data.
const char* kMeshioScript = R"PY(
import sys, json, zlib
import numpy as np
import meshio
m = meshio.read(sys.argv[1])
def crc(a):
    return zlib.crc32(np.ascontiguousarray(a).tobytes())
tets = [i for i, c in enumerate(m.cells) if c.type.startswith("tetra")]
blocks = [m.cells[i].data[:, :4] for i in tets]
conn = np.concatenate(blocks).astype(np.int64) if blocks else np.zeros((0, 4), np.int64)
conn.sort(axis=1)
counts = {}
for c in m.cells:
    counts[c.type] = counts.get(c.type, 0) + len(c.data)
out = {"points": len(m.points), "tets": len(conn), "coords": crc(m.points.astype(np.float64)), "conn": crc(conn),
       "point_data": {k: crc(np.asarray(v, dtype=np.float64)) for k, v in m.point_data.items()
                      if not k.startswith("gmsh:")}, "types": counts}
for k in ("gmsh:physical", "gmsh:geometrical"):
    if k in m.cell_data and tets:
        out[k] = crc(np.concatenate([m.cell_data[k][i] for i in tets]).astype(np.int32))
print(json.dumps(out))
)PY";

nlohmann::json meshioRead(const std::string& dir, const std::string& path) {
  const std::string script = dir + "/meshio_read.py";
  if (!test::fileExists(script)) writeFile(script, kMeshioScript);
  const auto r = runShell("/usr/bin/python3 " + script + " '" + path + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  try {
    return nlohmann::json::parse(r.out);
  } catch (const std::exception&) {
    ADD_FAILURE() << "no JSON from meshio: " << r.out << r.err;
    return {};
  }
}

bool meshioAvailable(std::string* why) {
  if (runShell("/usr/bin/python3 -c 'import meshio'").exit_code == 0) return true;
  *why = "/usr/bin/python3 cannot import meshio (install python3-meshio)";
  return false;
}

uLong crcOf(const void* data, size_t bytes) {
  return crc32(0, static_cast<const Bytef*>(data), static_cast<uInt>(bytes));
}

// Compares our import of `path` (a pure tetrahedral mesh) with meshio's.
void expectAgreesWithMeshio(const std::string& dir, const std::string& path, const TetMesh& mesh) {
  const nlohmann::json seen = meshioRead(dir, path);
  ASSERT_TRUE(seen.contains("points")) << path;
  EXPECT_EQ(seen["points"], mesh.numPoints()) << path;
  EXPECT_EQ(seen["tets"], mesh.numTets()) << path;
  EXPECT_EQ(seen["coords"], crcOf(mesh.coords.data(), mesh.coords.size() * 8)) << path;
  std::vector<int64_t> conn;
  for (Tet t : mesh.tets) {
    std::sort(t.begin(), t.end());
    conn.insert(conn.end(), t.begin(), t.end());
  }
  EXPECT_EQ(seen["conn"], crcOf(conn.data(), conn.size() * 8)) << path;
  for (const char* tag : {"gmsh:physical", "gmsh:geometrical"}) {
    const Field* f = findField(mesh.cell_fields, tag);
    ASSERT_NE(f, nullptr) << path << " " << tag;
    ASSERT_TRUE(seen.contains(tag)) << path << " " << tag;
    EXPECT_EQ(seen[tag], crcOf(f->bytes.data(), f->bytes.size())) << path << " " << tag;
  }
  for (const auto& [name, crc] : seen["point_data"].items()) {
    const Field* f = findField(mesh.point_fields, name);
    ASSERT_NE(f, nullptr) << path << " " << name;
    EXPECT_EQ(crc, crcOf(f->bytes.data(), f->bytes.size())) << path << " " << name;
  }
}

const char* kVariants[][2] = {{"msh22", ""}, {"msh22", "-bin"}, {"msh41", ""}, {"msh41", "-bin"}};

TEST(GmshImport, EveryVariantWrittenByGmshAgreesWithMeshio) {
  std::string why;
  if (!gmshAvailable(&why) || !meshioAvailable(&why)) GTEST_SKIP() << why;
  const std::string dir = tempDir("gmsh_variants");
  size_t tets = 0, points = 0;
  for (const auto& v : kVariants) {
    for (const std::string order : {"1", "2"}) {
      const std::string name = std::string(v[0]) + v[1] + "_o" + order + ".msh";
      const std::string path =
          makeGmshFile(dir, name, std::string("-format ") + v[0] + " " + v[1] + " -order " + order);
      SCOPED_TRACE(name);
      EXPECT_EQ(detectInputFormat(path), InputFormat::kGmsh);
      auto r = importMesh({path}, ImportOptions{});
      ASSERT_TRUE(r.isOk()) << r.status().message();
      const TetMesh& m = r->mesh;
      EXPECT_GT(m.numTets(), 50u);
      const std::string version = std::string(v[0]) == "msh22" ? "2.2" : "4.1";
      EXPECT_EQ(*m.findMetadata("source.format"), "gmsh " + version + (v[1][0] ? " binary" : " ASCII"));
      // Both physical volumes, with their names.
      const Field* physical = findField(m.cell_fields, "gmsh:physical");
      ASSERT_NE(physical, nullptr);
      std::map<int32_t, size_t> groups;
      for (size_t t = 0; t < m.numTets(); ++t) ++groups[physical->data<int32_t>()[t]];
      EXPECT_EQ(groups.size(), 2u);
      EXPECT_GT(groups[11], 0u);
      EXPECT_GT(groups[12], 0u);
      EXPECT_EQ(*m.findMetadata("gmsh.physical_name.11"), "left");
      EXPECT_EQ(*m.findMetadata("gmsh.physical_name.12"), "right");
      // The bottom triangles are in the file and said to be skipped.
      EXPECT_TRUE(hasWarning(r->report, "cells of lower dimension (")) << allWarnings(r->report);
      EXPECT_TRUE(hasWarning(r->report, "triangle")) << allWarnings(r->report);
      if (order == "2") {
        EXPECT_TRUE(hasWarning(r->report, "tetrahedron10 (type 11)")) << allWarnings(r->report);
        // Mid-edge nodes are points that no tetrahedron uses.
        std::vector<uint8_t> used(m.numPoints());
        for (const Tet& t : m.tets)
          for (uint32_t p : t) used[p] = 1;
        EXPECT_LT(std::count(used.begin(), used.end(), 1), static_cast<long>(m.numPoints()) / 2);
      } else {
        // Every variant of the same mesh gives the same mesh.
        if (tets == 0) tets = m.numTets(), points = m.numPoints();
        EXPECT_EQ(m.numTets(), tets);
        EXPECT_EQ(m.numPoints(), points);
      }
      expectAgreesWithMeshio(dir, path, m);
    }
  }
}

TEST(GmshImport, NodeDataWrittenByGmshInEveryVariant) {
  std::string why;
  if (!gmshAvailable(&why)) GTEST_SKIP() << why;
  const std::string dir = tempDir("gmsh_data");
  const std::string mesh_file = makeGmshFile(dir, "plain.msh", "-format msh22");
  for (const std::string version : {"2.2", "4.1"}) {
    for (bool binary : {false, true}) {
      const std::string path = makeGmshDataFile(dir, mesh_file, version, binary);
      SCOPED_TRACE(path);
      auto r = importMesh({path}, ImportOptions{});
      ASSERT_TRUE(r.isOk()) << r.status().message();
      const TetMesh& m = r->mesh;
      const Field* temp = findField(m.point_fields, "temp");
      ASSERT_NE(temp, nullptr) << allWarnings(r->report);
      ASSERT_EQ(temp->components, 1u);
      ASSERT_EQ(temp->type, ScalarType::kFloat64);
      // The last time step: x + 2y at every point (as gmsh prints it again: to 16 digits).
      for (size_t p = 0; p < m.numPoints(); ++p)
        ASSERT_NEAR(temp->data<double>()[p], m.coords[3 * p] + 2 * m.coords[3 * p + 1], 1e-14) << p;
      EXPECT_TRUE(hasWarning(r->report, "$NodeData 'temp': read time step 1, the last of its 2 time steps"))
          << allWarnings(r->report);
      // Not compared with meshio: meshio 5 takes $NodeData rows in file order whatever their node tags
      // say (gmsh writes them in an order of its own), and refuses binary ones that are not in tag order.
    }
  }
}

// A gmsh extrusion of a surface of quadrangles and triangles: hexahedra and prisms.
TEST(GmshImport, RecombinedHexahedraAndPrisms) {
  std::string why;
  if (!gmshAvailable(&why)) GTEST_SKIP() << why;
  const std::string dir = tempDir("gmsh_recombine");
  const std::string geo = dir + "/ext.geo";
  writeFile(geo,
            "Point(1) = {0, 0, 0, 0.3}; Point(2) = {1, 0, 0, 0.3}; Point(3) = {1, 1, 0, 0.3};\n"
            "Point(4) = {0, 1, 0, 0.3}; Point(5) = {2, 0.5, 0, 0.3};\n"
            "Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n"
            "Line(5) = {2, 5}; Line(6) = {5, 3};\n"
            "Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n"
            "Curve Loop(2) = {5, 6, -2}; Plane Surface(2) = {2};\n"
            "Transfinite Curve{1, 2, 3, 4} = 4; Transfinite Surface{1}; Recombine Surface{1};\n"
            "Extrude {0, 0, 1} { Surface{1, 2}; Layers{3}; Recombine; }\n");
  for (const auto& v : kVariants) {
    const std::string path = dir + "/ext_" + v[0] + v[1] + ".msh";
    const auto g = runShell("gmsh -3 -format " + std::string(v[0]) + " " + v[1] + " '" + geo + "' -o '" + path + "'");
    ASSERT_EQ(g.exit_code, 0) << g.out << g.err;
    SCOPED_TRACE(path);
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    // 27 hexahedra (3x3x3) into 6 tetrahedra each, and the prisms of the triangle side into 3 (their
    // number as meshio counts them).
    size_t prisms = (r->mesh.numTets() - 27 * 6) / 3;
    if (meshioAvailable(&why)) {
      const nlohmann::json seen = meshioRead(dir, path);
      EXPECT_EQ(seen["types"]["hexahedron"], 27);
      prisms = seen["types"]["wedge"].get<size_t>();
    }
    EXPECT_GT(prisms, 0u);
    EXPECT_EQ(r->mesh.numTets(), 27 * 6 + 3 * prisms);
    // gmsh stores its elements positively, prisms turning their first triangle towards the second
    // (VTK's wedge turns it away): none of their tetrahedra is reported flipped.
    EXPECT_EQ(r->report.flipped, 0u);
    // No physical groups: MSH 2.2 writes 0 as each element's physical tag, MSH 4.1 nothing.
    if (const Field* physical = findField(r->mesh.cell_fields, "gmsh:physical")) {
      EXPECT_EQ(std::string(v[0]), "msh22");
      for (size_t t = 0; t < r->mesh.numTets(); ++t) EXPECT_EQ(physical->data<int32_t>()[t], 0);
    }
    ASSERT_NE(findField(r->mesh.cell_fields, "gmsh:geometrical"), nullptr);
    EXPECT_TRUE(hasWarning(r->report, "cells of lower dimension")) << allWarnings(r->report);
    // The split conforms: the converted file is valid.
    const auto c = runGtn("convert '" + path + "' -o '" + path + ".gtn'");
    ASSERT_EQ(c.exit_code, 0) << c.err;
    const auto val = runGtn("validate '" + path + ".gtn'");
    EXPECT_EQ(val.exit_code, 0) << val.out << val.err;
  }
}

// A volume in two physical groups: MSH 2.2 lists each of its elements twice (once per group), MSH
// 4.1 gives its entity two physical tags. Either way each element is read once, in the first group.
TEST(GmshImport, VolumeInTwoPhysicalGroups) {
  std::string why;
  if (!gmshAvailable(&why)) GTEST_SKIP() << why;
  const std::string dir = tempDir("gmsh_two_groups");
  const std::string geo = dir + "/two.geo";
  writeFile(geo,
            "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1, 1};\nMesh.MeshSizeMax = 0.5;\n"
            "Physical Volume(\"a\", 1) = {1};\nPhysical Volume(\"b\", 2) = {1};\n");
  size_t tets = 0;
  for (const auto& v : kVariants) {
    const std::string path = dir + "/two_" + v[0] + v[1] + ".msh";
    const auto g = runShell("gmsh -3 -format " + std::string(v[0]) + " " + v[1] + " '" + geo + "' -o '" + path + "'");
    ASSERT_EQ(g.exit_code, 0) << g.out << g.err;
    SCOPED_TRACE(path);
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const TetMesh& m = r->mesh;
    if (tets == 0) tets = m.numTets();
    EXPECT_EQ(m.numTets(), tets);
    std::set<Tet> distinct;
    for (Tet t : m.tets) {
      std::sort(t.begin(), t.end());
      distinct.insert(t);
    }
    EXPECT_EQ(distinct.size(), m.numTets());
    const Field* physical = findField(m.cell_fields, "gmsh:physical");
    ASSERT_NE(physical, nullptr);
    for (size_t t = 0; t < m.numTets(); ++t) ASSERT_EQ(physical->data<int32_t>()[t], 1);
    EXPECT_TRUE(hasWarning(r->report, std::string(v[0]) == "msh22"
                                          ? std::to_string(tets) + " volume elements repeated with the same nodes"
                                          : "1 volume entities belong to several physical groups"))
        << allWarnings(r->report);
  }
  // Partitioned: the volume is still one entity of the model, whatever its partitioned entities.
  const std::string parts = dir + "/two_parts.msh";
  const auto g = runShell("gmsh -3 -format msh41 -part 3 '" + geo + "' -o '" + parts + "'");
  ASSERT_EQ(g.exit_code, 0) << g.out << g.err;
  auto r = importMesh({parts}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const Field* physical = findField(r->mesh.cell_fields, "gmsh:physical");
  ASSERT_NE(physical, nullptr);
  for (size_t t = 0; t < r->mesh.numTets(); ++t) ASSERT_EQ(physical->data<int32_t>()[t], 1);
  EXPECT_TRUE(hasWarning(r->report, "1 volume entities belong to several physical groups")) << allWarnings(r->report);
}

// A mesh that gmsh partitions (-part 3) keeps its physical groups and entities: MSH 4.1 puts its elements
// in partitioned entities, listed in $PartitionedEntities with their physical tags and the entity they
// were cut from. Each tetrahedron, found by its corners, gets the fields it has in the file not partitioned.
TEST(GmshImport, PartitionedFilesKeepPhysicalGroupsAndEntities) {
  std::string why;
  if (!gmshAvailable(&why)) GTEST_SKIP() << why;
  const std::string dir = tempDir("gmsh_partitioned");
  using Corners = std::array<std::array<double, 3>, 4>;
  auto fieldsByCorners = [](const TetMesh& m) {
    std::map<Corners, std::pair<int32_t, int32_t>> by;
    const Field* physical = findField(m.cell_fields, "gmsh:physical");
    const Field* geometrical = findField(m.cell_fields, "gmsh:geometrical");
    EXPECT_NE(physical, nullptr);
    EXPECT_NE(geometrical, nullptr);
    if (physical == nullptr || geometrical == nullptr) return by;
    for (size_t t = 0; t < m.numTets(); ++t) {
      Corners c;
      for (int k = 0; k < 4; ++k)
        for (int a = 0; a < 3; ++a) c[k][a] = m.coords[3 * m.tets[t][k] + a];
      std::sort(c.begin(), c.end());
      by[c] = {physical->data<int32_t>()[t], geometrical->data<int32_t>()[t]};
    }
    return by;
  };
  for (const std::string binary : {"", "-bin"}) {
    // ASCII coordinates are rounded: compare with the same mesh written the same way.
    const std::string whole = makeGmshFile(dir, "whole" + binary + ".msh", "-format msh41 " + binary);
    const std::string path = makeGmshFile(dir, "parts" + binary + ".msh", "-format msh41 -part 3 " + binary);
    SCOPED_TRACE(path);
    auto w = importMesh({whole}, ImportOptions{});
    ASSERT_TRUE(w.isOk()) << w.status().message();
    const auto expected = fieldsByCorners(w->mesh);
    std::set<int32_t> groups;
    for (const auto& entry : expected) groups.insert(entry.second.first);
    EXPECT_EQ(groups, (std::set<int32_t>{11, 12}));
    ASSERT_NE(test::readFile(path).find("$PartitionedEntities"), std::string::npos);
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->mesh.numTets(), w->mesh.numTets());
    const auto got = fieldsByCorners(r->mesh);
    size_t differ = 0;
    for (const auto& [corners, fields] : got) {
      auto it = expected.find(corners);
      if (it == expected.end() || it->second != fields) ++differ;
    }
    EXPECT_EQ(got.size(), expected.size());
    EXPECT_EQ(differ, 0u) << "tetrahedra whose gmsh:physical or gmsh:geometrical differ from the unpartitioned file's";
    EXPECT_EQ(*r->mesh.findMetadata("gmsh.physical_name.11"), "left");
    EXPECT_FALSE(hasWarning(r->report, "PartitionedEntities")) << allWarnings(r->report);
  }
}

// gmsh -save_parametric writes MSH 2 nodes as $ParametricNodes (each node's entity, then its curve or
// surface parameters): the same mesh as without. By hand: nodes on a point, a curve, a surface, a
// volume and (text only) on no entity.
TEST(GmshImport, ParametricNodesOfMsh2) {
  std::string why;
  if (!gmshAvailable(&why)) GTEST_SKIP() << why;
  const std::string dir = tempDir("gmsh_parametric");
  for (const std::string binary : {"", "-bin"}) {
    const std::string plain = makeGmshFile(dir, "plain" + binary + ".msh", "-format msh22 " + binary);
    const std::string path = makeGmshFile(dir, "param" + binary + ".msh", "-format msh22 -save_parametric " + binary);
    SCOPED_TRACE(path);
    ASSERT_NE(test::readFile(path).find("$ParametricNodes"), std::string::npos);
    auto a = importMesh({plain}, ImportOptions{});
    auto b = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(a.isOk()) << a.status().message();
    ASSERT_TRUE(b.isOk()) << b.status().message();
    EXPECT_EQ(b->mesh.coords, a->mesh.coords);
    EXPECT_EQ(b->mesh.tets, a->mesh.tets);
    ASSERT_EQ(b->mesh.cell_fields.size(), a->mesh.cell_fields.size());
    for (size_t f = 0; f < a->mesh.cell_fields.size(); ++f)
      EXPECT_EQ(b->mesh.cell_fields[f].bytes, a->mesh.cell_fields[f].bytes) << a->mesh.cell_fields[f].name;
    EXPECT_FALSE(hasWarning(b->report, "ParametricNodes")) << allWarnings(b->report);
  }
  const std::string text =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$ParametricNodes\n5\n"
      "1 0 0 0 0 7\n2 1 0 0 1 3 0.25\n3 0 1 0 2 4 0.5 0.75\n4 0 0 1\n5 0.2 0.2 0.2 3 1\n"
      "$EndParametricNodes\n$Elements\n1\n1 4 2 6 1 1 2 3 4\n$EndElements\n";
  writeFile(dir + "/hand.msh", text);
  auto r = importMesh({dir + "/hand.msh"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numPoints(), 5u);
  ASSERT_EQ(r->mesh.numTets(), 1u);
  EXPECT_EQ(r->mesh.point(4)[0], 0.2);
  EXPECT_EQ(r->mesh.point(3)[2], 1.0);
  // A dimension that no entity has is an error naming the node and the line.
  std::string bad = text;
  bad.replace(bad.find("2 4 0.5 0.75"), 1, "7");
  writeFile(dir + "/bad.msh", bad);
  auto e = importMesh({dir + "/bad.msh"}, ImportOptions{});
  ASSERT_FALSE(e.isOk());
  EXPECT_EQ(e.status().message(), dir + "/bad.msh:8: node 3: entity dimension 7 is not 0 to 3");
}

// A hand-written MSH 2.2 file: a hexahedron, a pyramid on it, a prism beside it and a tetrahedron on
// the prism, with sparse node tags, boundary elements, $ElementData and $ElementNodeData.
const char* kMixed =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n2\n3 1 \"solid\"\n2 9 \"skin\"\n$EndPhysicalNames\n"
    "$Nodes\n12\n"
    "10 0 0 0\n20 1 0 0\n30 1 1 0\n40 0 1 0\n50 0 0 1\n60 1 0 1\n70 1 1 1\n80 0 1 1\n"
    "900 0.5 0.5 1.5\n1000 2 0 0\n1100 2 0 1\n123456789 2 1 1.5\n"
    "$EndNodes\n"
    "$Elements\n6\n"
    "1 5 2 1 4 10 20 30 40 50 60 70 80\n"
    "2 7 2 1 4 50 60 70 80 900\n"
    "3 6 2 1 5 20 1000 30 60 1100 70\n"
    "4 4 2 1 5 60 1100 70 123456789\n"
    "5 2 2 9 3 10 20 30\n"
    "6 15 2 9 3 10\n"
    "$EndElements\n"
    "$ElementData\n1\n\"heat\"\n1\n0.0\n3\n0\n2\n5\n1 1.5 -1\n2 2.5 -2\n3 3.5 -3\n4 4.5 -4\n5 9 9\n$EndElementData\n"
    "$ElementNodeData\n1\n\"en\"\n1\n0.0\n3\n0\n1\n1\n4 4 1 2 3 4\n$EndElementNodeData\n";

TEST(GmshImport, MixedCellsSparseTagsAndElementData) {
  const std::string dir = tempDir("gmsh_mixed");
  const std::string path = dir + "/mixed.msh";
  writeFile(path, kMixed);
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  EXPECT_EQ(m.numPoints(), 12u);
  EXPECT_EQ(m.numTets(), 6u + 2u + 3u + 1u);
  EXPECT_EQ(m.point(11)[2], 1.5);
  const Field* heat = findField(m.cell_fields, "heat");
  ASSERT_NE(heat, nullptr);
  ASSERT_EQ(heat->components, 2u);
  // The hexahedron's 6 tetrahedra carry its values, the pyramid's 2 its own, and so on.
  std::map<double, size_t> per_value;
  for (size_t t = 0; t < m.numTets(); ++t) ++per_value[heat->data<double>()[2 * t]];
  EXPECT_EQ(per_value, (std::map<double, size_t>{{1.5, 6}, {2.5, 2}, {3.5, 3}, {4.5, 1}}));
  const Field* physical = findField(m.cell_fields, "gmsh:physical");
  const Field* geometrical = findField(m.cell_fields, "gmsh:geometrical");
  ASSERT_NE(physical, nullptr);
  ASSERT_NE(geometrical, nullptr);
  size_t in4 = 0;
  for (size_t t = 0; t < m.numTets(); ++t) {
    EXPECT_EQ(physical->data<int32_t>()[t], 1);
    in4 += geometrical->data<int32_t>()[t] == 4;
  }
  EXPECT_EQ(in4, 8u);
  EXPECT_EQ(*m.findMetadata("gmsh.physical_name.1"), "solid");
  EXPECT_EQ(m.findMetadata("gmsh.physical_name.9"), nullptr);
  EXPECT_TRUE(hasWarning(r->report, "skipped 2 cells of lower dimension (1 triangle (type 2), 1 point (type 15))"))
      << allWarnings(r->report);
  EXPECT_TRUE(hasWarning(r->report, "1 $ElementData values of skipped lower-dimension elements not read"))
      << allWarnings(r->report);
  EXPECT_TRUE(hasWarning(r->report, "skipped 1 $ElementNodeData sections")) << allWarnings(r->report);

  // gtn convert, info and validate take it.
  const auto c = runGtn("convert '" + path + "' -o '" + dir + "/mixed.gtn'");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto info = runGtn("info '" + path + "'");
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE((info.out + info.err).find("12"), std::string::npos);
  const auto val = runGtn("validate '" + path + "'");
  EXPECT_EQ(val.exit_code, 0) << val.out << val.err;
  const auto val2 = runGtn("validate '" + dir + "/mixed.gtn'");
  EXPECT_EQ(val2.exit_code, 0) << val2.out << val2.err;
}

// A $NodeData that gives a node two different values (two sections of one time step, or a row
// repeated) keeps the last and says so; the same value twice (partitions repeat their shared nodes)
// says nothing. The same for $ElementData.
TEST(GmshImport, DataGivenTwiceDifferentlyKeepsTheLastAndWarns) {
  const std::string dir = tempDir("gmsh_twice");
  const std::string head =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
      "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n"
      "$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 2 3 4 5\n$EndElements\n";
  auto nodeData = [](const std::string& rows, int n) {
    return "$NodeData\n1\n\"p\"\n1\n0.0\n3\n0\n1\n" + std::to_string(n) + "\n" + rows + "$EndNodeData\n";
  };
  const std::string elementData = "$ElementData\n1\n\"q\"\n1\n0.0\n3\n0\n1\n3\n1 10\n2 20\n1 11\n$EndElementData\n";
  writeFile(dir + "/twice.msh",
            head + nodeData("1 1\n2 2\n3 3\n", 3) + nodeData("3 3\n4 4\n5 5\n1 7\n", 4) + elementData);
  auto r = importMesh({dir + "/twice.msh"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const Field* p = findField(r->mesh.point_fields, "p");
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->data<double>()[0], 7.0);
  EXPECT_EQ(p->data<double>()[2], 3.0);
  EXPECT_TRUE(hasWarning(r->report,
                         "$NodeData 'p' gives 1 points a second, different value in the same time step (the last "
                         "one is kept)"))
      << allWarnings(r->report);
  const Field* q = findField(r->mesh.cell_fields, "q");
  ASSERT_NE(q, nullptr);
  EXPECT_TRUE(hasWarning(r->report,
                         "$ElementData 'q' gives 1 volume cells a second, different value in the same time step (the "
                         "last one is kept)"))
      << allWarnings(r->report);
  // The same values repeated: no such warning.
  writeFile(dir + "/same.msh", head + nodeData("1 1\n2 2\n3 3\n", 3) + nodeData("3 3\n4 4\n5 5\n1 1\n", 4));
  auto same = importMesh({dir + "/same.msh"}, ImportOptions{});
  ASSERT_TRUE(same.isOk()) << same.status().message();
  EXPECT_EQ(allWarnings(same->report).find("different value"), std::string::npos) << allWarnings(same->report);
}

// Binary files written here in both byte orders and both versions: two tetrahedra, a $NodeData.
std::string binaryFile(bool big_endian, int version, int size_bytes = 8) {
  std::string s = version == 2 ? "$MeshFormat\n2.2 1 8\n" : "$MeshFormat\n4.1 1 " + std::to_string(size_bytes) + "\n";
  auto put = [&](const void* p, size_t n) {
    std::string b(static_cast<const char*>(p), n);
    if (big_endian) std::reverse(b.begin(), b.end());
    s += b;
  };
  auto i32 = [&](int32_t v) { put(&v, 4); };
  auto f64 = [&](double v) { put(&v, 8); };
  auto sz = [&](uint64_t v) {
    if (size_bytes == 4) {
      const uint32_t w = static_cast<uint32_t>(v);
      put(&w, 4);
    } else {
      put(&v, 8);
    }
  };
  i32(1);
  s += "\n$EndMeshFormat\n";
  const double xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  const int tags[5] = {7, 3, 99, 5, 1000};
  if (version == 2) {
    s += "$Nodes\n5\n";
    for (int i = 0; i < 5; ++i) {
      i32(tags[i]);
      for (double c : xyz[i]) f64(c);
    }
    s += "\n$EndNodes\n$Elements\n2\n";
    i32(4), i32(2), i32(2);  // type, count, tags
    i32(1), i32(3), i32(8), i32(7), i32(3), i32(99), i32(5);
    i32(2), i32(3), i32(8), i32(3), i32(99), i32(5), i32(1000);
    s += "\n$EndElements\n";
  } else {
    s += "$Entities\n";
    sz(0), sz(0), sz(0), sz(1);
    i32(8);
    for (int k = 0; k < 6; ++k) f64(0);
    sz(1), i32(3);
    sz(0);
    s += "\n$EndEntities\n$Nodes\n";
    sz(1), sz(5), sz(3), sz(1000);
    i32(3), i32(8), i32(1), sz(5);  // parametric: u v w after each point
    for (int t : tags) sz(static_cast<uint64_t>(t));
    for (int i = 0; i < 5; ++i) {
      for (double c : xyz[i]) f64(c);
      for (int k = 0; k < 3; ++k) f64(0.25);
    }
    s += "\n$EndNodes\n$Elements\n";
    sz(1), sz(2), sz(1), sz(2);
    i32(3), i32(8), i32(4), sz(2);
    sz(1), sz(7), sz(3), sz(99), sz(5);
    sz(2), sz(3), sz(99), sz(5), sz(1000);
    s += "\n$EndElements\n";
  }
  s += "$NodeData\n1\n\"t\"\n1\n0\n3\n0\n1\n5\n";
  for (int i = 0; i < 5; ++i) i32(tags[i]), f64(10.0 * i);
  s += "\n$EndNodeData\n";
  return s;
}

TEST(GmshImport, BinaryBothByteOrdersAndSizes) {
  const std::string dir = tempDir("gmsh_binary");
  for (int version : {2, 4}) {
    for (bool big : {false, true}) {
      for (int size_bytes : {4, 8}) {
        if (version == 2 && size_bytes == 4) continue;
        const std::string path =
            dir + "/b" + std::to_string(version) + (big ? "be" : "le") + std::to_string(size_bytes) + ".msh";
        writeFile(path, binaryFile(big, version, size_bytes));
        SCOPED_TRACE(path);
        auto r = importMesh({path}, ImportOptions{});
        ASSERT_TRUE(r.isOk()) << r.status().message();
        const TetMesh& m = r->mesh;
        ASSERT_EQ(m.numPoints(), 5u);
        ASSERT_EQ(m.numTets(), 2u);
        EXPECT_EQ(m.coords, (std::vector<double>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1}));
        const Field* t = findField(m.point_fields, "t");
        ASSERT_NE(t, nullptr);
        for (size_t p = 0; p < 5; ++p) EXPECT_EQ(t->data<double>()[p], 10.0 * p);
        const Field* physical = findField(m.cell_fields, "gmsh:physical");
        ASSERT_NE(physical, nullptr);
        EXPECT_EQ(physical->data<int32_t>()[1], 3);
        const Field* geometrical = findField(m.cell_fields, "gmsh:geometrical");
        ASSERT_NE(geometrical, nullptr);
        EXPECT_EQ(geometrical->data<int32_t>()[0], 8);
        std::vector<std::array<uint32_t, 4>> sorted;
        for (Tet q : m.tets) {
          std::sort(q.begin(), q.end());
          sorted.push_back(q);
        }
        EXPECT_EQ(sorted, (std::vector<std::array<uint32_t, 4>>{{0, 1, 2, 3}, {1, 2, 3, 4}}));
      }
    }
  }
}

// Damaged and hostile files: a clean error naming the file and the place, never a crash or a huge
// allocation.
TEST(GmshImport, DamagedFilesGiveCleanErrors) {
  const std::string dir = tempDir("gmsh_damaged");
  auto expectError = [&](const std::string& name, const std::string& text, const std::string& part) {
    const std::string path = dir + "/" + name;
    writeFile(path, text);
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_FALSE(r.isOk()) << name;
    EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(part), std::string::npos) << name << ": " << r.status().message();
  };
  const std::string mixed = kMixed;
  auto replaced = [](std::string s, const std::string& from, const std::string& to) {
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  expectError("badref.msh", replaced(mixed, "4 4 2 1 5 60 1100 70 123456789", "4 4 2 1 5 60 1100 70 12345"),
              ":29: element 4 (tetrahedron) refers to node 12345, which $Nodes does not define");
  expectError("hugenodes.msh", replaced(mixed, "$Nodes\n12\n", "$Nodes\n999999999999\n"),
              ":10: node count 999999999999 needs at least");
  expectError("hugeelements.msh", replaced(mixed, "$Elements\n6\n", "$Elements\n4000000000\n"),
              "element count 4000000000 needs at least");
  expectError("hugedata.msh", replaced(mixed, "3\n0\n2\n5\n", "3\n0\n2\n500000000000\n"), "needs at least");
  expectError("truncated.msh", mixed.substr(0, mixed.find("$EndElements") - 30), "file ends where");
  expectError("dupnode.msh", replaced(mixed, "1000 2 0 0", "900 2 0 0"), "node tag 900 occurs twice");
  expectError("badtype.msh", replaced(mixed, "6 15 2 9 3 10", "6 77 2 9 3 10"), "element type 77");
  expectError("counts.msh", replaced(mixed, "$Nodes\n12\n", "$Nodes\n11\n"), "expected $EndNodes");
  expectError("version.msh", replaced(mixed, "2.2 0 8", "4.0 0 8"), "MSH format version 4.0 is not read");
  expectError("datanode.msh", mixed + "$NodeData\n1\n\"x\"\n1\n0\n3\n0\n1\n1\n77 1\n$EndNodeData\n",
              "gives a value to node 77");
  expectError("nan.msh", replaced(mixed, "10 0 0 0", "10 nan 0 0"), "not finite");
  expectError("surface.msh",
              "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
              "$Elements\n1\n1 2 0 1 2 3\n$EndElements\n",
              "no volume elements, only 1 triangle (type 2)");

  // Binary: truncated anywhere, a damaged byte-order mark, a huge block count.
  const std::string bin = binaryFile(false, 4);
  for (size_t cut : {bin.size() / 4, bin.size() / 2, bin.size() - 30}) {
    const std::string path = dir + "/cut" + std::to_string(cut) + ".msh";
    writeFile(path, bin.substr(0, cut));
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_FALSE(r.isOk()) << cut;
    EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
  }
  std::string bad_one = bin;
  bad_one[bad_one.find("8\n") + 2] = 2;
  expectError("one.msh", bad_one, "neither little- nor big-endian");
  std::string huge = bin;
  const size_t nodes = huge.find("$Nodes\n") + 7;
  const uint64_t big = 1ull << 40;
  std::memcpy(&huge[nodes + 8], &big, 8);  // the node count
  expectError("hugebin.msh", huge, "at byte " + std::to_string(nodes + 8) + ": node count 1099511627776 needs");
}

// Truncations everywhere and a thousand byte changes of small ASCII and binary files: each import ends
// in a mesh or an error that names the file.
TEST(GmshImport, TruncatedAndMutatedFilesNeverCrash) {
  const std::string dir = tempDir("gmsh_mutated");
  const std::string path = dir + "/m.msh";
  std::mt19937 rng(36);
  size_t errors = 0, runs = 0;
  for (const std::string& original :
       {std::string(kMixed), binaryFile(false, 2), binaryFile(true, 4), binaryFile(false, 4, 4)}) {
    auto attempt = [&](const std::string& bytes) {
      writeFile(path, bytes);
      auto r = importMesh({path}, ImportOptions{});
      ++runs;
      if (!r.isOk()) {
        ++errors;
        ASSERT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
      }
    };
    for (size_t cut = 0; cut < original.size(); cut += 1 + cut % 5) attempt(original.substr(0, cut));
    for (int k = 0; k < 250; ++k) {
      std::string bytes = original;
      for (int changes = 1 + static_cast<int>(rng() % 3); changes > 0; --changes) {
        const size_t at = rng() % bytes.size();
        switch (rng() % 3) {
          case 0: bytes[at] = static_cast<char>(rng()); break;
          case 1: bytes[at] = "0123456789-$ \n\xff"[rng() % 15]; break;
          default: bytes.insert(at, std::to_string(rng())); break;
        }
      }
      attempt(bytes);
    }
  }
  EXPECT_GT(errors, runs / 2);  // most damage is detected, not read as another mesh
}

}  // namespace
}  // namespace gtn

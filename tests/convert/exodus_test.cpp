// Exodus II import: files written here with the Exodus library's own writer (mixed volume blocks,
// quadratic tetrahedra, blocks of lower dimension, nodal, element and global variables over several
// time steps, every netCDF container), read back and compared with VTK's Exodus reader and meshio;
// damaged and truncated files.
#include <exodusII.h>
#include <gtest/gtest.h>
#include <netcdf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "convert/import.h"
#include "mesh/mesh_stats.h"
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

// The mesh: a 4 x 2 x 2 grid of nodes (x fastest, node k+1 at (k % 4, k / 4 % 2, k / 8)), the cube
// [0,1] a HEX8, the cube [1,2] two WEDGE6, the cube [2,3] three pyramids from its corner (3,0,0): two
// PYRAMID5 and the third as two TETRA4. Under the hexahedron a TETRA10 on the triangle (0,0,0),
// (1,0,0), (1,1,0) with apex (0.5,0.3,-1) and its six mid-edge nodes. Then a QUAD4 block of two
// elements, a BAR2 block of three and a TRI3 block of one (lower dimension: skipped), and an empty
// block.
constexpr int kGridNodes = 16, kNodes = kGridNodes + 1 + 6;
int gridNode(int x, int y, int z) { return 1 + x + 4 * y + 8 * z; }

struct Block {
  int64_t id;
  const char* type;
  int nodes_per;
  std::vector<int64_t> conn;
  size_t elements() const { return nodes_per ? conn.size() / nodes_per : 0; }
};

std::vector<Block> blocks() {
  auto g = gridNode;
  std::vector<Block> b;
  b.push_back({10,
               "HEX8",
               8,
               {g(0, 0, 0), g(1, 0, 0), g(1, 1, 0), g(0, 1, 0), g(0, 0, 1), g(1, 0, 1), g(1, 1, 1), g(0, 1, 1)}});
  b.push_back({20,
               "WEDGE",
               6,
               {g(1, 0, 0), g(2, 0, 0), g(2, 1, 0), g(1, 0, 1), g(2, 0, 1), g(2, 1, 1),  //
                g(1, 0, 0), g(2, 1, 0), g(1, 1, 0), g(1, 0, 1), g(2, 1, 1), g(1, 1, 1)}});
  // Apex (3,0,0); bases: the face x = 2 and the face y = 1.
  b.push_back({30,
               "PYRAMID",
               5,
               {g(2, 0, 0), g(2, 1, 0), g(2, 1, 1), g(2, 0, 1), g(3, 0, 0),  //
                g(2, 1, 0), g(3, 1, 0), g(3, 1, 1), g(2, 1, 1), g(3, 0, 0)}});
  // The third pyramid, base z = 1, as two tetrahedra.
  b.push_back({40,
               "TETRA",
               4,
               {g(2, 0, 1), g(3, 0, 1), g(3, 1, 1), g(3, 0, 0), g(2, 0, 1), g(3, 1, 1), g(2, 1, 1), g(3, 0, 0)}});
  const int apex = kGridNodes + 1, m = kGridNodes + 2;
  b.push_back({50, "TETRA10", 10, {g(0, 0, 0), g(1, 0, 0), g(1, 1, 0), apex, m, m + 1, m + 2, m + 3, m + 4, m + 5}});
  b.push_back({60,
               "QUAD4",
               4,
               {g(0, 0, 0), g(1, 0, 0), g(1, 0, 1), g(0, 0, 1), g(1, 0, 0), g(2, 0, 0), g(2, 0, 1), g(1, 0, 1)}});
  b.push_back({70, "BAR2", 2, {g(0, 0, 0), g(1, 0, 0), g(1, 0, 0), g(2, 0, 0), g(2, 0, 0), g(3, 0, 0)}});
  b.push_back({80, "TRI3", 3, {g(0, 0, 1), g(1, 0, 1), g(1, 1, 1)}});
  b.push_back({90, "NULL", 0, {}});
  return b;
}

// Values: nodal temperature 1000 t + node, velocity (node, -node, t); element stress 100 t + 10 b +
// e (block index b, element e), pressure only on the HEX and WEDGE blocks; global energy 7 t.
double temperature(int t, int node) { return 1000.0 * t + node + 0.5; }
double stress(int t, size_t b, size_t e) {
  return 100.0 * t + 10.0 * static_cast<double>(b) + static_cast<double>(e) + 0.25;
}
double pressure(int t, size_t b, size_t e) { return -stress(t, b, e); }

struct WriteOptions {
  int mode = EX_CLOBBER;  // | EX_NETCDF4, EX_NORMAL_MODEL ...
  int word_size = 8;
  int steps = 3;
  bool sets = true;                  // a node set and a side set
  bool pressure_everywhere = false;  // else only on the HEX and WEDGE blocks
};

void check(int status, const char* what) { ASSERT_GE(status, 0) << what; }

void writeExodus(const std::string& path, const WriteOptions& o) {
  int comp_ws = 8, io_ws = o.word_size;
  const int exoid = ex_create(path.c_str(), o.mode, &comp_ws, &io_ws);
  ASSERT_GE(exoid, 0) << path;
  const std::vector<Block> bl = blocks();
  size_t num_elem = 0;
  for (const Block& b : bl) num_elem += b.elements();
  check(ex_put_init(exoid, "a mixed test mesh", 3, kNodes, static_cast<int64_t>(num_elem),
                    static_cast<int64_t>(bl.size()), o.sets ? 1 : 0, o.sets ? 1 : 0),
        "ex_put_init");
  std::vector<double> x(kNodes), y(kNodes), z(kNodes);
  for (int k = 0; k < kGridNodes; ++k) x[k] = k % 4, y[k] = k / 4 % 2, z[k] = k / 8;
  x[kGridNodes] = 0.5, y[kGridNodes] = 0.3, z[kGridNodes] = -1;
  // Mid-edge nodes of the TETRA10 (edges 0-1, 1-2, 2-0, 0-3, 1-3, 2-3).
  const double corner[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0.5, 0.3, -1}};
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (int e = 0; e < 6; ++e) {
    x[kGridNodes + 1 + e] = (corner[edges[e][0]][0] + corner[edges[e][1]][0]) / 2;
    y[kGridNodes + 1 + e] = (corner[edges[e][0]][1] + corner[edges[e][1]][1]) / 2;
    z[kGridNodes + 1 + e] = (corner[edges[e][0]][2] + corner[edges[e][1]][2]) / 2;
  }
  check(ex_put_coord(exoid, x.data(), y.data(), z.data()), "ex_put_coord");
  for (const Block& b : bl) {
    check(ex_put_elem_block(exoid, b.id, b.type, static_cast<int64_t>(b.elements()), b.nodes_per, 0),
          "ex_put_elem_block");
    if (b.elements() == 0) continue;
    std::vector<int> conn(b.conn.begin(), b.conn.end());
    check(ex_put_elem_conn(exoid, b.id, conn.data()), "ex_put_elem_conn");
  }
  if (o.sets) {
    const int nodes[] = {1, 2, 3};
    check(ex_put_node_set_param(exoid, 1, 3, 0), "ex_put_node_set_param");
    check(ex_put_node_set(exoid, 1, nodes), "ex_put_node_set");
    const int elems[] = {1}, sides[] = {5};
    check(ex_put_side_set_param(exoid, 2, 1, 0), "ex_put_side_set_param");
    check(ex_put_side_set(exoid, 2, elems, sides), "ex_put_side_set");
  }
  check(ex_put_variable_param(exoid, EX_NODAL, 4), "nodal variable count");
  const char* node_names[] = {"temperature", "velocity_x", "velocity_y", "velocity_z"};
  check(ex_put_variable_names(exoid, EX_NODAL, 4, const_cast<char**>(node_names)), "nodal names");
  check(ex_put_variable_param(exoid, EX_ELEM_BLOCK, 2), "element variable count");
  const char* elem_names[] = {"stress", "pressure"};
  check(ex_put_variable_names(exoid, EX_ELEM_BLOCK, 2, const_cast<char**>(elem_names)), "element names");
  std::vector<int> truth;
  for (size_t b = 0; b < bl.size(); ++b) {
    truth.push_back(1);
    truth.push_back(b < 2 || o.pressure_everywhere ? 1 : 0);
  }
  check(ex_put_truth_table(exoid, EX_ELEM_BLOCK, static_cast<int>(bl.size()), 2, truth.data()), "truth table");
  check(ex_put_variable_param(exoid, EX_GLOBAL, 1), "global variable count");
  const char* global_names[] = {"energy"};
  check(ex_put_variable_names(exoid, EX_GLOBAL, 1, const_cast<char**>(global_names)), "global names");
  for (int t = 1; t <= o.steps; ++t) {
    const double time = 0.5 * t;
    check(ex_put_time(exoid, t, &time), "ex_put_time");
    std::vector<double> v(kNodes);
    for (int k = 0; k < kNodes; ++k) v[k] = temperature(t, k);
    check(ex_put_var(exoid, t, EX_NODAL, 1, 1, kNodes, v.data()), "temperature");
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < kNodes; ++k) v[k] = c == 0 ? k : c == 1 ? -k : t;
      check(ex_put_var(exoid, t, EX_NODAL, 2 + c, 1, kNodes, v.data()), "velocity_");
    }
    for (size_t b = 0; b < bl.size(); ++b) {
      const size_t n = bl[b].elements();
      if (n == 0) continue;
      std::vector<double> s(n), p(n);
      for (size_t e = 0; e < n; ++e) s[e] = stress(t, b, e), p[e] = pressure(t, b, e);
      check(ex_put_var(exoid, t, EX_ELEM_BLOCK, 1, bl[b].id, static_cast<int64_t>(n), s.data()), "stress");
      if (b < 2 || o.pressure_everywhere)
        check(ex_put_var(exoid, t, EX_ELEM_BLOCK, 2, bl[b].id, static_cast<int64_t>(n), p.data()), "pressure");
    }
    const double energy = 7.0 * t;
    check(ex_put_var(exoid, t, EX_GLOBAL, 1, 0, 1, &energy), "energy");
  }
  check(ex_close(exoid), "ex_close");
}

StatusOr<ImportResult> load(const std::string& path, int step = 0) {
  ImportOptions o;
  o.exodus_time_step = step;
  return importMesh({path}, o);
}

// The per-cell values of a per-tetrahedron field: runs of equal values merged (every element's value
// differs from the next one's here), in tetrahedron order, which follows the elements.
std::vector<double> runs(const Field& f, uint32_t c = 0) {
  std::vector<double> out;
  for (size_t t = 0; t < f.itemCount(); ++t) {
    const double v = f.get(t, c);
    if (out.empty() || !(out.back() == v || (std::isnan(out.back()) && std::isnan(v)))) out.push_back(v);
  }
  return out;
}

void expectMesh(const ImportResult& r, int step, ScalarType value_type, const std::string& what) {
  const TetMesh& m = r.mesh;
  ASSERT_EQ(m.numPoints(), static_cast<size_t>(kNodes)) << what;
  // 6 (hexahedron) + 2 x 3 (wedges) + 2 x 2 (pyramids) + 2 + 1 tetrahedra.
  ASSERT_EQ(m.numTets(), 19u) << what;
  EXPECT_EQ(m.coord_type, value_type) << what;
  const MeshStats s = computeMeshStats(m);
  EXPECT_NEAR(s.total_volume, 3.0 + 1.0 / 6, 1e-12) << what;
  EXPECT_EQ(s.inverted, 0u) << what;
  EXPECT_EQ(s.non_manifold_faces, 0u) << what;
  // Blocks as a cell field, in block order.
  const Field* id = findField(m.cell_fields, "block_id");
  ASSERT_NE(id, nullptr) << what;
  EXPECT_EQ(runs(*id), (std::vector<double>{10, 20, 30, 40, 50})) << what;
  size_t per_block[5] = {0, 0, 0, 0, 0};
  for (size_t t = 0; t < m.numTets(); ++t) ++per_block[static_cast<int>(id->get(t, 0)) / 10 - 1];
  EXPECT_EQ(per_block[0], 6u);
  EXPECT_EQ(per_block[1], 6u);
  EXPECT_EQ(per_block[2], 4u);
  EXPECT_EQ(per_block[3], 2u);
  EXPECT_EQ(per_block[4], 1u);
  // Nodal variables of the step; the velocity components joined.
  const Field* temp = findField(m.point_fields, "temperature");
  const Field* vel = findField(m.point_fields, "velocity_");
  ASSERT_NE(temp, nullptr) << what;
  ASSERT_NE(vel, nullptr) << what;
  EXPECT_EQ(temp->type, value_type);
  EXPECT_EQ(vel->components, 3u);
  for (int k = 0; k < kNodes; ++k) {
    EXPECT_EQ(temp->get(k, 0), temperature(step, k)) << what << " node " << k;
    EXPECT_EQ(vel->get(k, 0), k);
    EXPECT_EQ(vel->get(k, 1), -k);
    EXPECT_EQ(vel->get(k, 2), step);
  }
  // Element variables, per element; pressure NaN where the truth table leaves it out.
  const Field* st = findField(m.cell_fields, "stress");
  const Field* pr = findField(m.cell_fields, "pressure");
  ASSERT_NE(st, nullptr) << what;
  ASSERT_NE(pr, nullptr) << what;
  std::vector<double> want_s, want_p;
  const size_t elements[5] = {1, 2, 2, 2, 1};
  for (size_t b = 0; b < 5; ++b)
    for (size_t e = 0; e < elements[b]; ++e) {
      want_s.push_back(stress(step, b, e));
      if (b < 2) want_p.push_back(pressure(step, b, e));
    }
  want_p.push_back(std::nan(""));
  EXPECT_EQ(runs(*st), want_s) << what;
  const std::vector<double> got_p = runs(*pr);
  ASSERT_EQ(got_p.size(), want_p.size()) << what;
  for (size_t i = 0; i + 1 < got_p.size(); ++i) EXPECT_EQ(got_p[i], want_p[i]) << what;
  EXPECT_TRUE(std::isnan(got_p.back())) << what;
  // Time, step and the global variable as metadata.
  ASSERT_NE(m.findMetadata("exodus.time_step"), nullptr);
  EXPECT_EQ(*m.findMetadata("exodus.time_step"), std::to_string(step) + " of 3");
  EXPECT_EQ(std::stod(*m.findMetadata("exodus.time")), 0.5 * step);
  EXPECT_EQ(std::stod(*m.findMetadata("exodus.global.energy")), 7.0 * step);
  EXPECT_EQ(*m.findMetadata("source.format"), "exodus");
  EXPECT_EQ(*m.findMetadata("exodus.title"), "a mixed test mesh");
  // What was left out, each said.
  const std::string all = allWarnings(r.report);
  EXPECT_TRUE(
      hasWarning(r.report, "skipped 6 elements of 14 that are not linear volume elements (3 BAR2, 2 QUAD4, 1 TRI3)"))
      << all;
  EXPECT_TRUE(hasWarning(r.report, "1 TETRA10 elements: only their corners are kept")) << all;
  EXPECT_TRUE(
      hasWarning(r.report, "element variable 'pressure' is not defined on element blocks 30, 40, 50: NaN there"))
      << all;
  EXPECT_TRUE(hasWarning(r.report, "skipped 1 node sets")) << all;
  EXPECT_TRUE(hasWarning(r.report, "skipped 1 side sets")) << all;
}

TEST(ExodusImport, MixedBlocksVariablesAndTimeSteps) {
  const std::string dir = tempDir("exodus-mixed");
  struct Case {
    const char* name;
    int mode;
    int word_size;
    const char* magic;
  };
  const Case cases[] = {
      {"classic.exo", EX_CLOBBER | EX_NORMAL_MODEL, 8, "CDF\x01"},
      {"large.e", EX_CLOBBER | EX_LARGE_MODEL, 8, "CDF\x02"},
      {"float.ex2", EX_CLOBBER, 4, "CDF"},
      {"hdf5.exo", EX_CLOBBER | EX_NETCDF4, 8, "\x89HDF"},
  };
  for (const Case& c : cases) {
    const std::string path = dir + "/" + c.name;
    WriteOptions o;
    o.mode = c.mode;
    o.word_size = c.word_size;
    writeExodus(path, o);
    EXPECT_EQ(test::readFile(path).rfind(c.magic, 0), 0u) << c.name;
    EXPECT_EQ(detectInputFormat(path), InputFormat::kExodus) << c.name;
    const ScalarType type = c.word_size == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
    auto last = load(path);
    ASSERT_TRUE(last.isOk()) << last.status().message();
    expectMesh(*last, 3, type, std::string(c.name) + " last step");
    EXPECT_TRUE(hasWarning(last->report, "read time step 3 (time 1.5), the last of 3; --time-step N reads another"))
        << allWarnings(last->report);
    for (int step : {1, 2}) {
      auto r = load(path, step);
      ASSERT_TRUE(r.isOk()) << r.status().message();
      expectMesh(*r, step, type, std::string(c.name) + " step " + std::to_string(step));
    }
    auto beyond = load(path, 4);
    ASSERT_FALSE(beyond.isOk());
    EXPECT_EQ(beyond.status().code(), StatusCode::kUsage);
    EXPECT_EQ(beyond.status().message(), path + ": --time-step 4: the file has time steps 1 to 3");
  }
  // Content, not the name, tells the format: an Exodus file named .bin (a PLOT3D extension) or
  // without an extension.
  ASSERT_EQ(
      runShell("cp " + dir + "/classic.exo " + dir + "/x.bin && cp " + dir + "/hdf5.exo " + dir + "/noext").exit_code,
      0);
  for (const char* name : {"x.bin", "noext"}) {
    auto r = load(dir + "/" + name);
    ASSERT_TRUE(r.isOk()) << name << ": " << r.status().message();
    EXPECT_EQ(r->mesh.numTets(), 19u);
  }
}

TEST(ExodusImport, NoTimeStepsAndNoSets) {
  const std::string dir = tempDir("exodus-static");
  WriteOptions o;
  o.steps = 0;
  o.sets = false;
  writeExodus(dir + "/m.exo", o);
  auto r = load(dir + "/m.exo");
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 19u);
  EXPECT_TRUE(r->mesh.point_fields.empty());
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r->mesh.cell_fields[0].name, "block_id");
  EXPECT_TRUE(hasWarning(r->report, "the file defines variables but holds no time step")) << allWarnings(r->report);
  EXPECT_FALSE(hasWarning(r->report, "sets")) << allWarnings(r->report);
  auto step = load(dir + "/m.exo", 1);
  ASSERT_FALSE(step.isOk());
  EXPECT_EQ(step.status().message(), dir + "/m.exo: --time-step 1: the file has no time steps");
}

// A file as meshio writes it, with the netCDF library and no file_size attribute: each nodal variable
// in its own netCDF variable (time_step, num_nodes), a vector as (time_step, num_nodes, 3). The Exodus
// library looks for them elsewhere and finds nothing (a warning); they are read with netCDF. A name
// without values is NaN with a warning, never zeros.
void writeMeshioStyle(const std::string& path, int format, bool with_values) {
  int nc = -1;
  auto ok = [](int status) { ASSERT_EQ(status, NC_NOERR) << nc_strerror(status); };
  ok(nc_create(path.c_str(), NC_CLOBBER | format, &nc));
  const double coords[3][5] = {{0, 1, 0, 0, 0.3}, {0, 0, 1, 0, 0.3}, {0, 0, 0, 1, -1}};
  const long long conn[2][4] = {{1, 2, 3, 4}, {1, 3, 2, 5}};
  int num_nodes, num_dim, num_elem, num_el_blk, len_string, time_step, in_blk, per_el, num_nod_var, vec;
  ok(nc_def_dim(nc, "num_nodes", 5, &num_nodes));
  ok(nc_def_dim(nc, "num_dim", 3, &num_dim));
  ok(nc_def_dim(nc, "num_elem", 2, &num_elem));
  ok(nc_def_dim(nc, "num_el_blk", 1, &num_el_blk));
  ok(nc_def_dim(nc, "len_string", 33, &len_string));
  ok(nc_def_dim(nc, "time_step", NC_UNLIMITED, &time_step));
  ok(nc_def_dim(nc, "num_el_in_blk1", 2, &in_blk));
  ok(nc_def_dim(nc, "num_nod_per_el1", 4, &per_el));
  ok(nc_def_dim(nc, "num_nod_var", 2, &num_nod_var));
  ok(nc_def_dim(nc, "dim_nod_var11", 3, &vec));
  const float version = 5.1f;
  const int word_size = 8;
  ok(nc_put_att_text(nc, NC_GLOBAL, "title", 19, "Created by meshio 5"));
  ok(nc_put_att_float(nc, NC_GLOBAL, "version", NC_FLOAT, 1, &version));
  ok(nc_put_att_float(nc, NC_GLOBAL, "api_version", NC_FLOAT, 1, &version));
  ok(nc_put_att_int(nc, NC_GLOBAL, "floating_point_word_size", NC_INT, 1, &word_size));
  int time_whole, coord, eb_prop1, connect1, names, scalar = -1, vector = -1;
  ok(nc_def_var(nc, "time_whole", NC_FLOAT, 1, &time_step, &time_whole));
  const int coord_dims[2] = {num_dim, num_nodes};
  ok(nc_def_var(nc, "coord", NC_DOUBLE, 2, coord_dims, &coord));
  ok(nc_def_var(nc, "eb_prop1", NC_INT, 1, &num_el_blk, &eb_prop1));
  const int conn_dims[2] = {in_blk, per_el};
  ok(nc_def_var(nc, "connect1", format == NC_NETCDF4 ? NC_INT64 : NC_INT, 2, conn_dims, &connect1));
  ok(nc_put_att_text(nc, connect1, "elem_type", 5, "TETRA"));
  const int name_dims[2] = {num_nod_var, len_string};
  ok(nc_def_var(nc, "name_nod_var", NC_CHAR, 2, name_dims, &names));
  if (with_values) {
    const int scalar_dims[2] = {time_step, num_nodes};
    ok(nc_def_var(nc, "vals_nod_var1", NC_DOUBLE, 2, scalar_dims, &scalar));
    const int vector_dims[3] = {time_step, num_nodes, vec};
    ok(nc_def_var(nc, "vals_nod_var2", NC_DOUBLE, 3, vector_dims, &vector));
  }
  ok(nc_enddef(nc));
  const size_t zero[3] = {0, 0, 0}, one = 1;
  const float t = 0.25f;
  ok(nc_put_vara_float(nc, time_whole, zero, &one, &t));
  ok(nc_put_var_double(nc, coord, &coords[0][0]));
  const int block = 7;
  ok(nc_put_var_int(nc, eb_prop1, &block));
  ok(nc_put_var_longlong(nc, connect1, &conn[0][0]));
  char name_text[2][33] = {{"temp"}, {"vel"}};
  ok(nc_put_var_text(nc, names, &name_text[0][0]));
  if (with_values) {
    double temp[5], vel[5][3];
    for (int i = 0; i < 5; ++i) {
      temp[i] = 10 + i;
      for (int c = 0; c < 3; ++c) vel[i][c] = coords[c][i] * 2;
    }
    const size_t scalar_count[2] = {1, 5}, vector_count[3] = {1, 5, 3};
    ok(nc_put_vara_double(nc, scalar, zero, scalar_count, temp));
    ok(nc_put_vara_double(nc, vector, zero, vector_count, &vel[0][0]));
  }
  ok(nc_close(nc));
}

TEST(ExodusImport, NodalVariablesStoredAsMeshioWritesThem) {
  const std::string dir = tempDir("exodus-meshio-style");
  for (int format : {0, NC_NETCDF4}) {
    const std::string path = dir + (format ? "/m4.exo" : "/m.exo");
    SCOPED_TRACE(path);
    ASSERT_NO_FATAL_FAILURE(writeMeshioStyle(path, format, true));
    auto r = load(path);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const TetMesh& m = r->mesh;
    ASSERT_EQ(m.numPoints(), 5u);
    EXPECT_EQ(m.numTets(), 2u);
    const Field* temp = findField(m.point_fields, "temp");
    const Field* vel = findField(m.point_fields, "vel");
    ASSERT_NE(temp, nullptr);
    for (size_t i = 0; i < 5; ++i) EXPECT_EQ(temp->get(i, 0), 10.0 + i) << i;
    ASSERT_NE(vel, nullptr);
    ASSERT_EQ(vel->components, 3u);
    for (size_t i = 0; i < 5; ++i) {
      for (uint32_t c = 0; c < 3; ++c) EXPECT_EQ(vel->get(i, c), 2 * m.point(i)[c]) << i << " " << c;
    }
    EXPECT_FALSE(hasWarning(r->report, "finds no values")) << allWarnings(r->report);
  }
  // Names without values anywhere: NaN and a warning.
  ASSERT_NO_FATAL_FAILURE(writeMeshioStyle(dir + "/none.exo", 0, false));
  auto r = load(dir + "/none.exo");
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const Field* temp = findField(r->mesh.point_fields, "temp");
  ASSERT_NE(temp, nullptr);
  for (size_t i = 0; i < 5; ++i) EXPECT_TRUE(std::isnan(temp->get(i, 0))) << i;
  EXPECT_TRUE(hasWarning(r->report,
                         "the Exodus library finds no values of the nodal variables 'temp', 'vel' at time "
                         "step 1: NaN there"))
      << allWarnings(r->report);
}

// The command line: info and validate show what was skipped, convert --time-step picks a step.
TEST(ExodusImport, CommandLine) {
  const std::string dir = tempDir("exodus-cli");
  writeExodus(dir + "/m.exo", WriteOptions{});
  auto info = runGtn("info " + dir + "/m.exo");
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE((info.out + info.err).find("3 BAR2, 2 QUAD4, 1 TRI3"), std::string::npos) << info.out << info.err;
  auto validate = runGtn("validate --json " + dir + "/m.exo");
  EXPECT_EQ(validate.exit_code, 0) << validate.out << validate.err;
  EXPECT_NE(validate.out.find("3 BAR2, 2 QUAD4, 1 TRI3"), std::string::npos) << validate.out;
  auto convert = runGtn("convert " + dir + "/m.exo -o " + dir + "/m.gtn --time-step 2");
  ASSERT_EQ(convert.exit_code, 0) << convert.err;
  auto back = importMesh({dir + "/m.gtn"}, ImportOptions{});
  ASSERT_TRUE(back.isOk()) << back.status().message();
  // The step's values (the .gtn file numbers the points its own way).
  const Field* temp = findField(back->mesh.point_fields, "temperature");
  ASSERT_NE(temp, nullptr);
  std::vector<double> got, want;
  for (int k = 0; k < kNodes; ++k) got.push_back(temp->get(k, 0)), want.push_back(temperature(2, k));
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, want);
  auto bad = runGtn("convert " + dir + "/m.exo -o " + dir + "/n.gtn --time-step 9");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--time-step 9: the file has time steps 1 to 3"), std::string::npos) << bad.err;
}

// --time-step given for a file that is not Exodus II is said to be ignored, not dropped in silence.
TEST(ExodusImport, TimeStepOnOtherFormatsIsIgnoredWithAWarning) {
  const std::string dir = tempDir("exodus-time-step-other");
  writeFile(dir + "/t.vtk",
            "# vtk DataFile Version 3.0\none tetrahedron\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n"
            "0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n");
  ImportOptions options;
  options.exodus_time_step = 2;
  auto r = importMesh({dir + "/t.vtk"}, options);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_TRUE(hasWarning(r->report, "--time-step 2 applies to Exodus II files only; ignored"))
      << allWarnings(r->report);
  const auto cli = runGtn("convert " + dir + "/t.vtk -o " + dir + "/t.gtn --time-step 2 -q");
  EXPECT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_NE(cli.err.find("--time-step 2 applies to Exodus II files only; ignored"), std::string::npos) << cli.err;
  auto plain = importMesh({dir + "/t.vtk"}, ImportOptions{});
  ASSERT_TRUE(plain.isOk());
  EXPECT_FALSE(hasWarning(plain->report, "--time-step")) << allWarnings(plain->report);
}

// ---- NFACED blocks (polyhedra, whose faces are those of the face blocks). ----

// Two unit cubes side by side (x in [0,1] and [1,2]) as NFACED elements over one face block, and a
// HEX8 on top of the first. The faces are listed once each, in no consistent winding (the face
// x = 1, shared, runs the same way for both cubes, as Exodus stores it), the second cube's faces
// in another order. `quad_faces`: the face block is of type QUAD4 rather than NSIDED. `bad`: 1 =
// the second cube lists face 12 (there are 11), 2 = a third cube lists the shared face again, 3 =
// the face counts add up to less than the block's total.
struct NfacedOptions {
  bool quad_faces = false;
  int bad = 0;
};

void writeNfaced(const std::string& path, const NfacedOptions& o) {
  int comp_ws = 8, io_ws = 8;
  const int exoid = ex_create(path.c_str(), EX_CLOBBER, &comp_ws, &io_ws);
  ASSERT_GE(exoid, 0) << path;
  const bool third = o.bad == 2;
  ex_init_params p{};
  std::snprintf(p.title, sizeof p.title, "polyhedra");
  p.num_dim = 3;
  p.num_nodes = 16;
  p.num_face = 11;
  p.num_face_blk = 1;
  p.num_elem = third ? 4 : 3;
  p.num_elem_blk = 2;
  check(ex_put_init_ext(exoid, &p), "ex_put_init_ext");
  const double x[16] = {0, 1, 1, 0, 0, 1, 1, 0, 2, 2, 2, 2, 0, 1, 1, 0};
  const double y[16] = {0, 0, 1, 1, 0, 0, 1, 1, 0, 1, 0, 1, 0, 0, 1, 1};
  const double z[16] = {0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 1, 1, 2, 2, 2, 2};
  check(ex_put_coord(exoid, x, y, z), "ex_put_coord");
  const int faces[44] = {1, 2, 3, 4, 5,  6, 7, 8,  1,  2, 6, 5, 4,  3, 7, 8,  1,  4, 8, 5,  2,  3,
                         7, 6, 2, 9, 10, 3, 6, 11, 12, 7, 2, 9, 11, 6, 3, 10, 12, 7, 9, 10, 12, 11};
  const int face_nodes[11] = {4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4};
  check(ex_put_block(exoid, EX_FACE_BLOCK, 10, o.quad_faces ? "QUAD4" : "NSIDED", 11, o.quad_faces ? 4 : 44, 0, 0, 0),
        "face block");
  check(ex_put_conn(exoid, EX_FACE_BLOCK, 10, faces, nullptr, nullptr), "face nodes");
  if (!o.quad_faces) check(ex_put_entity_count_per_polyhedra(exoid, EX_FACE_BLOCK, 10, face_nodes), "face counts");
  const int hex[8] = {5, 6, 7, 8, 13, 14, 15, 16};
  check(ex_put_block(exoid, EX_ELEM_BLOCK, 50, "HEX8", 1, 8, 0, 0, 0), "hex block");
  check(ex_put_conn(exoid, EX_ELEM_BLOCK, 50, hex, nullptr, nullptr), "hex nodes");
  std::vector<int> cube_faces = {1, 2, 3, 4, 5, 6, 11, 8, 6, 7, 10, 9};
  std::vector<int> counts = {6, 6};
  if (o.bad == 1) cube_faces[6] = 12;
  if (third) {
    cube_faces.insert(cube_faces.end(), {1, 2, 3, 4, 5, 6});
    counts.push_back(6);
  }
  if (o.bad == 3) counts[1] = 5;
  check(ex_put_block(exoid, EX_ELEM_BLOCK, 100, "NFACED", static_cast<int64_t>(counts.size()), 0, 0,
                     static_cast<int64_t>(cube_faces.size()), 0),
        "polyhedron block");
  check(ex_put_conn(exoid, EX_ELEM_BLOCK, 100, nullptr, nullptr, cube_faces.data()), "polyhedron faces");
  check(ex_put_entity_count_per_polyhedra(exoid, EX_ELEM_BLOCK, 100, counts.data()), "polyhedron face counts");
  check(ex_put_variable_param(exoid, EX_ELEM_BLOCK, 1), "element variable count");
  const char* names[] = {"stress"};
  check(ex_put_variable_names(exoid, EX_ELEM_BLOCK, 1, const_cast<char**>(names)), "element names");
  const double time = 1, hex_stress = 5, cube_stress[3] = {10, 20, 30};
  check(ex_put_time(exoid, 1, &time), "ex_put_time");
  check(ex_put_var(exoid, 1, EX_ELEM_BLOCK, 1, 50, 1, &hex_stress), "hex stress");
  check(ex_put_var(exoid, 1, EX_ELEM_BLOCK, 1, 100, static_cast<int64_t>(counts.size()), cube_stress), "stress");
  check(ex_close(exoid), "ex_close");
}

TEST(ExodusImport, NfacedPolyhedraBecomeTetrahedra) {
  const std::string dir = tempDir("exodus-nfaced");
  for (bool quad_faces : {false, true}) {
    const std::string path = dir + (quad_faces ? "/quad.exo" : "/nsided.exo");
    writeNfaced(path, NfacedOptions{.quad_faces = quad_faces});
    auto r = load(path);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const TetMesh& m = r->mesh;
    EXPECT_EQ(m.numPoints(), 16u);
    // A cube is coned from its smallest vertex over the fans of the three faces without it.
    ASSERT_EQ(m.numTets(), 18u);
    const MeshStats s = computeMeshStats(m);
    EXPECT_NEAR(s.total_volume, 3.0, 1e-12);
    EXPECT_EQ(s.inverted, 0u);
    EXPECT_EQ(s.zero_volume, 0u);
    EXPECT_EQ(r->report.flipped, 0u);
    // Each tetrahedron lies in its cell: the hexahedron's, then each cube's, in the file's order.
    const Field* id = findField(m.cell_fields, "block_id");
    const Field* stress = findField(m.cell_fields, "stress");
    ASSERT_NE(id, nullptr);
    ASSERT_NE(stress, nullptr);
    EXPECT_EQ(runs(*stress), (std::vector<double>{5, 10, 20}));
    for (size_t t = 0; t < m.numTets(); ++t) {
      const double cube = stress->get(t, 0) / 10;  // 0.5 (the hexahedron), 1 or 2
      EXPECT_EQ(id->get(t, 0), cube < 1 ? 50 : 100) << t;
      for (uint32_t v : m.tets[t]) {
        const double* p = &m.coords[3 * v];
        if (cube < 1) EXPECT_GE(p[2], 1.0) << t;
        else EXPECT_TRUE(p[2] <= 1 && p[0] >= cube - 1 && p[0] <= cube) << t;
      }
    }
    // The face block is read, and the turned faces are how Exodus stores them: neither is reported.
    for (const std::string& w : r->report.warnings) {
      EXPECT_EQ(w.find("face block"), std::string::npos) << w;
      EXPECT_EQ(w.find("wind"), std::string::npos) << w;
    }
    const auto cli = runGtn("convert '" + path + "' -o '" + dir + "/p.gtn' -q");
    ASSERT_EQ(cli.exit_code, 0) << cli.err;
    const auto valid = runGtn("validate '" + dir + "/p.gtn'");
    EXPECT_EQ(valid.exit_code, 0) << valid.out << valid.err;
  }
  const std::pair<int, std::string> errors[] = {
      {1, "/bad.exo: element block 100 (NFACED), element 2 refers to face 12; faces are numbered 1 to 11"},
      {2,
       "/bad.exo: element block 100 (NFACED), element 3 is the third polyhedron to list face 6; a face bounds at "
       "most two cells"},
      {3, "/bad.exo: element block 100 (NFACED): its elements' face counts add up to 11, not 12"},
  };
  for (const auto& [bad, message] : errors) {
    writeNfaced(dir + "/bad.exo", NfacedOptions{.bad = bad});
    auto r = load(dir + "/bad.exo");
    ASSERT_FALSE(r.isOk()) << bad;
    EXPECT_EQ(r.status().message(), dir + message);
  }
}

// ---- VTK's Exodus reader and meshio read the same files. ----

const char* kClientScript = R"PY(
import sys, json
import numpy as np
path, step = sys.argv[2], int(sys.argv[3])
if sys.argv[1] == "vtk":
    from vtkmodules.vtkIOExodus import vtkExodusIIReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    r = vtkExodusIIReader()
    r.SetFileName(path)
    r.UpdateInformation()
    for t in (r.NODAL, r.ELEM_BLOCK):
        for i in range(r.GetNumberOfObjectArrays(t)):
            r.SetObjectArrayStatus(t, i, 1)
    r.SetTimeStep(step - 1)
    r.SetSqueezePoints(False)
    r.Update()
    out = {"blocks": []}
    blocks = r.GetOutput().GetBlock(0)
    for b in range(blocks.GetNumberOfBlocks()):
        g = blocks.GetBlock(b)
        if g is None:
            continue
        cd, pd = g.GetCellData(), g.GetPointData()
        out["blocks"].append({
            "id": int(r.GetObjectId(r.ELEM_BLOCK, b)), "cells": g.GetNumberOfCells(), "points": g.GetNumberOfPoints(),
            "cell_data": {cd.GetArrayName(i): vtk_to_numpy(cd.GetArray(i)).tolist() for i in range(cd.GetNumberOfArrays())},
            "point_data": {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)).tolist() for i in range(pd.GetNumberOfArrays())}})
else:
    import meshio
    m = meshio.read(path)
    out = {"points": len(m.points), "cells": [[c.type, len(c.data)] for c in m.cells],
           "point_data": {k: np.asarray(v).tolist() for k, v in m.point_data.items()},
           "cell_data": {k: [np.asarray(a).tolist() for a in v] for k, v in m.cell_data.items()}}
print(json.dumps(out))
)PY";

bool clientAvailable(const char* module, std::string* why) {
  if (runShell(std::string("/usr/bin/python3 -c 'import ") + module + "' 2>&1").exit_code == 0) return true;
  *why = std::string("/usr/bin/python3 cannot import ") + module;
  return false;
}

nlohmann::json runClient(const std::string& dir, const std::string& mode, const std::string& path, int step) {
  const std::string script = dir + "/client.py";
  if (!test::fileExists(script)) writeFile(script, kClientScript);
  const auto r = runShell("/usr/bin/python3 " + script + " " + mode + " '" + path + "' " + std::to_string(step));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  try {
    return nlohmann::json::parse(r.out);
  } catch (const std::exception&) {
    ADD_FAILURE() << "no JSON from the " << mode << " client: " << r.out << r.err;
    return {};
  }
}

TEST(ExodusImport, AgreesWithVtksExodusReader) {
  std::string why;
  if (!clientAvailable("vtkmodules.vtkIOExodus", &why)) GTEST_SKIP() << why;
  const std::string dir = tempDir("exodus-vtk");
  for (int mode : {EX_CLOBBER, EX_CLOBBER | EX_NETCDF4}) {
    const std::string path = dir + (mode & EX_NETCDF4 ? "/h.exo" : "/c.exo");
    writeExodus(path, WriteOptions{.mode = mode});
    for (int step : {1, 3}) {
      auto r = load(path, step);
      ASSERT_TRUE(r.isOk()) << r.status().message();
      const TetMesh& m = r->mesh;
      const nlohmann::json vtk = runClient(dir, "vtk", path, step);
      const Field* id = findField(m.cell_fields, "block_id");
      ASSERT_NE(id, nullptr);
      // VTK reads every block (skipped ones included); ours are the volume blocks, in its order.
      std::vector<double> vtk_volume_ids, vtk_stress, vtk_pressure;
      size_t lower = 0;
      for (const auto& b : vtk["blocks"]) {
        const int64_t bid = b["id"];
        EXPECT_EQ(b["points"], kNodes);
        if (bid >= 60) {
          lower += b["cells"].get<size_t>();
          continue;
        }
        vtk_volume_ids.push_back(static_cast<double>(bid));
        for (double v : b["cell_data"]["stress"]) vtk_stress.push_back(v);
        if (b["cell_data"].contains("pressure"))
          for (double v : b["cell_data"]["pressure"]) vtk_pressure.push_back(v);
        // Point data: every node (SqueezePointsOff), the same values as ours.
        const auto& t = b["point_data"]["temperature"];
        ASSERT_EQ(t.size(), m.numPoints());
        const Field* temp = findField(m.point_fields, "temperature");
        for (size_t k = 0; k < m.numPoints(); ++k) EXPECT_EQ(t[k].get<double>(), temp->get(k, 0));
        // VTK joins velocity_x/_y/_z into one 3-component array too.
        ASSERT_TRUE(b["point_data"].contains("velocity_")) << b["point_data"].dump().substr(0, 300);
        const auto& v = b["point_data"]["velocity_"];
        const Field* vel = findField(m.point_fields, "velocity_");
        ASSERT_NE(vel, nullptr);
        for (size_t k = 0; k < m.numPoints(); ++k)
          for (uint32_t c = 0; c < 3; ++c) EXPECT_EQ(v[k][c].get<double>(), vel->get(k, c));
      }
      EXPECT_EQ(lower, 6u);  // the elements our warning counts as skipped
      EXPECT_EQ(runs(*id), vtk_volume_ids);
      EXPECT_EQ(runs(*findField(m.cell_fields, "stress")), vtk_stress);
      std::vector<double> ours_p = runs(*findField(m.cell_fields, "pressure"));
      ASSERT_FALSE(ours_p.empty());
      ours_p.pop_back();  // the NaN of the blocks without pressure, which VTK leaves without the array
      EXPECT_EQ(ours_p, vtk_pressure);
    }
  }
}

TEST(ExodusImport, AgreesWithMeshio) {
  std::string why;
  if (!clientAvailable("meshio, netCDF4", &why)) GTEST_SKIP() << why << " (meshio reads Exodus with python3-netcdf4)";
  const std::string dir = tempDir("exodus-meshio");
  // meshio reads the first time step, nodal variables stored one per netCDF variable (the default
  // large model) and element variables defined on every block.
  writeExodus(dir + "/c.exo", WriteOptions{.pressure_everywhere = true});
  auto r = load(dir + "/c.exo", 1);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  const nlohmann::json io = runClient(dir, "meshio", dir + "/c.exo", 1);
  EXPECT_EQ(io["points"], m.numPoints());
  const nlohmann::json want_cells = nlohmann::json::parse(
      R"([["hexahedron", 1], ["wedge", 2], ["pyramid", 2], ["tetra", 2], ["tetra10", 1], ["quad", 2], ["line", 3],
          ["triangle", 1]])");
  EXPECT_EQ(io["cells"], want_cells);
  // meshio keeps velocity_x, _y, _z apart (it joins only upper-case X, Y, Z); ours are the components.
  const std::pair<const char*, uint32_t> arrays[] = {
      {"temperature", 0}, {"velocity_x", 0}, {"velocity_y", 1}, {"velocity_z", 2}};
  for (const auto& [name, c] : arrays) {
    ASSERT_TRUE(io["point_data"].contains(name)) << io["point_data"].dump().substr(0, 300);
    const auto& values = io["point_data"][name];
    const Field* f = findField(m.point_fields, name[0] == 't' ? "temperature" : "velocity_");
    ASSERT_NE(f, nullptr);
    ASSERT_EQ(values.size(), m.numPoints());
    for (size_t k = 0; k < m.numPoints(); ++k) EXPECT_EQ(values[k].get<double>(), f->get(k, c)) << name << " " << k;
  }
  // Element variables: meshio's per-block arrays of the volume blocks are ours.
  for (const char* name : {"stress", "pressure"}) {
    std::vector<double> values;
    for (size_t b = 0; b < 5; ++b)
      for (double v : io["cell_data"][name][b]) values.push_back(v);
    EXPECT_EQ(runs(*findField(m.cell_fields, name)), values) << name;
  }
}

// ---- Damaged files: a clean error naming the file, never a crash. ----

TEST(ExodusErrors, DamagedAndTruncatedFiles) {
  const std::string dir = tempDir("exodus-damaged");
  for (int mode : {EX_CLOBBER | EX_NORMAL_MODEL, EX_CLOBBER | EX_NETCDF4}) {
    const std::string good_path = dir + "/good.exo";
    writeExodus(good_path, WriteOptions{.mode = mode});
    const std::string good = test::readFile(good_path);
    auto expectClean = [&](const std::string& bytes, const std::string& what, bool must_fail = false) {
      const std::string path = dir + "/bad.exo";
      writeFile(path, bytes);
      auto r = load(path);
      if (must_fail) {
        EXPECT_FALSE(r.isOk()) << what;
      }
      if (r.isOk()) {
        // Damage to values (netCDF has no checksums) or where nothing is read may leave a readable
        // file; importMesh checked its consistency.
        EXPECT_TRUE(r->mesh.checkConsistency(path).isOk()) << what;
        return;
      }
      EXPECT_EQ(r.status().message().rfind(path + ": ", 0), 0u) << what << ": " << r.status().message();
    };
    // Every prefix length on a coarse grid, and the last bytes one by one: a truncated file is an
    // error (classic netCDF would read the missing values as zeros).
    for (size_t n = 0; n < good.size(); n += std::max<size_t>(1, good.size() / 97))
      expectClean(good.substr(0, n), "prefix " + std::to_string(n), true);
    for (size_t n = good.size() - std::min<size_t>(good.size(), 16); n < good.size(); ++n)
      expectClean(good.substr(0, n), "prefix " + std::to_string(n), true);
    writeFile(dir + "/cut.exo", good.substr(0, good.size() - 4));
    auto cut = load(dir + "/cut.exo");
    ASSERT_FALSE(cut.isOk());
    // netCDF-4: the end of file the HDF5 superblock records (the libraries would say "HDF error", and the
    // Exodus library on standard error that netCDF-4 is not supported).
    if (mode & EX_NETCDF4)
      EXPECT_EQ(cut.status().message(), dir + "/cut.exo: truncated: its HDF5 superblock gives the file " +
                                            std::to_string(good.size()) + " bytes, but it has " +
                                            std::to_string(good.size() - 4));
    else
      EXPECT_EQ(cut.status().message(), dir + "/cut.exo: truncated: its netCDF header places values up to byte " +
                                            std::to_string(good.size()) + ", but the file has " +
                                            std::to_string(good.size() - 4) + " bytes");
    // A flipped byte across the file.
    for (size_t at = 0; at < good.size(); at += std::max<size_t>(1, good.size() / 211)) {
      std::string bad = good;
      bad[at] = static_cast<char>(bad[at] ^ 0x5A);
      expectClean(bad, "byte " + std::to_string(at) + " flipped");
    }
  }
  // Not an Exodus file at all, under an Exodus name: the reason is netCDF's.
  writeFile(dir + "/text.exo", "hello\n");
  auto r = load(dir + "/text.exo");
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().message().rfind(dir + "/text.exo: cannot open it as an Exodus II file (ex_open: ", 0), 0u)
      << r.status().message();
}

// A 2D file and a file of shells only are refused, saying why.
TEST(ExodusErrors, NoVolume) {
  const std::string dir = tempDir("exodus-novolume");
  int comp_ws = 8, io_ws = 8;
  int id = ex_create((dir + "/flat.exo").c_str(), EX_CLOBBER, &comp_ws, &io_ws);
  ASSERT_GE(id, 0);
  ASSERT_GE(ex_put_init(id, "2d", 2, 3, 1, 1, 0, 0), 0);
  const double x[] = {0, 1, 0}, y[] = {0, 0, 1};
  ASSERT_GE(ex_put_coord(id, x, y, nullptr), 0);
  ASSERT_GE(ex_put_elem_block(id, 1, "TRI3", 1, 3, 0), 0);
  const int tri[] = {1, 2, 3};
  ASSERT_GE(ex_put_elem_conn(id, 1, tri), 0);
  ASSERT_GE(ex_close(id), 0);
  auto r = load(dir + "/flat.exo");
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().message(),
            dir + "/flat.exo: a 2-dimensional Exodus II mesh; only 3-dimensional meshes hold tetrahedra");

  id = ex_create((dir + "/shell.exo").c_str(), EX_CLOBBER, &comp_ws, &io_ws);
  ASSERT_GE(id, 0);
  ASSERT_GE(ex_put_init(id, "shell", 3, 4, 1, 1, 0, 0), 0);
  const double sx[] = {0, 1, 1, 0}, sy[] = {0, 0, 1, 1}, sz[] = {0, 0, 0, 0};
  ASSERT_GE(ex_put_coord(id, sx, sy, sz), 0);
  ASSERT_GE(ex_put_elem_block(id, 7, "SHELL4", 1, 4, 0), 0);
  const int quad[] = {1, 2, 3, 4};
  ASSERT_GE(ex_put_elem_conn(id, 7, quad), 0);
  ASSERT_GE(ex_close(id), 0);
  r = load(dir + "/shell.exo");
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().message(),
            dir + "/shell.exo: no volume elements (TETRA, HEX, WEDGE, PYRAMID, NFACED), only 1 SHELL4");
}

}  // namespace
}  // namespace gtn

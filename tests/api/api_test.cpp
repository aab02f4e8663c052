// The public API (include/gatun/gatun.h) on meshes the test builds: write, read back bit for bit,
// read a level, a ratio and some fields, convert, validate and render as the gtn command does.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <thread>
#include <tuple>

#include "codec/pieces.h"
#include "gatun/gatun.h"
#include "render/image.h"
#include "test_util.h"

namespace {

using gtn::test::readFile;
using gtn::test::runGtn;
using gtn::test::tempDir;
using gtn::test::writeFile;

// An n x n x n grid of cubes, each split into six tetrahedra around its main diagonal (all positively
// oriented, then every other one inverted), with the point field "density" (float32, varying), the
// 3-component point field "velocity" (float64) and the cell field "region" (int32).
gatun::Mesh gridMesh(int n) {
  gatun::Mesh m;
  const int p = n + 1;
  auto id = [&](int i, int j, int k) { return static_cast<uint32_t>((k * p + j) * p + i); };
  std::vector<float> density;
  std::vector<double> velocity;
  for (int k = 0; k < p; ++k)
    for (int j = 0; j < p; ++j)
      for (int i = 0; i < p; ++i) {
        m.points.insert(m.points.end(), {double(i), double(j) * 1.25, double(k) * 0.75});
        density.push_back(static_cast<float>(std::sin(i * 0.7) + j * j * 0.1 + k * 0.3));
        velocity.insert(velocity.end(), {double(i) - j, double(k) * 0.5, double(i * j * k)});
      }
  std::vector<int32_t> region;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t c[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        // Six tetrahedra sharing the diagonal c0-c6; orientation is the library's business.
        const int paths[6][2] = {{1, 2}, {2, 3}, {3, 7}, {7, 4}, {4, 5}, {5, 1}};
        for (const auto& q : paths) {
          if (m.tets.size() % 2 == 0) m.tets.push_back({c[0], c[q[0]], c[q[1]], c[6]});
          else m.tets.push_back({c[0], c[q[1]], c[q[0]], c[6]});
          region.push_back((i + j + k) % 3);
        }
      }
  m.coord_type = gatun::ScalarType::kFloat64;
  m.point_fields.push_back(gatun::Field::of("density", 1, density));
  m.point_fields.push_back(gatun::Field::of("velocity", 3, velocity));
  m.cell_fields.push_back(gatun::Field::of("region", 1, region));
  m.metadata.push_back({"made.by", "api_test"});
  return m;
}

using Point = std::tuple<double, double, double>;
Point pointOf(const gatun::Mesh& m, uint32_t i) { return {m.points[3 * i], m.points[3 * i + 1], m.points[3 * i + 2]}; }

// Point -> its point field values; tetrahedron (as its sorted corner points) -> its cell field values.
// Equal for two meshes that differ only by the numbering of points and tetrahedra.
struct Canonical {
  std::map<Point, std::vector<double>> points;
  std::map<std::vector<Point>, std::vector<double>> tets;
  bool operator==(const Canonical&) const = default;
};
Canonical canonical(const gatun::Mesh& m) {
  Canonical c;
  for (uint32_t i = 0; i < m.pointCount(); ++i) {
    std::vector<double>& v = c.points[pointOf(m, i)];
    for (const gatun::Field& f : m.point_fields)
      for (uint32_t k = 0; k < f.components; ++k) v.push_back(f.value(i, k));
  }
  for (size_t t = 0; t < m.tetCount(); ++t) {
    std::vector<Point> corners;
    for (uint32_t v : m.tets[t]) corners.push_back(pointOf(m, v));
    std::sort(corners.begin(), corners.end());
    std::vector<double>& v = c.tets[corners];
    for (const gatun::Field& f : m.cell_fields)
      for (uint32_t k = 0; k < f.components; ++k) v.push_back(f.value(t, k));
  }
  return c;
}

double signedVolume(const gatun::Mesh& m, const gatun::Tet& t) {
  const double* a = &m.points[3 * t[0]];
  double e[3][3];
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) e[r][k] = m.points[3 * t[r + 1] + k] - a[k];
  return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

TEST(Api, WriteThenReadGivesTheMeshBackBitForBit) {
  const std::string dir = tempDir("api_roundtrip");
  const gatun::Mesh mesh = gridMesh(5);
  ASSERT_GT(signedVolume(mesh, mesh.tets[0]), 0);
  ASSERT_LT(signedVolume(mesh, mesh.tets[1]), 0);
  std::vector<std::string> warnings;
  gatun::WriteOptions options;
  options.levels = 2;
  const gatun::Error written = gatun::write(dir + "/grid.gtn", mesh, options, &warnings);
  ASSERT_TRUE(written.ok()) << written.message();
  // Half of the tetrahedra of gridMesh are inverted: write() turns them around and says so.
  ASSERT_FALSE(warnings.empty());
  EXPECT_EQ(warnings[0], "gatun::write(" + dir + "/grid.gtn): flipped 375 tetrahedra to positive orientation");

  auto info = gatun::readInfo(dir + "/grid.gtn");
  ASSERT_TRUE(info.ok()) << info.error().message();
  EXPECT_EQ(info.value().levels.at(0).points, mesh.pointCount());
  EXPECT_EQ(info.value().levels.at(0).tets, mesh.tetCount());
  EXPECT_EQ(info.value().levels.size(), 3u);
  EXPECT_TRUE(info.value().levels[0].has_merge_tree);
  ASSERT_EQ(info.value().point_fields.size(), 2u);
  EXPECT_EQ(info.value().point_fields[1].name, "velocity");
  EXPECT_EQ(info.value().point_fields[1].components, 3u);
  EXPECT_EQ(info.value().cell_fields.at(0).type, gatun::ScalarType::kInt32);
  EXPECT_EQ(info.value().command_line, "gatun::write(grid.gtn)");
  EXPECT_EQ(info.value().bbox_max[1], 6.25);

  gatun::ReadReport report;
  auto back = gatun::read(dir + "/grid.gtn", {}, &report);
  ASSERT_TRUE(back.ok()) << back.error().message();
  const gatun::Mesh& m = back.value();
  EXPECT_EQ(m.pointCount(), mesh.pointCount());
  EXPECT_EQ(m.tetCount(), mesh.tetCount());
  EXPECT_EQ(report.level, 0u);
  EXPECT_EQ(report.merges, 0u);
  EXPECT_TRUE(canonical(m) == canonical(mesh));
  for (const gatun::Tet& t : m.tets) EXPECT_GT(signedVolume(m, t), 0);
  ASSERT_NE(m.pointField("density"), nullptr);
  EXPECT_EQ(m.pointField("density")->type, gatun::ScalarType::kFloat32);
  bool has_meta = false;
  for (const auto& [k, v] : m.metadata) has_meta |= k == "made.by" && v == "api_test";
  EXPECT_TRUE(has_meta);
}

// A mesh with errors of its own (two tetrahedra overlapping) is refused with kInvalidData naming them,
// and nothing is written; keep_invalid writes it, with a warning.
TEST(Api, WriteRefusesAMeshWithErrorsOfItsOwnUnlessKept) {
  const std::string dir = tempDir("api_overlap");
  gatun::Mesh mesh;
  mesh.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.1, 0.1, 0.1};
  mesh.tets = {{0, 1, 2, 3}, {0, 1, 2, 4}};
  const std::string path = dir + "/overlap.gtn";
  const gatun::Error refused = gatun::write(path, mesh);
  EXPECT_EQ(refused.code(), gatun::ErrorCode::kInvalidData);
  EXPECT_NE(refused.message().find("errors that `gtn validate` would report on the file (BOUNDARY_ORIENTATION"),
            std::string::npos)
      << refused.message();
  EXPECT_FALSE(gtn::test::fileExists(path));
  gatun::WriteOptions keep;
  keep.keep_invalid = true;
  std::vector<std::string> warnings;
  const gatun::Error kept = gatun::write(path, mesh, keep, &warnings);
  ASSERT_TRUE(kept.ok()) << kept.message();
  EXPECT_TRUE(gtn::test::fileExists(path));
  ASSERT_FALSE(warnings.empty());
  EXPECT_NE(warnings.back().find("--keep-invalid"), std::string::npos) << warnings.back();
}

TEST(Api, ReaderReadsLevelsRatiosAndSomeFields) {
  const std::string dir = tempDir("api_levels");
  const gatun::Mesh mesh = gridMesh(6);
  gatun::WriteOptions options;
  options.levels = 2;
  ASSERT_TRUE(gatun::write(dir + "/grid.gtn", mesh, options).ok());
  auto opened = gatun::Reader::open(dir + "/grid.gtn");
  ASSERT_TRUE(opened.ok()) << opened.error().message();
  gatun::Reader reader = std::move(opened).value();
  const gatun::FileInfo& info = reader.info();
  ASSERT_EQ(info.levels.size(), 3u);

  gatun::ReadReport report;
  auto level1 = reader.read({.level = 1}, &report);
  ASSERT_TRUE(level1.ok()) << level1.error().message();
  EXPECT_EQ(level1.value().pointCount(), info.levels[1].points);
  EXPECT_EQ(level1.value().tetCount(), info.levels[1].tets);
  EXPECT_LT(level1.value().tetCount(), mesh.tetCount());
  EXPECT_EQ(report.level, 1u);
  EXPECT_EQ(report.merges, info.levels[1].merges);

  auto half = reader.read({.ratio = 0.3}, &report);
  ASSERT_TRUE(half.ok()) << half.error().message();
  EXPECT_LT(half.value().pointCount(), mesh.pointCount());
  EXPECT_NEAR(report.ratio, 0.3, 0.02);
  for (const gatun::Tet& t : half.value().tets) EXPECT_GT(signedVolume(half.value(), t), 0);

  auto some = reader.read({.fields = {"velocity"}});
  ASSERT_TRUE(some.ok()) << some.error().message();
  ASSERT_EQ(some.value().point_fields.size(), 1u);
  EXPECT_EQ(some.value().point_fields[0].name, "velocity");
  EXPECT_TRUE(some.value().cell_fields.empty());

  auto missing_field = reader.read({.fields = {"pressure"}});
  ASSERT_FALSE(missing_field.ok());
  EXPECT_EQ(missing_field.error().code(), gatun::ErrorCode::kUsage);
  EXPECT_NE(missing_field.error().message().find("no field named 'pressure'"), std::string::npos)
      << missing_field.error().message();
  EXPECT_THROW(missing_field.value(), std::bad_optional_access);

  auto no_level = reader.read({.level = 40});
  ASSERT_FALSE(no_level.ok());
  EXPECT_EQ(no_level.error().exitCode(), 2);
  EXPECT_NE(no_level.error().message().find("level 40: the file holds"), std::string::npos);
  auto bad_ratio = reader.read({.ratio = 1.5});
  ASSERT_FALSE(bad_ratio.ok());
  EXPECT_EQ(bad_ratio.error().code(), gatun::ErrorCode::kUsage);

  // Independent levels: the same levels, each storing all its vertices (a larger file).
  options.independent_levels = true;
  ASSERT_TRUE(gatun::write(dir + "/independent.gtn", mesh, options).ok());
  auto whole = gatun::Reader::open(dir + "/independent.gtn");
  ASSERT_TRUE(whole.ok()) << whole.error().message();
  ASSERT_EQ(whole.value().info().levels.size(), 3u);
  EXPECT_GT(whole.value().info().bytes, info.bytes);
  auto whole1 = whole.value().read({.level = 1});
  ASSERT_TRUE(whole1.ok()) << whole1.error().message();
  EXPECT_EQ(whole1.value().pointCount(), level1.value().pointCount());
  EXPECT_EQ(whole1.value().tetCount(), level1.value().tetCount());
}

TEST(Api, ErrorsCarryTheCommandsMessages) {
  const std::string dir = tempDir("api_errors");
  auto none = gatun::read(dir + "/absent.gtn");
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code(), gatun::ErrorCode::kIo);
  EXPECT_EQ(none.error().exitCode(), 3);
  EXPECT_NE(none.error().message().find(dir + "/absent.gtn"), std::string::npos);

  writeFile(dir + "/junk.gtn", std::string(200, 'x'));
  auto junk = gatun::readInfo(dir + "/junk.gtn");
  ASSERT_FALSE(junk.ok());
  EXPECT_EQ(junk.error().code(), gatun::ErrorCode::kNotOurFile);
  EXPECT_NE(junk.error().message().find("junk.gtn: byte offset 0: bad magic"), std::string::npos)
      << junk.error().message();

  gatun::Mesh bad = gridMesh(1);
  bad.tets[2][3] = 99;
  const gatun::Error refused = gatun::write(dir + "/bad.gtn", bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.code(), gatun::ErrorCode::kUsage);
  EXPECT_NE(refused.message().find("99"), std::string::npos) << refused.message();
  EXPECT_FALSE(gtn::test::fileExists(dir + "/bad.gtn"));
}

TEST(Api, ConvertWritesTheBytesOfGtnConvert) {
  const std::string dir = tempDir("api_convert");
  writeFile(dir + "/hex.vtk", gtn::test::shearedHexGridVtk(4, false, true));
  ASSERT_EQ(runGtn("convert -q " + dir + "/hex.vtk -o " + dir + "/cli.gtn").exit_code, 0);
  auto cli_info = gatun::readInfo(dir + "/cli.gtn");
  ASSERT_TRUE(cli_info.ok()) << cli_info.error().message();

  gatun::ConvertOptions options;
  options.write.command_line = cli_info.value().command_line;  // the same provenance
  const gatun::Error converted = gatun::convert({dir + "/hex.vtk"}, dir + "/api.gtn", options);
  ASSERT_TRUE(converted.ok()) << converted.message();
  EXPECT_EQ(readFile(dir + "/api.gtn"), readFile(dir + "/cli.gtn"));

  // Back to VTK and in again: the same mesh.
  ASSERT_TRUE(gatun::convert({dir + "/api.gtn"}, dir + "/back.vtu").ok());
  auto imported = gatun::importMesh({dir + "/back.vtu"});
  ASSERT_TRUE(imported.ok()) << imported.error().message();
  auto level0 = gatun::read(dir + "/api.gtn");
  ASSERT_TRUE(level0.ok());
  EXPECT_TRUE(canonical(imported.value()) == canonical(level0.value()));
  EXPECT_EQ(imported.value().tetCount(), 4u * 4u * 4u * 6u);

  const gatun::Error onto_input = gatun::convert({dir + "/hex.vtk"}, dir + "/hex.vtk");
  EXPECT_EQ(onto_input.code(), gatun::ErrorCode::kUsage);
  EXPECT_EQ(gatun::convert({dir + "/hex.vtk"}, dir + "/x.obj").code(), gatun::ErrorCode::kUsage);
  auto not_gtn = gatun::Reader::open(dir + "/hex.vtk");
  ASSERT_FALSE(not_gtn.ok());
  EXPECT_NE(not_gtn.error().message().find("not .gtn"), std::string::npos) << not_gtn.error().message();
}

// greedy_ranking is `gtn convert --greedy-ranking`: the same bytes, and another tree than the default's.
TEST(Api, GreedyRankingIsTheCommandsFlag) {
  const std::string dir = tempDir("api_greedy");
  writeFile(dir + "/hex.vtk", gtn::test::shearedHexGridVtk(5, false, true));
  ASSERT_EQ(runGtn("convert -q " + dir + "/hex.vtk -o " + dir + "/cli.gtn --greedy-ranking").exit_code, 0);
  auto cli_info = gatun::readInfo(dir + "/cli.gtn");
  ASSERT_TRUE(cli_info.ok()) << cli_info.error().message();
  gatun::ConvertOptions options;
  options.write.command_line = cli_info.value().command_line;
  options.write.greedy_ranking = true;
  ASSERT_TRUE(gatun::convert({dir + "/hex.vtk"}, dir + "/api.gtn", options).ok());
  EXPECT_EQ(readFile(dir + "/api.gtn"), readFile(dir + "/cli.gtn"));
  options.write.greedy_ranking = false;
  ASSERT_TRUE(gatun::convert({dir + "/hex.vtk"}, dir + "/lazy.gtn", options).ok());
  EXPECT_NE(readFile(dir + "/lazy.gtn"), readFile(dir + "/cli.gtn"));
}

TEST(Api, ValidateReportsWhatGtnValidateReports) {
  const std::string dir = tempDir("api_validate");
  ASSERT_TRUE(gatun::write(dir + "/grid.gtn", gridMesh(3)).ok());
  auto good = gatun::validate({dir + "/grid.gtn"});
  ASSERT_TRUE(good.ok()) << good.error().message();
  EXPECT_TRUE(good.value().ok()) << good.value().text;
  EXPECT_EQ(good.value().errors, 0u);
  const auto cli = runGtn("validate " + dir + "/grid.gtn");
  EXPECT_EQ(cli.exit_code, 0);
  EXPECT_EQ(good.value().text, cli.out);
  const auto cli_json = runGtn("validate --json " + dir + "/grid.gtn");
  EXPECT_EQ(good.value().json, cli_json.out);

  std::string bytes = readFile(dir + "/grid.gtn");
  writeFile(dir + "/cut.gtn", bytes.substr(0, bytes.size() / 2));
  auto cut = gatun::validate({dir + "/cut.gtn"});
  ASSERT_TRUE(cut.ok()) << cut.error().message();
  EXPECT_FALSE(cut.value().ok());
  ASSERT_FALSE(cut.value().issues.empty());
  EXPECT_EQ(cut.value().issues[0].severity, gatun::Severity::kError);
  EXPECT_EQ(cut.value().text, runGtn("validate " + dir + "/cut.gtn").out);

  // A mesh file: the import's and the mesh's checks.
  writeFile(dir + "/hex.vtk", gtn::test::shearedHexGridVtk(3, /*mirrored=*/true));
  auto mesh_file = gatun::validate({dir + "/hex.vtk"});
  ASSERT_TRUE(mesh_file.ok()) << mesh_file.error().message();
  EXPECT_EQ(mesh_file.value().text, runGtn("validate " + dir + "/hex.vtk").out);
  EXPECT_FALSE(mesh_file.value().issues.empty());  // the mirrored cells were turned around

  auto absent = gatun::validate({dir + "/absent.gtn"});
  ASSERT_FALSE(absent.ok());
  EXPECT_EQ(absent.error().code(), gatun::ErrorCode::kIo);
}

TEST(Api, RenderDrawsThePixelsOfGtnRender) {
  const std::string dir = tempDir("api_render");
  ASSERT_TRUE(gatun::write(dir + "/grid.gtn", gridMesh(4)).ok());
  gatun::RenderOptions options;
  options.width = 80;
  options.height = 60;
  options.azimuth = 40;
  auto image = gatun::render({dir + "/grid.gtn"}, options);
  ASSERT_TRUE(image.ok()) << image.error().message();
  ASSERT_EQ(image.value().rgb.size(), 80u * 60u * 3u);
  size_t lit = 0;
  for (uint8_t c : image.value().rgb) lit += c != 0;
  EXPECT_GT(lit, 1000u);
  ASSERT_TRUE(gatun::writePng(dir + "/api.png", image.value()).ok());

  ASSERT_EQ(runGtn("render " + dir + "/grid.gtn -o " + dir + "/cli.png --size 80x60 --azimuth 40 --no-cache").exit_code,
            0);
  auto cli = gtn::readPng(dir + "/cli.png");
  ASSERT_TRUE(cli.isOk()) << cli.status().message();
  EXPECT_EQ(cli->rgb, image.value().rgb);
  auto png = gtn::readPng(dir + "/api.png");
  ASSERT_TRUE(png.isOk());
  EXPECT_EQ(png->rgb, image.value().rgb);

  options.ratio = 0.5;
  auto coarse = gatun::render({dir + "/grid.gtn"}, options);
  ASSERT_TRUE(coarse.ok()) << coarse.error().message();
  ASSERT_EQ(
      runGtn("render " + dir + "/grid.gtn -o " + dir + "/cli-half.png --size 80x60 --azimuth 40 --ratio 0.5 --no-cache")
          .exit_code,
      0);
  EXPECT_EQ(gtn::readPng(dir + "/cli-half.png")->rgb, coarse.value().rgb);

  options.ratio.reset();
  options.field = "region";
  auto cell = gatun::render({dir + "/grid.gtn"}, options);
  ASSERT_FALSE(cell.ok());
  EXPECT_EQ(cell.error().code(), gatun::ErrorCode::kUsage);
  EXPECT_NE(cell.error().message().find("'region' is a cell field"), std::string::npos) << cell.error().message();

  // A transfer function file that is not there: the CLI's message (render/transfer_function.h).
  options.field.clear();
  options.transfer = dir + "/none.tf";
  auto no_tf = gatun::render({dir + "/grid.gtn"}, options);
  ASSERT_FALSE(no_tf.ok());
  EXPECT_NE(no_tf.error().message().find(dir + "/none.tf: cannot open the transfer function file (no such file)"),
            std::string::npos)
      << no_tf.error().message();

  gatun::Image wrong;
  wrong.width = 4;
  wrong.height = 4;
  wrong.rgb.resize(10);
  EXPECT_EQ(gatun::writePng(dir + "/wrong.png", wrong).code(), gatun::ErrorCode::kUsage);
}

// The header's promise: calls on different files may run at once. Four threads each write, read and
// render their own file; every result equals the one made alone.
TEST(Api, ThreadsWorkOnTheirOwnFiles) {
  const std::string dir = tempDir("api_threads");
  const gatun::Mesh mesh = gridMesh(4);
  ASSERT_TRUE(gatun::write(dir + "/alone.gtn", mesh).ok());
  const std::string alone = readFile(dir + "/alone.gtn");
  gatun::RenderOptions view;
  view.width = 48;
  view.height = 48;
  auto alone_image = gatun::render({dir + "/alone.gtn"}, view);
  ASSERT_TRUE(alone_image.ok());
  std::vector<std::string> bytes(4);
  std::vector<bool> same_mesh(4, false), same_image(4, false);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      const std::string path = dir + "/t" + std::to_string(t) + ".gtn";
      gatun::WriteOptions options;
      options.command_line = "gatun::write(alone.gtn)";
      if (!gatun::write(path, mesh, options).ok()) return;
      bytes[t] = readFile(path);
      auto back = gatun::read(path);
      same_mesh[t] = back.ok() && canonical(back.value()) == canonical(mesh);
      auto image = gatun::render({path}, view);
      same_image[t] = image.ok() && image.value().rgb == alone_image.value().rgb;
    });
  for (std::thread& t : threads) t.join();
  for (int t = 0; t < 4; ++t) {
    EXPECT_EQ(bytes[t], alone) << "thread " << t;
    EXPECT_TRUE(same_mesh[t]) << "thread " << t;
    EXPECT_TRUE(same_image[t]) << "thread " << t;
  }
}

// A level stored as pieces: the piece table, reads of chosen pieces and of a box, the level's numbers
// of a part's points and tetrahedra.
static_assert(gatun::WriteOptions{}.piece_tets == gtn::kDefaultPieceTets, "the API's default is gtn convert's");

TEST(Api, ReadsPiecesAndBoxesOfALevelInPieces) {
  const std::string dir = tempDir("api_pieces");
  const gatun::Mesh mesh = gridMesh(12);  // 10,368 tetrahedra
  gatun::WriteOptions options;
  options.levels = 0;
  options.piece_tets = 4096;
  ASSERT_TRUE(gatun::write(dir + "/grid.gtn", mesh, options).ok());
  auto opened = gatun::Reader::open(dir + "/grid.gtn");
  ASSERT_TRUE(opened.ok()) << opened.error().message();
  gatun::Reader reader = std::move(opened).value();
  const gatun::LevelInfo& level = reader.info().levels.at(0);
  ASSERT_GT(level.pieces.size(), 2u);
  uint64_t tets = 0, bytes = 0;
  for (const gatun::PieceInfo& p : level.pieces) {
    EXPECT_LE(p.tets, 4096u);
    EXPECT_GT(p.bytes, 0u);
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(reader.info().bbox_min[k], p.bbox_min[k]);
      EXPECT_LE(p.bbox_min[k], p.bbox_max[k]);
      EXPECT_LE(p.bbox_max[k], reader.info().bbox_max[k]);
    }
    tets += p.tets;
    bytes += p.bytes;
  }
  EXPECT_EQ(tets, mesh.tetCount());
  EXPECT_LT(bytes, level.bytes);

  gatun::ReadReport report;
  auto whole = reader.read({}, &report);
  ASSERT_TRUE(whole.ok()) << whole.error().message();
  const gatun::Mesh& w = whole.value();
  EXPECT_EQ(report.pieces.size(), level.pieces.size());
  EXPECT_TRUE(report.point_ids.empty() && report.tet_ids.empty());

  // Each piece alone: its points and tetrahedra are the whole read's of the same numbers; together the
  // pieces hold every tetrahedron once and every point (seam points in several pieces).
  std::vector<int> tet_seen(w.tetCount(), 0), point_seen(w.pointCount(), 0);
  for (uint32_t p = 0; p < level.pieces.size(); ++p) {
    auto part = reader.read({.pieces = std::vector<uint32_t>{p}}, &report);
    ASSERT_TRUE(part.ok()) << part.error().message();
    const gatun::Mesh& m = part.value();
    EXPECT_EQ(report.pieces, std::vector<uint32_t>{p});
    EXPECT_EQ(m.tetCount(), level.pieces[p].tets);
    ASSERT_EQ(report.point_ids.size(), m.pointCount());
    ASSERT_EQ(report.tet_ids.size(), m.tetCount());
    for (uint32_t i = 0; i < m.pointCount(); ++i) {
      EXPECT_EQ(pointOf(m, i), pointOf(w, report.point_ids[i]));
      EXPECT_EQ(m.pointField("density")->value(i, 0), w.pointField("density")->value(report.point_ids[i], 0));
      ++point_seen[report.point_ids[i]];
    }
    for (size_t t = 0; t < m.tetCount(); ++t) {
      for (int k = 0; k < 4; ++k) EXPECT_EQ(report.point_ids[m.tets[t][k]], w.tets[report.tet_ids[t]][k]);
      EXPECT_EQ(m.cellField("region")->value(t, 0), w.cellField("region")->value(report.tet_ids[t], 0));
      ++tet_seen[report.tet_ids[t]];
    }
  }
  EXPECT_EQ(std::count(tet_seen.begin(), tet_seen.end(), 1), static_cast<std::ptrdiff_t>(w.tetCount()));
  EXPECT_EQ(std::count(point_seen.begin(), point_seen.end(), 0), 0);
  EXPECT_GT(std::count_if(point_seen.begin(), point_seen.end(), [](int n) { return n > 1; }), 0);

  // A box: the pieces whose bounding boxes meet it are decoded, and the tetrahedra meeting it kept,
  // the same as the box read of each such piece alone.
  const std::array<double, 6> box{0.0, 0.0, 0.0, 3.5, 4.0, 2.5};
  std::vector<uint32_t> in_box;
  for (uint32_t p = 0; p < level.pieces.size(); ++p) {
    const gatun::PieceInfo& pi = level.pieces[p];
    bool meets = true;
    for (int k = 0; k < 3; ++k) meets = meets && pi.bbox_min[k] <= box[k + 3] && box[k] <= pi.bbox_max[k];
    if (meets) in_box.push_back(p);
  }
  ASSERT_FALSE(in_box.empty());
  ASSERT_LT(in_box.size(), level.pieces.size());
  auto boxed = reader.read({.box = box}, &report);
  ASSERT_TRUE(boxed.ok()) << boxed.error().message();
  EXPECT_EQ(report.pieces, in_box);
  std::set<uint64_t> boxed_ids(report.tet_ids.begin(), report.tet_ids.end());
  EXPECT_GT(boxed_ids.size(), 0u);
  EXPECT_LT(boxed_ids.size(), w.tetCount());
  std::set<uint64_t> one_by_one;
  for (uint32_t p : in_box) {
    ASSERT_TRUE(reader.read({.pieces = std::vector<uint32_t>{p}, .box = box}, &report).ok());
    one_by_one.insert(report.tet_ids.begin(), report.tet_ids.end());
  }
  EXPECT_EQ(boxed_ids, one_by_one);

  auto no_piece = reader.read({.pieces = std::vector<uint32_t>{0, 99}});
  ASSERT_FALSE(no_piece.ok());
  EXPECT_NE(no_piece.error().message().find("level 0: pieces: no piece 99 (the level has"), std::string::npos)
      << no_piece.error().message();
  auto with_ratio = reader.read({.ratio = 0.5, .pieces = std::vector<uint32_t>{0}});
  ASSERT_FALSE(with_ratio.ok());
  EXPECT_EQ(with_ratio.error().code(), gatun::ErrorCode::kUsage);
  options.piece_tets = 100;
  const gatun::Error small = gatun::write(dir + "/small.gtn", mesh, options);
  EXPECT_EQ(small.code(), gatun::ErrorCode::kUsage);
  EXPECT_NE(small.message().find("piece_tets 100 is below the smallest piece, 4096 tetrahedra"), std::string::npos)
      << small.message();
}

TEST(Api, VersionIsTheCommands) {
  EXPECT_EQ(std::string(gatun::version()), GTN_VERSION_STRING);
  EXPECT_NE(runGtn("--version").out.find(gatun::version()), std::string::npos);
}

}  // namespace

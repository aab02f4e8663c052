// A program built against the installed package (find_package(gatun), target gatun::gatun), in C++17:
// it makes a mesh, writes it as .gtn, reads it back, reads a ratio, converts, validates and renders,
// and checks each result. Usage: gatun_consumer WORK_DIR [GTN_COMMAND]; exit 0 when every check holds.
#include <gatun/gatun.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
  std::printf("%s: %s\n", ok ? "ok" : "FAILED", what.c_str());
  if (!ok) ++failures;
}

// An n x n x n grid of cubes, six tetrahedra each, with a point field and a cell field.
gatun::Mesh grid(int n) {
  gatun::Mesh m;
  const int p = n + 1;
  auto id = [&](int i, int j, int k) { return static_cast<uint32_t>((k * p + j) * p + i); };
  std::vector<double> temperature;
  for (int k = 0; k < p; ++k)
    for (int j = 0; j < p; ++j)
      for (int i = 0; i < p; ++i) {
        m.points.insert(m.points.end(), {double(i), double(j), double(k)});
        temperature.push_back(std::cos(0.5 * i) + 0.2 * j * k);
      }
  std::vector<uint8_t> part;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t c[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        const int paths[6][2] = {{1, 2}, {2, 3}, {3, 7}, {7, 4}, {4, 5}, {5, 1}};
        for (const auto& q : paths) {
          m.tets.push_back({c[0], c[q[0]], c[q[1]], c[6]});
          part.push_back(static_cast<uint8_t>(k));
        }
      }
  m.point_fields.push_back(gatun::Field::of("temperature", 1, temperature));
  m.cell_fields.push_back(gatun::Field::of("part", 1, part));
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: gatun_consumer WORK_DIR [GTN_COMMAND]\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::filesystem::create_directories(dir);
  std::printf("gatun %s\n", gatun::version());

  const gatun::Mesh mesh = grid(6);
  const std::string gtn = dir + "/grid.gtn";
  std::vector<std::string> warnings;
  gatun::WriteOptions options;
  options.levels = 2;
  gatun::Error error = gatun::write(gtn, mesh, options, &warnings);
  check(error.ok(), "write " + gtn + (error.ok() ? "" : ": " + error.message()));

  gatun::Result<gatun::FileInfo> info = gatun::readInfo(gtn);
  check(info.ok() && info.value().levels.size() == 3 && info.value().levels[0].points == mesh.pointCount() &&
            info.value().levels[0].tets == mesh.tetCount(),
        "readInfo: level 0 has the mesh's counts, and two mip levels follow");

  gatun::Result<gatun::Mesh> back = gatun::read(gtn);
  bool same_values = back.ok() && back.value().pointCount() == mesh.pointCount() &&
                     back.value().tetCount() == mesh.tetCount() && back.value().pointField("temperature") &&
                     back.value().cellField("part");
  if (same_values) {
    // The same multiset of values (the numbering may differ).
    double a = 0, b = 0;
    for (size_t i = 0; i < mesh.pointCount(); ++i) a += mesh.point_fields[0].value(i);
    for (size_t i = 0; i < back.value().pointCount(); ++i) b += back.value().pointField("temperature")->value(i);
    same_values = std::fabs(a - b) <= 1e-9 * std::fabs(a);
  }
  check(same_values, "read: " + std::to_string(mesh.pointCount()) + " points, " + std::to_string(mesh.tetCount()) +
                         " tetrahedra and their fields back");

  gatun::ReadOptions half;
  half.ratio = 0.5;
  gatun::ReadReport report;
  gatun::Result<gatun::Mesh> coarse = gatun::read(gtn, half, &report);
  check(coarse.ok() && coarse.value().pointCount() < mesh.pointCount() && std::fabs(report.ratio - 0.5) < 0.05,
        "read at ratio 0.5: " +
            (coarse.ok() ? std::to_string(coarse.value().pointCount()) + " points" : coarse.error().message()));

  gatun::ReadOptions missing;
  missing.level = 99;
  gatun::Result<gatun::Mesh> none = gatun::read(gtn, missing);
  check(!none.ok() && none.error().code() == gatun::ErrorCode::kUsage && none.error().exitCode() == 2,
        "read level 99: " + (none.ok() ? std::string("no error") : none.error().message()));

  const std::string vtu = dir + "/grid.vtu", again = dir + "/again.gtn";
  error = gatun::convert({gtn}, vtu);
  check(error.ok(), "convert to .vtu" + (error.ok() ? "" : ": " + error.message()));
  error = gatun::convert({vtu}, again);
  check(error.ok(), "convert .vtu to .gtn" + (error.ok() ? "" : ": " + error.message()));
  gatun::Result<gatun::Mesh> imported = gatun::importMesh({vtu});
  check(imported.ok() && imported.value().tetCount() == mesh.tetCount(), "importMesh .vtu: the same tetrahedra");

  gatun::Result<gatun::ValidationReport> valid = gatun::validate({again});
  check(valid.ok() && valid.value().ok() && valid.value().errors == 0,
        "validate " + again + (valid.ok() ? "" : ": " + valid.error().message()));

  gatun::RenderOptions view;
  view.width = 64;
  view.height = 48;
  gatun::Result<gatun::Image> image = gatun::render({gtn}, view);
  size_t lit = 0;
  if (image.ok())
    for (uint8_t c : image.value().rgb) lit += c != 0;
  check(image.ok() && image.value().rgb.size() == 64u * 48u * 3u && lit > 100,
        "render 64x48: " + std::to_string(lit) + " lit channels");
  if (image.ok()) {
    error = gatun::writePng(dir + "/grid.png", image.value());
    check(error.ok() && std::filesystem::file_size(dir + "/grid.png") > 100, "writePng");
  }

  if (argc > 2) {  // the installed command agrees
    const std::string run = std::string(argv[2]) + " validate " + again + " > " + dir + "/validate.txt 2>&1";
    check(std::system(run.c_str()) == 0, "the installed gtn validates " + again);
  }
  std::printf("%s\n", failures ? "consumer: FAILED" : "consumer: ok");
  return failures ? 1 : 0;
}

// bench-compression: the level codec in bits per tetrahedron, beside generic compressors of the raw
// binary arrays, then the bytes of the files `gtn convert` writes beside the .vtu files VTK writes, on
// every dataset of ../shared/data (or GTN_DATA_DIR) or on files the user names.
//
//   build/bench-compression [DATA_DIR [DATASET_SUBSTRING]] [OPTIONS]
//   build/bench-compression --files DATASET... [--split 5|6] [OPTIONS]
//   OPTIONS: --no-baselines  no zstd, xz, fpzip or VTK: the codec and the .gtn files alone
//            --no-files      the codec table only
//            --gtn PATH      the gtn program the file table runs (default: this build's)
//            --python PATH   a Python that imports VTK's modules (default /usr/bin/python3, Debian's
//                            python3-paraview; ParaView's pvpython also works)
//            --keep          keep each dataset's files (their directory is printed)
//
// With --files each argument is one dataset: a mesh file (.vtk, .vtu, .mesh, .meshb, .off), TetGen
// `x.ele` or `x.node`, a .p3d meta-file, or PLOT3D files joined by '+' (`grid.xyz+grid.q`, an
// argument that names an existing file is never split); --split picks how their hexahedra, wedges and
// pyramids become tetrahedra (default 6).
//
// The codec table. Columns: conn = boundary + peeling connectivity; geom = coordinates; fields =
// point and cell fields; total. Baselines on the raw arrays in their source types (uint32 tetrahedron
// indices; coordinates one axis after another, every x, then every y, then every z, which xz packs a
// little tighter than x y z per point on most meshes; then the fields as the source stores them):
// zstd -19 and xz -9 of the connectivity array and of the coordinate + field arrays (the `zstd` and
// `xz` programs), and fpzip (when built with it) of each float array, in grid order (i, j, k) for
// PLOT3D (points an importer added after the grid's, Steiner points of warped cells, as a 1-D array
// of their own) and in source order otherwise; non-float fields are added to the fpzip column at their xz -9
// size. Speeds are single-threaded rates in thread CPU time, of the fastest of several runs; "live" is
// the decoder's peak number of live vertices and "heap" its peak heap memory above what was allocated
// before it started (the payload it reads, which a streaming reader holds a chunk at a time, not
// counted), in MiB, counted by this program's operator new. Every encoding is decoded once more into
// a mesh and compared with the source up to renumbering (coordinates and field values bit for bit,
// orientation kept). Its last column judges the codec's targets: conn at most 2.5 b/t; geom + fields
// smaller than xz -9 of the coordinate + field arrays (xz.gf); and each value stream (the
// coordinates, each point field, each cell field) no larger than xz -9 of its own raw array (the
// coordinates axis after axis, a field as the source stores it), listed below the row in bytes
// (neither judged with --no-baselines).
//
// The file table, in bytes. `gtn convert` writes the default file (its defaults) and level 0 alone
// (--levels 0 --no-merge-tree); below each row, the default file's levels (each without its merge
// tree), its merge trees and the rest (prefix, header, directory, trailer), which add up to its size.
// `gtn export` writes level 0 as .vtu, and bench/vtk_vtu.py has VTK (vtkXMLUnstructuredGridWriter,
// appended binary, VTK's default settings otherwise) write that mesh again with zlib, lz4 and lzma
// compression and uncompressed. xz is xz -9 of the raw connectivity plus that of the raw coordinate
// and field arrays (the codec table's xz.c + xz.gf); fpzip that of the coordinates and float fields
// (non-float fields at xz -9) in each order tried, the smallest shown in the row: source order; grid
// order i, j, k as a 3-D array for a single-block PLOT3D grid; decode (level 0's vertices and
// tetrahedra as the decoder emits them); and morton (points by the Morton key of their position,
// cells by that of their centroid). Ratios: def/L0, zlib/L0 (level 0 against the zlib .vtu), zlib/def,
// def/lzma; the targets: the default file at most 1.3 times level 0, at most a third of the zlib .vtu
// and smaller than the lzma .vtu, and level 0 at most 16.5 b/t on bluntfin/5 and 26 on combustion/5.
//
// A summary after each table names the datasets that miss a target. Exit status: 2 on a usage error
// (nothing measured); 1 when a dataset fails to import, encode, decode losslessly, convert, export or
// be written by VTK (the other datasets are still measured); else 3 when a value stream is larger than
// xz -9 of its raw array; else 4 when a file target is missed; else 0.
#include <malloc.h>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "codec/level_check.h"
#include "codec/level_codec.h"
#include "convert/import.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stream.h"

#ifdef GTN_HAVE_FPZIP
#include <fpzip.h>
#endif

// Heap accounting for the decoder's peak memory: every operator new and delete of this program goes
// through these, which keep the bytes in use (as malloc_usable_size reports them) and their peak.
namespace heap {
std::atomic<size_t> in_use{0}, peak{0};
void* counted(void* p) {
  if (!p) throw std::bad_alloc();
  const size_t now = in_use.fetch_add(malloc_usable_size(p)) + malloc_usable_size(p);
  size_t old = peak.load();
  while (now > old && !peak.compare_exchange_weak(old, now)) {
  }
  return p;
}
void release(void* p) {
  if (!p) return;
  in_use.fetch_sub(malloc_usable_size(p));
  std::free(p);
}
void* aligned(size_t n, std::align_val_t a) {
  void* p = nullptr;
  if (posix_memalign(&p, std::max(sizeof(void*), static_cast<size_t>(a)), n ? n : 1) != 0) p = nullptr;
  return counted(p);
}
// Starts a new peak from what is in use now; returns that baseline.
size_t resetPeak() {
  const size_t now = in_use.load();
  peak.store(now);
  return now;
}
}  // namespace heap

void* operator new(size_t n) { return heap::counted(std::malloc(n ? n : 1)); }
void* operator new[](size_t n) { return heap::counted(std::malloc(n ? n : 1)); }
void* operator new(size_t n, std::align_val_t a) { return heap::aligned(n, a); }
void* operator new[](size_t n, std::align_val_t a) { return heap::aligned(n, a); }
void operator delete(void* p) noexcept { heap::release(p); }
void operator delete[](void* p) noexcept { heap::release(p); }
void operator delete(void* p, size_t) noexcept { heap::release(p); }
void operator delete[](void* p, size_t) noexcept { heap::release(p); }
void operator delete(void* p, std::align_val_t) noexcept { heap::release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { heap::release(p); }
void operator delete(void* p, size_t, std::align_val_t) noexcept { heap::release(p); }
void operator delete[](void* p, size_t, std::align_val_t) noexcept { heap::release(p); }

namespace {

// Thread CPU time: the benchmark machine may be shared, and wall-clock rates would measure the load.
using gtn::bench::Dataset;
using gtn::bench::threadSeconds;

// Size of `data` compressed by a command reading stdin (e.g. "xz -9 -c").
size_t externalSize(const std::vector<uint8_t>& data, const std::string& command) {
  if (data.empty()) return 0;
  char path[] = "/tmp/gtn-bench-XXXXXX";
  const int fd = mkstemp(path);
  if (fd < 0) return 0;
  FILE* f = fdopen(fd, "wb");
  fwrite(data.data(), 1, data.size(), f);
  fclose(f);
  const std::string cmd = command + " < " + path + " | wc -c";
  size_t n = 0;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    if (fscanf(p, "%zu", &n) != 1) n = 0;
    pclose(p);
  }
  std::remove(path);
  return n;
}

void append(std::vector<uint8_t>& out, const void* p, size_t n) {
  const uint8_t* b = static_cast<const uint8_t*>(p);
  out.insert(out.end(), b, b + n);
}

// Grid dimensions of a PLOT3D whole-grid file (big-endian int32 ni nj nk), or 0s.
void plot3dDims(const std::string& path, int dims[3]) {
  dims[0] = dims[1] = dims[2] = 0;
  std::ifstream in(path, std::ios::binary);
  uint8_t b[12];
  if (!in.read(reinterpret_cast<char*>(b), 12)) return;
  for (int i = 0; i < 3; ++i) dims[i] = (b[4 * i] << 24) | (b[4 * i + 1] << 16) | (b[4 * i + 2] << 8) | b[4 * i + 3];
}

#ifdef GTN_HAVE_FPZIP
size_t fpzipSize(const void* data, bool is_double, size_t n, const int dims[3]) {
  // A grid's points come first; points an importer added after them (Steiner points of warped
  // cells) are coded as a 1-D array of their own.
  const size_t grid = dims ? size_t(dims[0]) * dims[1] * dims[2] : 0;
  if (grid > 0 && grid < n)
    return fpzipSize(data, is_double, grid, dims) +
           fpzipSize(static_cast<const uint8_t*>(data) + grid * (is_double ? 8 : 4), is_double, n - grid, nullptr);
  std::vector<uint8_t> buf(n * (is_double ? 8 : 4) * 2 + 1024);
  FPZ* fpz = fpzip_write_to_buffer(buf.data(), buf.size());
  fpz->type = is_double ? FPZIP_TYPE_DOUBLE : FPZIP_TYPE_FLOAT;
  fpz->prec = 0;
  if (grid == n) {
    fpz->nx = dims[0];
    fpz->ny = dims[1];
    fpz->nz = dims[2];
  } else {
    fpz->nx = static_cast<int>(n);
    fpz->ny = fpz->nz = 1;
  }
  fpz->nf = 1;
  size_t out = 0;
  if (fpzip_write_header(fpz)) out = fpzip_write(fpz, data);
  fpzip_write_close(fpz);
  return out;
}

// fpzip of a mesh's coordinates (one axis after another) and float fields (one component after
// another), in the mesh's order, as a 3-D array of `dims` for the grid's points (the first ones) when
// given, else 1-D;
// `nonfloat_bytes` (the xz -9 size of the non-float fields) added.
size_t fpzipMeshBytes(const gtn::TetMesh& m, const int dims[3], size_t nonfloat_bytes) {
  size_t bytes = nonfloat_bytes;
  const size_t n = m.numPoints();
  const bool f32 = m.coord_type == gtn::ScalarType::kFloat32;
  for (int c = 0; c < 3; ++c) {
    if (f32) {
      std::vector<float> a(n);
      for (size_t v = 0; v < n; ++v) a[v] = static_cast<float>(m.coords[3 * v + c]);
      bytes += fpzipSize(a.data(), false, n, dims);
    } else {
      std::vector<double> a(n);
      for (size_t v = 0; v < n; ++v) a[v] = m.coords[3 * v + c];
      bytes += fpzipSize(a.data(), true, n, dims);
    }
  }
  for (const auto* list : {&m.point_fields, &m.cell_fields})
    for (const gtn::Field& f : *list) {
      if (!gtn::isFloatType(f.type)) continue;
      const size_t items = f.itemCount();
      const bool dbl = f.type == gtn::ScalarType::kFloat64;
      const int* dd = list == &m.point_fields ? dims : nullptr;
      for (uint32_t c = 0; c < f.components; ++c) {
        std::vector<uint8_t> a(items * f.valueSize());
        for (size_t i = 0; i < items; ++i)
          std::memcpy(&a[i * f.valueSize()], &f.bytes[(i * f.components + c) * f.valueSize()], f.valueSize());
        bytes += fpzipSize(a.data(), dbl, items, dd);
      }
    }
  return bytes;
}

// Morton (Z-order) key of a point in the box [lo, hi]: 21 bits per axis, interleaved.
uint64_t mortonKey(const double p[3], const double lo[3], const double hi[3]) {
  uint64_t key = 0;
  uint32_t q[3];
  for (int a = 0; a < 3; ++a) {
    const double t = hi[a] > lo[a] ? (p[a] - lo[a]) / (hi[a] - lo[a]) : 0.0;
    q[a] = static_cast<uint32_t>(std::clamp(t, 0.0, 1.0) * 2097151.0);
  }
  for (int b = 20; b >= 0; --b)
    for (int a = 0; a < 3; ++a) key = (key << 1) | ((q[a] >> b) & 1u);
  return key;
}

// The mesh's coordinates and fields reordered: points by the Morton key of their position, cells by
// that of their centroid (ties kept in source order). Connectivity is not carried (fpzip needs none).
gtn::TetMesh mortonOrdered(const gtn::TetMesh& m) {
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (size_t v = 0; v < m.numPoints(); ++v)
    for (int a = 0; a < 3; ++a)
      lo[a] = std::min(lo[a], m.coords[3 * v + a]), hi[a] = std::max(hi[a], m.coords[3 * v + a]);
  const auto order = [&](size_t n, auto position) {
    std::vector<std::pair<uint64_t, uint32_t>> keys(n);
    for (size_t i = 0; i < n; ++i) {
      double p[3];
      position(i, p);
      keys[i] = {mortonKey(p, lo, hi), static_cast<uint32_t>(i)};
    }
    std::sort(keys.begin(), keys.end());
    return keys;
  };
  const auto points =
      order(m.numPoints(), [&](size_t v, double p[3]) { std::memcpy(p, m.point(v), 3 * sizeof(double)); });
  const auto cells = order(m.numTets(), [&](size_t t, double p[3]) {
    p[0] = p[1] = p[2] = 0;
    for (uint32_t v : m.tets[t])
      for (int a = 0; a < 3; ++a) p[a] += 0.25 * m.coords[3 * v + a];
  });
  gtn::TetMesh out;
  out.coord_type = m.coord_type;
  out.coords.resize(m.coords.size());
  for (size_t i = 0; i < points.size(); ++i)
    std::memcpy(&out.coords[3 * i], m.point(points[i].second), 3 * sizeof(double));
  for (const auto& [src, dst, keys] :
       {std::tie(m.point_fields, out.point_fields, points), std::tie(m.cell_fields, out.cell_fields, cells)})
    for (const gtn::Field& f : src) {
      gtn::Field g(f.name, f.components, f.type, f.itemCount());
      for (size_t i = 0; i < keys.size(); ++i) g.copyItem(f, keys[i].second, i);
      dst.push_back(std::move(g));
    }
  return out;
}
#endif

// The codec's connectivity target (boundary + peeling), from the Gatun paper.
constexpr double kMaxConnectivityBits = 2.5;
// The file targets: the default file at most 1.3 times level 0 alone, at most a third of the zlib .vtu
// and smaller than the lzma .vtu; level 0 of the curvilinear grids (5-split) within these bits per
// tetrahedron, all included.
constexpr double kMaxDefaultOverLevel0 = 1.3;
constexpr double kMaxDefaultOverZlibVtu = 1.0 / 3.0;
constexpr double kMaxBluntFinBits = 16.5, kMaxCombustionBits = 26.0;

// One --files argument as a dataset: the file itself, or PLOT3D files joined by '+'.
Dataset namedDataset(const std::string& arg, int split) {
  Dataset d{"", {}, split};
  if (std::filesystem::exists(arg)) {
    d.inputs = {arg};
  } else {
    for (size_t begin = 0, plus;; begin = plus + 1) {
      plus = arg.find('+', begin);
      d.inputs.push_back(arg.substr(begin, plus == std::string::npos ? std::string::npos : plus - begin));
      if (plus == std::string::npos) break;
    }
  }
  for (const std::string& in : d.inputs) {
    if (!d.name.empty()) d.name += '+';
    d.name += std::filesystem::path(in).filename().string();
  }
  return d;
}

// The files of one dataset: `gtn convert` with its defaults and with level 0 alone, and the .vtu files
// VTK writes of level 0 (as `gtn export` writes it: points, tetrahedra, all fields).
struct FileSizes {
  uint64_t level0_alone = 0;   // gtn convert --levels 0 --no-merge-tree
  uint64_t default_bytes = 0;  // gtn convert with its defaults
  struct Level {
    uint64_t bytes = 0, merge_tree = 0, tets = 0;  // bytes of the level without its merge tree
  };
  std::vector<Level> levels;       // of the default file
  uint64_t other = 0;              // the default file outside its levels: prefix, header, directory, trailer
  uint64_t vtu[4] = {0, 0, 0, 0};  // zlib, lz4, lzma, raw (uncompressed) .vtu; 0 when not measured
};
constexpr const char* kVtuKinds[4] = {"zlib", "lz4", "lzma", "raw"};

// The programs the file table runs.
struct Tools {
  std::string gtn = GTN_CLI_PATH;                 // --gtn
  std::string python = "/usr/bin/python3";        // --python: one that imports VTK's modules
  std::string vtk_script = GTN_BENCH_VTK_SCRIPT;  // bench/vtk_vtu.py
  bool vtk = true;                                // false with --no-baselines
};

// Writes the files in `dir` and measures them; `decoded` receives level 0 as the decoder emits it.
// Returns "" on success, else what failed (its output is in dir/log).
std::string measureFiles(const Dataset& d, const Tools& tools, const std::string& dir, FileSizes& out,
                         gtn::TetMesh& decoded) {
  using gtn::bench::runLogged;
  using gtn::bench::shellQuote;
  const std::string log = dir + "/log", def = dir + "/default.gtn", l0 = dir + "/level0.gtn", vtu = dir + "/level0.vtu";
  const std::string convert = shellQuote(tools.gtn) + " convert " + gtn::bench::convertInputs(d) + " -q";
  if (!runLogged(convert + " -o " + shellQuote(def), log)) return "gtn convert (defaults)";
  if (!runLogged(convert + " --levels 0 --no-merge-tree -o " + shellQuote(l0), log))
    return "gtn convert --levels 0 --no-merge-tree";
  std::error_code ec;
  out.level0_alone = std::filesystem::file_size(l0, ec);
  if (ec) return l0 + ": " + ec.message();
  auto reader = gtn::GtnReader::open(def);
  if (!reader.isOk()) return reader.status().message();
  out.default_bytes = (*reader)->file().bytes;
  uint64_t in_levels = 0;
  for (size_t i = 0; i < (*reader)->levels(); ++i) {
    const gtn::GtnLevelInfo& info = (*reader)->level(i);
    FileSizes::Level level;
    level.tets = info.header.tets;
    for (const gtn::GtnChunkInfo& c : info.chunks)
      (c.section == "merge_tree" ? level.merge_tree : level.bytes) += c.bytes;
    in_levels += level.bytes + level.merge_tree;
    out.levels.push_back(level);
  }
  out.other = out.default_bytes - in_levels;
  auto level0 = gtn::GtnReader::open(l0);
  if (!level0.isOk()) return level0.status().message();
  gtn::TetMeshBuilder builder;
  if (const gtn::Status st = (*level0)->decodeLevel(0, builder); !st.isOk()) return st.message();
  decoded = std::move(builder.mesh());
  if (!tools.vtk) return "";
  if (!runLogged(shellQuote(tools.gtn) + " export " + shellQuote(def) + " -o " + shellQuote(vtu), log))
    return "gtn export";
  if (!runLogged(shellQuote(tools.python) + " " + shellQuote(tools.vtk_script) + " write " + shellQuote(vtu) + " " +
                     shellQuote(dir + "/vtk"),
                 log))
    return "VTK's .vtu writer (" + tools.python + " " + tools.vtk_script + ")";
  for (int k = 0; k < 4; ++k) {
    out.vtu[k] = std::filesystem::file_size(dir + "/vtk." + kVtuKinds[k] + ".vtu", ec);
    if (ec) return dir + "/vtk." + kVtuKinds[k] + ".vtu: " + ec.message();
  }
  return "";
}

// The raw bytes of a mesh's non-float fields, point fields first (fpzip codes only floats).
std::vector<uint8_t> nonFloatBytes(const gtn::TetMesh& m) {
  std::vector<uint8_t> out;
  for (const auto* list : {&m.point_fields, &m.cell_fields})
    for (const gtn::Field& f : *list)
      if (!gtn::isFloatType(f.type)) append(out, f.bytes.data(), f.bytes.size());
  return out;
}

// One dataset's line of the file table.
struct FileRow {
  std::string name;
  size_t tets = 0;
  FileSizes sizes;
  size_t xz = 0;  // xz -9 of the raw connectivity, coordinate and field arrays; 0 when not measured
  std::vector<std::pair<std::string, size_t>> fpzip;  // bytes per order tried
  double max_level0_bits = 0;                         // the dataset's level-0 target in bits per tetrahedron, 0: none
};

std::string withCommas(uint64_t n) {
  const std::string digits = std::to_string(n);
  std::string s;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) s += ',';
    s += digits[i];
  }
  return s;
}

// Prints the file table and its targets; returns the datasets that miss one.
std::vector<std::string> printFileTable(const std::vector<FileRow>& rows, int w, bool skip_baselines) {
  std::vector<std::string> missed;
  if (rows.empty()) return missed;
  std::printf(
      "\nfiles, bytes: default = `gtn convert` with its defaults; L0 = `gtn convert --levels 0 --no-merge-tree`;\n"
      "zlib, lz4, lzma, raw = level 0 as .vtu written by VTK (appended binary; raw: uncompressed); xz = xz -9 of the "
      "raw\n"
      "connectivity, coordinate and field arrays; fpzip = coordinates and fields (non-float fields at xz -9) in the\n"
      "smallest of the orders tried (source; grid i, j, k for PLOT3D; decode: level 0's decoded order; morton)\n");
  std::printf("%-*s %8s | %10s %10s | %10s %10s %10s %10s | %10s %10s %-6s | %6s %6s %6s %6s %6s | %s\n", w, "dataset",
              "tets", "L0", "default", "zlib.vtu", "lz4.vtu", "lzma.vtu", "raw.vtu", "xz", "fpzip", "order", "L0",
              "def/", "zlib/", "zlib/", "def/", "targets");
  std::printf("%-*s %8s | %10s %10s | %10s %10s %10s %10s | %10s %10s %-6s | %6s %6s %6s %6s %6s | %s\n", w, "", "", "",
              "", "", "", "", "", "", "", "", "b/t", "L0", "L0", "def", "lzma",
              "def<=1.3 L0, def<=zlib/3, def<lzma, L0 b/t");
  const auto cell = [](uint64_t n) { return n ? withCommas(n) : std::string("-"); };
  for (const FileRow& r : rows) {
    const FileSizes& z = r.sizes;
    const double nt = static_cast<double>(r.tets), def = static_cast<double>(z.default_bytes);
    const double l0 = static_cast<double>(z.level0_alone);
    const double zlib = static_cast<double>(z.vtu[0]), lzma = static_cast<double>(z.vtu[2]);
    const auto best = std::min_element(r.fpzip.begin(), r.fpzip.end(),
                                       [](const auto& a, const auto& b) { return a.second < b.second; });
    const bool has_vtu = z.vtu[0] > 0 && z.vtu[2] > 0;
    const double l0_bits = 8.0 * l0 / nt;
    const bool levels_ok = def <= kMaxDefaultOverLevel0 * l0;
    const bool zlib_ok = !has_vtu || def <= kMaxDefaultOverZlibVtu * zlib, lzma_ok = !has_vtu || def < lzma;
    const bool bits_ok = r.max_level0_bits == 0 || l0_bits <= r.max_level0_bits;
    char ratio[4][16];
    std::snprintf(ratio[0], 16, "%.2f", def / l0);
    std::snprintf(ratio[1], 16, has_vtu ? "%.2f" : "-", zlib / l0);
    std::snprintf(ratio[2], 16, has_vtu ? "%.2f" : "-", zlib / def);
    std::snprintf(ratio[3], 16, has_vtu ? "%.2f" : "-", def / lzma);
    char bits_target[32] = "-";
    if (r.max_level0_bits > 0) std::snprintf(bits_target, sizeof bits_target, "%s", bits_ok ? "ok" : "MISS");
    std::printf("%-*s %8zu | %10s %10s | %10s %10s %10s %10s | %10s %10s %-6s | %6.2f %6s %6s %6s %6s | %s %s %s %s\n",
                w, r.name.c_str(), r.tets, cell(z.level0_alone).c_str(), cell(z.default_bytes).c_str(),
                cell(z.vtu[0]).c_str(), cell(z.vtu[1]).c_str(), cell(z.vtu[2]).c_str(), cell(z.vtu[3]).c_str(),
                cell(r.xz).c_str(), best == r.fpzip.end() ? "-" : withCommas(best->second).c_str(),
                best == r.fpzip.end() ? "-" : best->first.c_str(), l0_bits, ratio[0], ratio[1], ratio[2], ratio[3],
                levels_ok ? "ok" : "MISS",
                !has_vtu  ? "-"
                : zlib_ok ? "ok"
                          : "MISS",
                !has_vtu  ? "-"
                : lzma_ok ? "ok"
                          : "MISS",
                bits_target);
    std::printf("  %-*s default file:", w - 2, "");
    uint64_t trees = 0;
    for (size_t i = 0; i < z.levels.size(); ++i) {
      std::printf(" L%zu %s (%s tets);", i, withCommas(z.levels[i].bytes).c_str(),
                  withCommas(z.levels[i].tets).c_str());
      trees += z.levels[i].merge_tree;
    }
    std::printf(" merge tree%s %s; header, directory, trailer %s\n", z.levels.size() > 1 ? "s" : "",
                withCommas(trees).c_str(), withCommas(z.other).c_str());
    if (!r.fpzip.empty()) {
      std::printf("  %-*s fpzip by order:", w - 2, "");
      for (const auto& [order, bytes] : r.fpzip)
        std::printf(" %s %s (%.2f b/t);", order.c_str(), withCommas(bytes).c_str(), 8.0 * bytes / nt);
      std::printf("\n");
    }
    char why[160];
    std::string misses;
    const auto miss = [&](const char* text) { misses += (misses.empty() ? "" : "; ") + std::string(text); };
    if (!levels_ok) {
      std::snprintf(why, sizeof why, "default %.2f x level 0 > %.1f", def / l0, kMaxDefaultOverLevel0);
      miss(why);
    }
    if (!zlib_ok) {
      std::snprintf(why, sizeof why, "default %.3f x zlib .vtu > 1/3", def / zlib);
      miss(why);
    }
    if (!lzma_ok) {
      std::snprintf(why, sizeof why, "default %.3f x lzma .vtu >= 1", def / lzma);
      miss(why);
    }
    if (!bits_ok) {
      std::snprintf(why, sizeof why, "level 0 %.2f b/t > %.1f", l0_bits, r.max_level0_bits);
      miss(why);
    }
    if (!misses.empty()) missed.push_back(r.name + " (" + misses + ")");
  }
  std::printf(
      "\nfile targets: default <= %.1f x level 0%s; level 0 <= %.1f b/t on bluntfin/5, <= %.1f b/t on "
      "combustion/5; %zu missed%s\n",
      kMaxDefaultOverLevel0,
      skip_baselines ? " (against the .vtu files not judged: --no-baselines)"
                     : ", <= 1/3 of the zlib .vtu, < the lzma .vtu",
      kMaxBluntFinBits, kMaxCombustionBits, missed.size(), missed.empty() ? "" : ":");
  for (const std::string& m : missed) std::printf("  %s\n", m.c_str());
  return missed;
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage =
      "usage: %s [DATA_DIR [DATASET_SUBSTRING]] [OPTIONS]\n"
      "       %s --files DATASET... [--split 5|6] [OPTIONS]\n"
      "  DATASET: a mesh file, TetGen x.ele, or PLOT3D files joined by '+' (grid.xyz+grid.q)\n"
      "  OPTIONS: --no-baselines (no zstd, xz, fpzip or VTK), --no-files (the codec table only),\n"
      "           --gtn PATH (the gtn program), --python PATH (a Python that imports VTK), --keep (keep the files)\n";
  if (argc > 1 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0)) {
    std::printf(usage, argv[0], argv[0]);
    return 0;
  }
  std::vector<Dataset> sets;
  std::string filter;
  bool skip_baselines = false, skip_files = false, keep = false, named = false;
  Tools tools;
  int split = 6;
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--files" && i == 1) {
      named = true;
    } else if (a == "--no-baselines") {
      skip_baselines = true;
    } else if (a == "--no-files") {
      skip_files = true;
    } else if (a == "--keep") {
      keep = true;
    } else if ((a == "--gtn" || a == "--python") && i + 1 < argc) {
      (a == "--gtn" ? tools.gtn : tools.python) = argv[++i];
    } else if (named && a == "--split" && i + 1 < argc &&
               (std::strcmp(argv[i + 1], "5") == 0 || std::strcmp(argv[i + 1], "6") == 0)) {
      split = std::atoi(argv[++i]);
    } else if (a[0] == '-') {
      std::fprintf(stderr, "bench-compression: unknown or incomplete option '%s'\n", argv[i]);
      std::fprintf(stderr, usage, argv[0], argv[0]);
      return 2;
    } else {
      args.push_back(a);
    }
  }
  if (named) {
    if (args.empty()) {
      std::fprintf(stderr, "bench-compression: --files needs at least one dataset\n");
      std::fprintf(stderr, usage, argv[0], argv[0]);
      return 2;
    }
    for (const std::string& arg : args) sets.push_back(namedDataset(arg, split));
  } else {
    if (args.size() > 2) {
      std::fprintf(stderr, "bench-compression: unexpected argument '%s'\n", args[2].c_str());
      std::fprintf(stderr, usage, argv[0], argv[0]);
      return 2;
    }
    sets =
        gtn::bench::sharedDatasets(gtn::bench::dataDir(args.empty() ? nullptr : args[0].c_str(), GTN_DEFAULT_DATA_DIR));
    if (args.size() > 1) filter = args[1];
  }
  tools.vtk = !skip_baselines;
  int w = 16;  // width of the dataset column
  for (const Dataset& d : sets) w = std::max(w, static_cast<int>(d.name.size()));
  std::printf("bits per tetrahedron; conn = boundary + peeling. Raw-array baselines: zstd -19, xz -9%s\n",
#ifdef GTN_HAVE_FPZIP
              ", fpzip (float arrays)"
#else
              " (built without fpzip)"
#endif
  );
  std::printf("%-*s %8s %8s | %6s %6s %6s %7s | %7s %7s | %7s %7s %7s | %6s %6s %7s %6s | %s\n", w, "dataset", "points",
              "tets", "conn", "geom", "fields", "total", "zstd.c", "xz.c", "zstd.gf", "xz.gf", "fpzip", "enc", "dec",
              "peak", "peak", "targets");
  std::printf("%-*s %8s %8s | %6s %6s %6s %7s | %7s %7s | %7s %7s %7s | %6s %6s %7s %6s | %s\n", w, "", "", "", "b/t",
              "b/t", "b/t", "b/t", "b/t", "b/t", "b/t", "b/t", "b/t", "Mt/s", "Mt/s", "live", "MiB",
              "conn, gf<xz, each<=xz");
  std::vector<std::string> failed, missed;  // datasets that failed to run; datasets that miss a target
  bool stream_missed = false;               // a value stream larger than xz -9 of its raw array
  std::vector<FileRow> files;               // the file table, printed after the codec table
  for (const Dataset& d : sets) {
    if (!filter.empty() && d.name.find(filter) == std::string::npos) continue;
    const auto fail = [&](const char* what, const std::string& why) {
      std::printf("%-*s %s failed: %s\n", w, d.name.c_str(), what, why.c_str());
      std::fflush(stdout);
      failed.push_back(d.name + " (" + what + ")");
    };
    gtn::ImportOptions io;
    io.split = d.split;
    auto imported = gtn::importMesh(d.inputs, io);
    if (!imported.isOk() || imported->mesh.numTets() == 0) {
      fail("import", imported.isOk() ? "no tetrahedra" : imported.status().message());
      continue;
    }
    const gtn::TetMesh& m = imported->mesh;
    const double nt = static_cast<double>(m.numTets());

    // Encode, repeated: the fastest run counts (other processes only ever slow a run down).
    int reps = 0;
    double t0 = threadSeconds();
    gtn::StatusOr<gtn::EncodedLevel> enc = gtn::encodeLevel(m, gtn::EncodeOptions{});
    double enc_s = threadSeconds() - t0, spent = enc_s;
    while (enc.isOk() && (spent < 0.6 || reps < 3) && reps < 50) {
      t0 = threadSeconds();
      enc = gtn::encodeLevel(m, gtn::EncodeOptions{});
      const double s = threadSeconds() - t0;
      enc_s = std::min(enc_s, s);
      spent += s;
      ++reps;
    }
    if (!enc.isOk()) {
      fail("encode", enc.status().message());
      continue;
    }
    const gtn::EncodedLevel& e = *enc;
    const gtn::LevelPayload pl = gtn::payloadOf(e);
    reps = 0;
    double dec_s = 1e300;
    spent = 0;
    gtn::DecodeStats stats;
    size_t heap_peak = 0;  // bytes, the largest over the runs (they should all agree)
    do {
      gtn::CountingSink sink;
      const size_t heap_base = heap::resetPeak();
      t0 = threadSeconds();
      const gtn::Status st = gtn::decodeLevel(e.header, pl, sink, &stats, d.name);
      const double s = threadSeconds() - t0;
      heap_peak = std::max(heap_peak, heap::peak.load() - heap_base);
      if (!st.isOk()) {
        fail("decode", st.message());
        reps = 0;
        break;
      }
      dec_s = std::min(dec_s, s);
      spent += s;
      ++reps;
    } while ((spent < 0.6 || reps < 5) && reps < 100);
    if (reps == 0) continue;
    if (const std::string why = gtn::losslessMismatch(m, e); !why.empty()) {
      fail("lossless decode", why);
      continue;
    }

    size_t field_bytes = 0;
    for (const auto& s : e.point_fields) field_bytes += s.size();
    for (const auto& s : e.cell_fields) field_bytes += s.size();
    const double conn = 8.0 * (e.boundary.size() + e.connectivity.size()) / nt;
    const double geom = 8.0 * e.geometry.size() / nt;
    const double fields = 8.0 * field_bytes / nt;

    // Raw arrays as the source stores them.
    std::vector<uint8_t> raw_conn, raw_gf, raw_nonfloat;
    for (const gtn::Tet& t : m.tets) append(raw_conn, t.data(), 16);
    const bool f32 = m.coord_type == gtn::ScalarType::kFloat32;
    std::vector<float> cf;
    std::vector<double> cd;
    for (int c = 0; c < 3; ++c)
      for (size_t v = 0; v < m.numPoints(); ++v) {
        if (f32) {
          const float x = static_cast<float>(m.coords[3 * v + c]);
          append(raw_gf, &x, 4);
        } else {
          append(raw_gf, &m.coords[3 * v + c], 8);
        }
      }
    for (const auto* list : {&m.point_fields, &m.cell_fields})
      for (const gtn::Field& f : *list) {
        append(raw_gf, f.bytes.data(), f.bytes.size());
        if (!gtn::isFloatType(f.type)) append(raw_nonfloat, f.bytes.data(), f.bytes.size());
      }
    if (skip_baselines) raw_conn.clear(), raw_gf.clear(), raw_nonfloat.clear();
    // Each value stream against xz -9 of its own raw array: the coordinates (the first 3 x points
    // values of raw_gf), then each point field and each cell field as the source stores it.
    struct StreamSize {
      std::string name;
      size_t coded, xz;
    };
    std::vector<StreamSize> streams;
    if (!skip_baselines) {
      const size_t coord_bytes = 3 * m.numPoints() * gtn::scalarSize(m.coord_type);
      streams.push_back({"coordinates", e.geometry.size(),
                         externalSize(std::vector<uint8_t>(raw_gf.begin(), raw_gf.begin() + coord_bytes), "xz -9 -c")});
      for (size_t f = 0; f < m.point_fields.size(); ++f)
        streams.push_back({"point field " + m.point_fields[f].name, e.point_fields[f].size(),
                           externalSize(m.point_fields[f].bytes, "xz -9 -c")});
      for (size_t f = 0; f < m.cell_fields.size(); ++f)
        streams.push_back({"cell field " + m.cell_fields[f].name, e.cell_fields[f].size(),
                           externalSize(m.cell_fields[f].bytes, "xz -9 -c")});
    }
    const double zc = 8.0 * externalSize(raw_conn, "zstd -q -19 -c") / nt;
    const size_t xz_conn = externalSize(raw_conn, "xz -9 -c"), xz_gf = externalSize(raw_gf, "xz -9 -c");
    const double xc = 8.0 * xz_conn / nt;
    const double zgf = 8.0 * externalSize(raw_gf, "zstd -q -19 -c") / nt;
    const double xgf = 8.0 * xz_gf / nt;
    double fp = -1;
    int dims[3] = {0, 0, 0};  // the grid's, for a single-block PLOT3D grid
    if (m.findMetadata("source.format") && *m.findMetadata("source.format") == "plot3d") plot3dDims(d.inputs[0], dims);
    const size_t nonfloat_xz = skip_baselines ? 0 : externalSize(raw_nonfloat, "xz -9 -c");
#ifdef GTN_HAVE_FPZIP
    if (!skip_baselines) fp = 8.0 * fpzipMeshBytes(m, dims, nonfloat_xz) / nt;
#endif
    if (std::getenv("GTN_BENCH_SPLIT"))
      std::printf("  boundary %.3f b/t (%llu triangles), peeling %.3f b/t\n", 8.0 * e.boundary.size() / nt,
                  static_cast<unsigned long long>(e.header.boundary_triangles), 8.0 * e.connectivity.size() / nt);
    // xz.gf is 0 when the xz program failed: nothing to judge against then.
    const bool judge_gf = !skip_baselines && xgf > 0;
    const bool conn_ok = conn <= kMaxConnectivityBits, gf_ok = !judge_gf || geom + fields < xgf;
    // A stream is judged when xz ran (its size is 0 when the program failed).
    std::string stream_misses;
    for (const StreamSize& s : streams)
      if (s.xz > 0 && s.coded > s.xz) {
        char why[200];
        std::snprintf(why, sizeof why, "%s%s %zu B > xz -9 %zu B", stream_misses.empty() ? "" : ", ", s.name.c_str(),
                      s.coded, s.xz);
        stream_misses += why;
      }
    std::printf(
        "%-*s %8zu %8zu | %6.3f %6.2f %6.2f %7.2f | %7.2f %7.2f | %7.2f %7.2f %7.2f | %6.2f %6.2f %7llu %6.2f | %s %s "
        "%s\n",
        w, d.name.c_str(), m.numPoints(), m.numTets(), conn, geom, fields, conn + geom + fields, zc, xc, zgf, xgf, fp,
        nt / enc_s / 1e6, nt / dec_s / 1e6, static_cast<unsigned long long>(stats.peak_live_vertices),
        heap_peak / 1048576.0, conn_ok ? "ok" : "MISS",
        !judge_gf ? "-"
        : gf_ok   ? "ok"
                  : "MISS",
        streams.empty()         ? "-"
        : stream_misses.empty() ? "ok"
                                : "MISS");
    if (!streams.empty()) {
      std::printf("  %-*s bytes coded / xz -9 of the raw array:", w - 2, "");
      for (const StreamSize& s : streams) std::printf(" %s %zu/%zu;", s.name.c_str(), s.coded, s.xz);
      std::printf("\n");
    }
    std::fflush(stdout);
    char why[160];
    std::string misses;
    if (!conn_ok) {
      std::snprintf(why, sizeof why, "conn %.3f b/t > %.1f", conn, kMaxConnectivityBits);
      misses = why;
    }
    if (!gf_ok) {
      std::snprintf(why, sizeof why, "geom + fields %.2f b/t >= xz -9 %.2f b/t", geom + fields, xgf);
      misses += (misses.empty() ? "" : "; ") + std::string(why);
    }
    if (!stream_misses.empty()) {
      misses += (misses.empty() ? "" : "; ") + stream_misses;
      stream_missed = true;
    }
    if (!misses.empty()) missed.push_back(d.name + " (" + misses + ")");
    if (skip_files) continue;

    // The files: written in a directory of their own, removed afterwards unless --keep or a step failed.
    const std::string dir = gtn::bench::makeTempDir("gtn-bench-compression");
    if (dir.empty()) {
      fail("files", "cannot make a temporary directory");
      continue;
    }
    FileRow row;
    row.name = d.name;
    row.tets = m.numTets();
    row.max_level0_bits = d.name == "bluntfin/5" ? kMaxBluntFinBits : d.name == "combustion/5" ? kMaxCombustionBits : 0;
    gtn::TetMesh decoded;
    if (const std::string why = measureFiles(d, tools, dir, row.sizes, decoded); !why.empty()) {
      fail("files", why + "; output in " + dir + "/log");
      continue;
    }
    if (!skip_baselines) {
      row.xz = xz_conn + xz_gf;
#ifdef GTN_HAVE_FPZIP
      row.fpzip.push_back({"source", fpzipMeshBytes(m, nullptr, nonfloat_xz)});
      if (dims[0] > 0 && size_t(dims[0]) * dims[1] * dims[2] <= m.numPoints())
        row.fpzip.push_back({"grid", fpzipMeshBytes(m, dims, nonfloat_xz)});
      row.fpzip.push_back(
          {"decode", fpzipMeshBytes(decoded, nullptr, externalSize(nonFloatBytes(decoded), "xz -9 -c"))});
      const gtn::TetMesh morton = mortonOrdered(m);
      row.fpzip.push_back({"morton", fpzipMeshBytes(morton, nullptr, externalSize(nonFloatBytes(morton), "xz -9 -c"))});
#endif
    }
    files.push_back(std::move(row));
    if (keep) std::printf("  files kept in %s\n", dir.c_str());
    else std::filesystem::remove_all(dir);
    std::fflush(stdout);
  }
  std::printf("\ntargets: conn <= %.1f b/t%s; %zu missed%s\n", kMaxConnectivityBits,
              skip_baselines
                  ? " (geom + fields and each value stream against xz -9 not judged: --no-baselines)"
                  : ", geom + fields < xz -9 of the raw coordinate + field arrays, each value stream <= xz -9 "
                    "of its raw array",
              missed.size(), missed.empty() ? "" : ":");
  for (const std::string& m : missed) std::printf("  %s\n", m.c_str());
  const std::vector<std::string> file_missed = printFileTable(files, w, skip_baselines);
  if (!failed.empty()) {
    std::printf("%zu failed:\n", failed.size());
    for (const std::string& f : failed) std::printf("  %s\n", f.c_str());
  }
  return !failed.empty() ? 1 : stream_missed ? 3 : !file_missed.empty() ? 4 : 0;
}

// bench-compression: the level codec in bits per tetrahedron, beside generic compressors of the raw
// binary arrays, on every dataset of ../shared/data (or GTN_DATA_DIR) or on files the user names.
//
//   build/bench-compression [DATA_DIR [DATASET_SUBSTRING [--no-baselines]]]
//   build/bench-compression --files DATASET... [--split 5|6] [--no-baselines]
//
// With --files each argument is one dataset: a mesh file (.vtk, .vtu, .mesh, .meshb, .off), TetGen
// `x.ele` or `x.node`, a .p3d meta-file, or PLOT3D files joined by '+' (`grid.xyz+grid.q`, an
// argument that names an existing file is never split); --split picks how their hexahedra, wedges and
// pyramids become tetrahedra (default 6).
//
// Columns: conn = boundary + peeling connectivity; geom = coordinates; fields = point and cell
// fields; total. Baselines on the raw arrays in their source types (uint32 tetrahedron indices;
// coordinates one axis after another, every x, then every y, then every z, which xz packs a little
// tighter than x y z per point on most meshes; then the fields as the source stores them): zstd -19
// and xz -9 of the connectivity array and of the coordinate + field arrays (the `zstd` and `xz`
// programs), and fpzip (when built with it) of each float array, in grid order (i, j, k) for PLOT3D
// and in source order otherwise; non-float fields are added to the fpzip column at their xz -9 size.
// Speeds are single-threaded rates in thread CPU time, of the fastest of several runs; "live" is the
// decoder's peak number of live vertices and "heap" its peak heap memory above what was allocated
// before it started (the payload it reads, which a streaming reader holds a chunk at a time, not
// counted), in MiB, counted by this program's operator new. Every encoding
// is decoded once more into a mesh and compared with the source up to renumbering (coordinates and
// field values bit for bit, orientation kept).
//
// The last column judges the codec's targets: conn at most 2.5 b/t; geom + fields smaller than xz -9
// of the coordinate + field arrays (xz.gf); and each value stream (the coordinates, each point field,
// each cell field) no larger than xz -9 of its own raw array (the coordinates axis after axis, a
// field as the source stores it), listed below the row in bytes (neither judged with
// --no-baselines). A final summary names the datasets that miss one. Exit status 1 when a dataset
// fails to import, encode or decode losslessly (the other datasets are still measured), 2 on a usage
// error, 3 when a value stream is larger than xz -9 of its raw array, else 0.
#include <algorithm>
#include <atomic>
#include <malloc.h>
#include <new>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "codec/level_check.h"
#include "codec/level_codec.h"
#include "convert/import.h"

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
  std::vector<uint8_t> buf(n * (is_double ? 8 : 4) * 2 + 1024);
  FPZ* fpz = fpzip_write_to_buffer(buf.data(), buf.size());
  fpz->type = is_double ? FPZIP_TYPE_DOUBLE : FPZIP_TYPE_FLOAT;
  fpz->prec = 0;
  if (dims && size_t(dims[0]) * dims[1] * dims[2] == n) {
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
#endif

// The codec's connectivity target (boundary + peeling), from the Gatun paper.
constexpr double kMaxConnectivityBits = 2.5;

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

}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: %s [DATA_DIR [DATASET_SUBSTRING [--no-baselines]]]\n"
                      "       %s --files DATASET... [--split 5|6] [--no-baselines]\n"
                      "  DATASET: a mesh file, TetGen x.ele, or PLOT3D files joined by '+' (grid.xyz+grid.q)\n";
  if (argc > 1 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0)) {
    std::printf(usage, argv[0], argv[0]);
    return 0;
  }
  std::vector<Dataset> sets;
  std::string filter;
  bool skip_baselines = false;
  if (argc > 1 && std::strcmp(argv[1], "--files") == 0) {
    int split = 6;
    std::vector<std::string> args;
    for (int i = 2; i < argc; ++i) {
      if (std::strcmp(argv[i], "--no-baselines") == 0) {
        skip_baselines = true;
      } else if (std::strcmp(argv[i], "--split") == 0 && i + 1 < argc &&
                 (std::strcmp(argv[i + 1], "5") == 0 || std::strcmp(argv[i + 1], "6") == 0)) {
        split = std::atoi(argv[++i]);
      } else if (argv[i][0] == '-') {
        std::fprintf(stderr, "bench-compression: unknown or incomplete option '%s'\n", argv[i]);
        std::fprintf(stderr, usage, argv[0], argv[0]);
        return 2;
      } else {
        args.push_back(argv[i]);
      }
    }
    if (args.empty()) {
      std::fprintf(stderr, "bench-compression: --files needs at least one dataset\n");
      std::fprintf(stderr, usage, argv[0], argv[0]);
      return 2;
    }
    for (const std::string& arg : args) sets.push_back(namedDataset(arg, split));
  } else {
    sets = gtn::bench::sharedDatasets(gtn::bench::dataDir(argc > 1 ? argv[1] : nullptr, GTN_DEFAULT_DATA_DIR));
    if (argc > 2) filter = argv[2];
    skip_baselines = argc > 3 && std::string(argv[3]) == "--no-baselines";
  }
  int w = 16;  // width of the dataset column
  for (const Dataset& d : sets) w = std::max(w, static_cast<int>(d.name.size()));
  std::printf("bits per tetrahedron; conn = boundary + peeling. Raw-array baselines: zstd -19, xz -9%s\n",
#ifdef GTN_HAVE_FPZIP
              ", fpzip (float arrays)"
#else
              " (built without fpzip)"
#endif
  );
  std::printf("%-*s %8s %8s | %6s %6s %6s %7s | %7s %7s | %7s %7s %7s | %6s %6s %7s %6s | %s\n", w, "dataset",
              "points", "tets", "conn", "geom", "fields", "total", "zstd.c", "xz.c", "zstd.gf", "xz.gf", "fpzip", "enc",
              "dec", "peak", "peak", "targets");
  std::printf("%-*s %8s %8s | %6s %6s %6s %7s | %7s %7s | %7s %7s %7s | %6s %6s %7s %6s | %s\n", w, "", "", "", "b/t",
              "b/t", "b/t", "b/t", "b/t", "b/t", "b/t", "b/t", "b/t", "Mt/s", "Mt/s", "live", "MiB",
              "conn, gf<xz, each<=xz");
  std::vector<std::string> failed, missed;  // datasets that failed to run; datasets that miss a target
  bool stream_missed = false;  // a value stream larger than xz -9 of its raw array
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
    const double xc = 8.0 * externalSize(raw_conn, "xz -9 -c") / nt;
    const double zgf = 8.0 * externalSize(raw_gf, "zstd -q -19 -c") / nt;
    const double xgf = 8.0 * externalSize(raw_gf, "xz -9 -c") / nt;
    double fp = -1;
#ifdef GTN_HAVE_FPZIP
    if (!skip_baselines) {
      int dims[3] = {0, 0, 0};
      if (m.findMetadata("source.format") && *m.findMetadata("source.format") == "plot3d") plot3dDims(d.inputs[0], dims);
      size_t bytes = externalSize(raw_nonfloat, "xz -9 -c");
      const size_t n = m.numPoints();
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
      fp = 8.0 * bytes / nt;
    }
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
        "%-*s %8zu %8zu | %6.3f %6.2f %6.2f %7.2f | %7.2f %7.2f | %7.2f %7.2f %7.2f | %6.2f %6.2f %7llu %6.2f | %s %s %s\n",
        w, d.name.c_str(), m.numPoints(), m.numTets(), conn, geom, fields, conn + geom + fields, zc, xc, zgf, xgf, fp,
        nt / enc_s / 1e6, nt / dec_s / 1e6, static_cast<unsigned long long>(stats.peak_live_vertices),
        heap_peak / 1048576.0,
        conn_ok ? "ok" : "MISS", !judge_gf ? "-" : gf_ok ? "ok" : "MISS",
        streams.empty() ? "-" : stream_misses.empty() ? "ok" : "MISS");
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
  }
  std::printf("\ntargets: conn <= %.1f b/t%s; %zu missed%s\n", kMaxConnectivityBits,
              skip_baselines ? " (geom + fields and each value stream against xz -9 not judged: --no-baselines)"
                             : ", geom + fields < xz -9 of the raw coordinate + field arrays, each value stream <= xz -9 "
                               "of its raw array",
              missed.size(), missed.empty() ? "" : ":");
  for (const std::string& m : missed) std::printf("  %s\n", m.c_str());
  if (!failed.empty()) {
    std::printf("%zu failed:\n", failed.size());
    for (const std::string& f : failed) std::printf("  %s\n", f.c_str());
  }
  return !failed.empty() ? 1 : stream_missed ? 3 : 0;
}

// gtn-make-sample OUTDIR [NI NJ NK]: writes the project's own small PLOT3D sample, OUTDIR/sample.xyz and
// OUTDIR/sample.q (big-endian float32, no record markers, single grid without a grid count, whole
// layout: the same layout as the blunt-fin files in ../shared/data/plot3d).
//
// The grid is a 24 x 16 x 12 sector (or NI x NJ x NK points of the same shape: the benchmarks' large
// grid) of a cylindrical shell around a fin-like ridge: i runs outwards
// from the body, j around the axis, k along it, so every cell is right-handed. The Q file holds a
// smooth swirling flow along the axis. Only +, -, *, / are used (no libm), so the files are the same
// bytes on every IEEE-754 platform; the program checks that every cell is non-degenerate and
// right-handed under both hexahedron splits before writing anything.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "format/file_io.h"
#include "mesh/hex_split.h"

namespace {

int kNi = 24, kNj = 16, kNk = 12;  // set once by main
constexpr double kGamma = 1.4;

struct Point {
  double x, y, z;
};

// The fin: a ridge at angle 0 whose height falls off as a rational bump around the axis.
double bump(double t) {
  const double a = t / 0.15;
  return 1.0 / (1.0 + a * a);
}

double radialStretch(double u) { return u * (0.6 + 0.4 * u); }  // clusters cells near the body

// Grid point (i, j, k); also returns its radial parameter u and angle parameter t.
Point gridPoint(int i, int j, int k, double* u_out, double* t_out) {
  const double u = static_cast<double>(i) / (kNi - 1);
  const double t = -0.4 + 0.8 * static_cast<double>(j) / (kNj - 1);  // tan(theta / 2)
  const double s = static_cast<double>(k) / (kNk - 1);
  const double cos_theta = (1.0 - t * t) / (1.0 + t * t), sin_theta = 2.0 * t / (1.0 + t * t);
  const double r_in = 0.5 + 0.25 * bump(t) * (1.0 - 0.6 * s);
  const double r_out = 2.0 + 0.1 * s;
  const double r = r_in + (r_out - r_in) * radialStretch(u);
  if (u_out) *u_out = u;
  if (t_out) *t_out = t;
  return {r * cos_theta, r * sin_theta, 2.0 * s + 0.08 * u * t};
}

void putBig32(std::string& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xFF));
}

void putFloat(std::string& out, double v) {
  const float f = static_cast<float>(v);
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  putBig32(out, bits);
}

double orient(const Point& a, const Point& b, const Point& c, const Point& d) {
  const double bx = b.x - a.x, by = b.y - a.y, bz = b.z - a.z;
  const double cx = c.x - a.x, cy = c.y - a.y, cz = c.z - a.z;
  const double dx = d.x - a.x, dy = d.y - a.y, dz = d.z - a.z;
  return bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 5) {
    std::fprintf(stderr, "usage: gtn-make-sample OUTDIR [NI NJ NK]\n");
    return 2;
  }
  if (argv[1][0] == '-') {  // an option, not a directory to create
    const bool help = std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0;
    std::fprintf(help ? stdout : stderr, "usage: gtn-make-sample OUTDIR [NI NJ NK]\n");
    return help ? 0 : 2;
  }
  if (argc == 5) {
    int* dims[3] = {&kNi, &kNj, &kNk};
    for (int a = 0; a < 3; ++a) {
      char* end = nullptr;
      const long d = std::strtol(argv[2 + a], &end, 10);
      if (*argv[2 + a] == '\0' || *end != '\0' || d < 2 || d > 1024) {
        std::fprintf(stderr, "gtn-make-sample: error: dimension '%s': expected an integer from 2 to 1024\n",
                     argv[2 + a]);
        return 2;
      }
      *dims[a] = static_cast<int>(d);
    }
    if (static_cast<double>(kNi) * kNj * kNk > 5e7) {
      std::fprintf(stderr, "gtn-make-sample: error: %d x %d x %d points: at most 5e7\n", kNi, kNj, kNk);
      return 2;
    }
  }
  const std::string dir = argv[1];
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    std::fprintf(stderr, "gtn-make-sample: error: %s: cannot create directory: %s\n", dir.c_str(),
                 ec.message().c_str());
    return 3;
  }

  const size_t n = static_cast<size_t>(kNi) * kNj * kNk;
  std::vector<Point> pts(n);
  std::vector<double> us(n), ts(n);
  auto index = [](int i, int j, int k) { return static_cast<size_t>(i + kNi * (j + kNj * k)); };
  for (int k = 0; k < kNk; ++k)
    for (int j = 0; j < kNj; ++j)
      for (int i = 0; i < kNi; ++i) pts[index(i, j, k)] = gridPoint(i, j, k, &us[index(i, j, k)], &ts[index(i, j, k)]);

  // Points are written as float32: check the cells with the rounded coordinates. A cell is right-handed
  // and non-degenerate when every tetrahedron of every split has the sign it has in the unit cube
  // (the split tables are not all positively oriented).
  std::vector<Point> rounded(pts);
  for (Point& p : rounded) p = {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
  const Point cube[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  auto splitAll = [](const uint32_t h[8]) {
    std::vector<gtn::Tet> tets;
    gtn::splitHexSix(h, tets);
    gtn::splitHexFive(h, false, tets);
    gtn::splitHexFive(h, true, tets);
    return tets;
  };
  const uint32_t local[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  const std::vector<gtn::Tet> reference = splitAll(local);
  for (int k = 0; k + 1 < kNk; ++k) {
    for (int j = 0; j + 1 < kNj; ++j) {
      for (int i = 0; i + 1 < kNi; ++i) {
        const uint32_t h[8] = {static_cast<uint32_t>(index(i, j, k)),
                               static_cast<uint32_t>(index(i + 1, j, k)),
                               static_cast<uint32_t>(index(i + 1, j + 1, k)),
                               static_cast<uint32_t>(index(i, j + 1, k)),
                               static_cast<uint32_t>(index(i, j, k + 1)),
                               static_cast<uint32_t>(index(i + 1, j, k + 1)),
                               static_cast<uint32_t>(index(i + 1, j + 1, k + 1)),
                               static_cast<uint32_t>(index(i, j + 1, k + 1))};
        const std::vector<gtn::Tet> tets = splitAll(h);
        for (size_t t = 0; t < tets.size(); ++t) {
          const gtn::Tet& a = tets[t];
          const gtn::Tet& r = reference[t];
          const double v = orient(rounded[a[0]], rounded[a[1]], rounded[a[2]], rounded[a[3]]);
          const double want = orient(cube[r[0]], cube[r[1]], cube[r[2]], cube[r[3]]);
          if (!(v * want > 0)) {
            std::fprintf(stderr, "gtn-make-sample: error: cell (%d, %d, %d) is degenerate or left-handed\n", i, j, k);
            return 1;
          }
        }
      }
    }
  }

  std::string xyz;
  for (int d : {kNi, kNj, kNk}) putBig32(xyz, static_cast<uint32_t>(d));
  for (size_t p = 0; p < n; ++p) putFloat(xyz, pts[p].x);
  for (size_t p = 0; p < n; ++p) putFloat(xyz, pts[p].y);
  for (size_t p = 0; p < n; ++p) putFloat(xyz, pts[p].z);

  // Flow: axial velocity slowed near the fin, a swirl around the axis, density and temperature
  // raised near the body; stagnation energy E = p / (gamma - 1) + rho |v|^2 / 2 with p = rho T / gamma.
  std::vector<double> rho(n), mx(n), my(n), mz(n), energy(n);
  for (size_t p = 0; p < n; ++p) {
    const double u = us[p], b = bump(ts[p]), w = (1.0 - u) * (1.0 - u);
    const double r2 = pts[p].x * pts[p].x + pts[p].y * pts[p].y;
    const double density = 1.0 + 0.3 * w * (1.0 + b);
    const double temperature = 1.0 + 0.2 * w;
    const double swirl = 0.25 / (1.0 + r2);
    const double vx = -swirl * pts[p].y, vy = swirl * pts[p].x, vz = 0.5 * (1.0 - 0.4 * w * b);
    const double pressure = density * temperature / kGamma;
    rho[p] = density;
    mx[p] = density * vx;
    my[p] = density * vy;
    mz[p] = density * vz;
    energy[p] = pressure / (kGamma - 1.0) + 0.5 * density * (vx * vx + vy * vy + vz * vz);
  }
  std::string q;
  for (int d : {kNi, kNj, kNk}) putBig32(q, static_cast<uint32_t>(d));
  for (double v : {0.5, 0.0, 1.0e5, 0.0}) putFloat(q, v);  // fsmach, alpha, Reynolds number, time
  for (const std::vector<double>* a : {&rho, &mx, &my, &mz, &energy})
    for (double v : *a) putFloat(q, v);

  for (const auto& [name, bytes] : {std::pair<std::string, const std::string*>{"sample.xyz", &xyz},
                                    std::pair<std::string, const std::string*>{"sample.q", &q}}) {
    const gtn::Status st = gtn::writeBytesAtomically(dir + "/" + name, bytes->data(), bytes->size());
    if (!st.isOk()) {
      std::fprintf(stderr, "gtn-make-sample: error: %s\n", st.message().c_str());
      return 3;
    }
  }
  return 0;
}

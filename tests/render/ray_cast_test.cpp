// The ray-casting core's two ways of holding a tetrahedron (a TetGeom copy, TetCorners over shared
// records) and its two ways of handing out the boundary's segments (an array, a SegmentSink) must
// give the same bits: the streaming renderer uses one of each, the generic renderer the other.
#include "render/ray_cast.h"

#include <gtest/gtest.h>

#include <limits>

#include <cstring>
#include <random>

#include "mesh/faces.h"

namespace gtn {
namespace {

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// A closed surface, an octahedron, with a scalar that varies over it.
BoundarySurface octahedron() {
  BoundarySurface s;
  s.points = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& p : s.points) s.scalars.push_back(p[0] + 2 * p[1] + 3 * p[2]);
  // Outward oriented.
  s.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return s;
}

class Collect : public SegmentSink {
 public:
  void begin(size_t segments) override {
    announced = segments;
    got.reserve(segments);
  }
  void segment(const RaySegment& s) override { got.push_back(s); }
  size_t announced = 0;
  std::vector<RaySegment> got;
};

// A camera framing the cube [-1, 1]^3 with a w x h image.
Camera cubeCamera(Projection projection, int w, int h) {
  const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  CameraOptions o;
  o.width = w;
  o.height = h;
  o.projection = projection;
  return Camera(lo, hi, o);
}

// A camera whose angle is not a number (the CLI refuses one; a library caller might not) gives rays
// of NaN depth: casting ends, with segments or none, instead of looping on crossings that compare
// with nothing.
TEST(CastBoundary, NonFiniteCameraEnds) {
  const BoundarySurface surface = octahedron();
  for (Projection projection : {Projection::kOrthographic, Projection::kPerspective}) {
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    CameraOptions o;
    o.width = 8;
    o.height = 8;
    o.projection = projection;
    o.azimuth = std::numeric_limits<double>::quiet_NaN();
    const RaySegments cast = castBoundary(Camera(lo, hi, o), surface);
    EXPECT_EQ(cast.pixel_start.size(), 65u);
  }
}

TEST(CastBoundary, SinkReceivesTheArraysSegmentsInOrder) {
  const BoundarySurface surface = octahedron();
  for (Projection projection : {Projection::kOrthographic, Projection::kPerspective}) {
    const Camera camera = cubeCamera(projection, 64, 48);
    const RaySegments array = castBoundary(camera, surface);
    ASSERT_GT(array.segments.size(), 250u);
    std::vector<uint32_t> pixel_start;
    Collect sink;
    castBoundary(camera, surface, &pixel_start, sink);
    EXPECT_EQ(pixel_start, array.pixel_start);
    EXPECT_EQ(sink.announced, array.segments.size());
    ASSERT_EQ(sink.got.size(), array.segments.size());
    for (size_t i = 0; i < sink.got.size(); ++i) {
      const RaySegment &a = array.segments[i], &b = sink.got[i];
      EXPECT_EQ(a.pixel, b.pixel);
      EXPECT_EQ(a.entry_tri, b.entry_tri);
      EXPECT_EQ(a.exit_tri, b.exit_tri);
      EXPECT_TRUE(sameBits(a.t_near, b.t_near) && sameBits(a.s_near, b.s_near) && sameBits(a.t_far, b.t_far) &&
                  sameBits(a.s_far, b.s_far))
          << "segment " << i;
    }
  }
}

TEST(TetCorners, CrossLikeTetGeomBitForBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (Projection projection : {Projection::kOrthographic, Projection::kPerspective}) {
    const Camera camera = cubeCamera(projection, 24, 24);
    const bool sheared = projection == Projection::kOrthographic;
    const ShearFrame frame = prepareRay(camera.ray(0, 0)).frame;
    int crossings = 0;
    for (int n = 0; n < 200; ++n) {
      CornerRecord records[4];
      TetGeom g;
      for (int i = 0; i < 4; ++i) {
        for (int c = 0; c < 3; ++c) records[i].p[c] = g.p[i][c] = 0.8 * u(rng);
        records[i].s = g.s[i] = u(rng);
        shearPoint(frame, records[i].p, records[i].q);
      }
      finishTetGeom(g);
      if (sheared) shearTetGeom(g, frame);
      const double* positions[4] = {records[0].p, records[1].p, records[2].p, records[3].p};
      uint8_t order[4][3];
      faceOrders(positions, order);
      ASSERT_EQ(std::memcmp(order, g.order, sizeof(order)), 0);
      const CornerRecord* corners[4] = {&records[0], &records[1], &records[2], &records[3]};
      const TetCorners tc{corners, order, sheared};
      for (int py = 0; py < camera.height(); py += 3) {
        for (int px = 0; px < camera.width(); px += 3) {
          const PreparedRay ray = prepareRay(camera.ray(px, py));
          Crossing a[4], b[4];
          crossTetFaces(ray, g, -1, a);
          crossTetFaces(ray, tc, -1, b);
          for (int k = 0; k < 4; ++k) {
            ASSERT_EQ(a[k].hit, b[k].hit);
            ASSERT_TRUE(sameBits(a[k].t, b[k].t) && sameBits(a[k].s, b[k].s));
            crossings += a[k].hit;
          }
          for (int entry = 0; entry < 4; ++entry) {
            for (bool forward : {true, false}) {
              Crossing x, y;
              const int exit = exitFace(ray, g, entry, forward, &x);
              ASSERT_EQ(exit, exitFace(ray, tc, entry, forward, &y));
              ASSERT_TRUE(x.hit == y.hit && sameBits(x.t, y.t) && sameBits(x.s, y.s));
              // The farthest face crossed other than the entry, exactly as crossTetFaces crosses it.
              int want = -1;
              for (int k = 0; k < 4; ++k)
                if (k != entry && a[k].hit && (want < 0 || (forward ? a[k].t > a[want].t : a[k].t < a[want].t)))
                  want = k;
              ASSERT_EQ(exit, want);
              if (want >= 0) {
                ASSERT_TRUE(x.hit && sameBits(x.t, a[want].t) && sameBits(x.s, a[want].s));
              }
            }
          }
        }
      }
    }
    EXPECT_GT(crossings, 500);
  }
}

}  // namespace
}  // namespace gtn

// Region reads (mesh/box_filter.h): which tetrahedra meet a box, and the compacted mesh they make.
#include <gtest/gtest.h>

#include "mesh/box_filter.h"

namespace gtn {
namespace {

bool meets(const std::array<std::array<double, 3>, 4>& t, std::array<double, 6> box) {
  const double* p[4] = {t[0].data(), t[1].data(), t[2].data(), t[3].data()};
  return tetMeetsBox(p, box.data(), box.data() + 3);
}

TEST(BoxFilter, SeparatingAxes) {
  const std::array<double, 6> box{0, 0, 0, 0.2, 0.2, 0.2};
  // Its bounding box [0,1]^3 holds the box, but the plane x + y + z = 1 separates them.
  EXPECT_FALSE(meets({{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}}}, box));
  // Holds the box without a corner in it.
  EXPECT_TRUE(meets({{{-1, -1, -1}, {2, -1, -1}, {-1, 2, -1}, {-1, -1, 2}}}, box));
  // One corner inside; one touching a face; one beside it.
  EXPECT_TRUE(meets({{{0.1, 0.1, 0.1}, {5, 0, 0}, {0, 5, 0}, {0, 0, 5}}}, box));
  EXPECT_TRUE(meets({{{0.2, 0.1, 0.1}, {1, 0, 0}, {1, 1, 0}, {1, 0, 1}}}, box));
  EXPECT_FALSE(meets({{{0.3, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 0, 1}}}, box));
  // An edge passes through the box while every corner stays outside.
  EXPECT_TRUE(meets({{{-1, 0.1, 0.1}, {1, 0.1, 0.1}, {0, 3, 3}, {0, 3, -3}}}, box));
  // Beside the box's edge (x = 0.2, y = 0.2), its bounding box overlapping the box: the plane
  // x + y = 0.45 of a face separates them.
  EXPECT_FALSE(meets({{{0.45, 0, 0}, {0, 0.45, 0}, {0.45, 0, 0.2}, {0.6, 0.6, 0.1}}}, box));
}

TEST(BoxFilter, CropKeepsTetrahedraPointsAndValues) {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  m.coords = {5, 5, 5, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 9, 9, 9, 10, 9, 9, 9, 10, 9, 9, 9, 10};
  m.tets = {{1, 2, 3, 4}, {5, 6, 7, 8}};
  Field pf("p", 1, ScalarType::kInt32, 9);
  for (int i = 0; i < 9; ++i) pf.set<int32_t>(i, 0, 100 + i);
  Field cf("c", 2, ScalarType::kFloat64, 2);
  cf.set<double>(0, 0, 1.5);
  cf.set<double>(0, 1, 2.5);
  cf.set<double>(1, 0, 3.5);
  cf.set<double>(1, 1, 4.5);
  m.point_fields.push_back(pf);
  m.cell_fields.push_back(cf);
  m.setMetadata("k", "v");
  const double lo[3] = {8.5, 8.5, 8.5}, hi[3] = {9.5, 9.5, 9.5};
  const TetMesh out = cropToBox(m, lo, hi);
  ASSERT_EQ(out.numTets(), 1u);
  ASSERT_EQ(out.numPoints(), 4u);
  EXPECT_EQ(out.coord_type, ScalarType::kFloat32);
  EXPECT_EQ(out.tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(out.coords[3], 10);
  EXPECT_EQ(out.point_fields[0].data<int32_t>()[0], 105);
  EXPECT_EQ(out.point_fields[0].data<int32_t>()[3], 108);
  EXPECT_EQ(out.cell_fields[0].data<double>()[0], 3.5);
  EXPECT_EQ(out.cell_fields[0].data<double>()[1], 4.5);
  ASSERT_NE(out.findMetadata("k"), nullptr);
  EXPECT_TRUE(out.checkConsistency("cropped").isOk());
  const double far_lo[3] = {20, 20, 20}, far_hi[3] = {21, 21, 21};
  const TetMesh none = cropToBox(m, far_lo, far_hi);
  EXPECT_EQ(none.numTets(), 0u);
  EXPECT_EQ(none.numPoints(), 0u);
  EXPECT_EQ(none.point_fields.size(), 1u);
}

}  // namespace
}  // namespace gtn

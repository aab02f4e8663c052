// The writer's check that an encoded level gives its mesh back (codec/level_check.h): silent on a
// faithful encoding, and naming the first difference when the level and the mesh disagree.
#include "codec/level_check.h"

#include <gtest/gtest.h>

#include <utility>

#include "codec_test_util.h"

namespace gtn {
namespace {

using test::gridMesh;

struct Encoded {
  TetMesh mesh;
  EncodedLevel level;
};

Encoded encodedGrid() {
  Encoded e;
  e.mesh = gridMesh(4, 3, 3, 5);
  Field f("temperature", 1, ScalarType::kFloat32, e.mesh.numPoints());
  for (size_t v = 0; v < e.mesh.numPoints(); ++v) f.data<float>()[v] = 0.25f * static_cast<float>(v);
  e.mesh.point_fields.push_back(f);
  auto level = encodeLevel(e.mesh, EncodeOptions{});
  EXPECT_TRUE(level.isOk());
  if (level.isOk()) e.level = std::move(level).value();
  return e;
}

TEST(LosslessMismatch, FaithfulEncodingPasses) {
  const Encoded e = encodedGrid();
  EXPECT_EQ(losslessMismatch(e.mesh, e.level), "");
}

TEST(LosslessMismatch, NamesTheFirstDifference) {
  const Encoded e = encodedGrid();
  TetMesh moved = e.mesh;
  moved.coords[3 * 7 + 1] = std::nextafter(moved.coords[3 * 7 + 1], 1e9);
  EXPECT_EQ(losslessMismatch(moved, e.level).rfind("source point 7 ", 0), 0u) << losslessMismatch(moved, e.level);

  TetMesh valued = e.mesh;
  valued.point_fields[0].data<float>()[11] = -1.0f;
  EXPECT_NE(losslessMismatch(valued, e.level).find("source point 11 "), std::string::npos);
  EXPECT_NE(losslessMismatch(valued, e.level).find("other field values"), std::string::npos);

  TetMesh reversed = e.mesh;
  std::swap(reversed.tets[5][0], reversed.tets[5][1]);
  EXPECT_EQ(losslessMismatch(reversed, e.level),
            "source tetrahedron 5 (decoded " + std::to_string(e.level.tet_order[5]) + ") is reversed");

  TetMesh renamed = e.mesh;
  renamed.point_fields[0].name = "pressure";
  EXPECT_EQ(losslessMismatch(renamed, e.level), "field names, types or components changed");

  TetMesh fewer = e.mesh;
  fewer.tets.pop_back();
  EXPECT_EQ(losslessMismatch(fewer, e.level), "the encoder's renumbering does not cover the source");
}

TEST(LosslessMismatch, BrokenStreamsAndOrders) {
  Encoded e = encodedGrid();
  EncodedLevel bad_order = e.level;
  std::swap(bad_order.vertex_order[0], bad_order.vertex_order[1]);
  const std::string swapped = losslessMismatch(e.mesh, bad_order);
  EXPECT_TRUE(swapped.find("source point") != std::string::npos ||
              swapped.find("source tetrahedron") != std::string::npos)
      << swapped;
  bad_order.vertex_order[1] = bad_order.vertex_order[0];
  EXPECT_EQ(losslessMismatch(e.mesh, bad_order), "the encoder's vertex order is not a permutation");

  // A range-coded stream must start with a zero byte (spec section 10.1).
  EncodedLevel broken = e.level;
  broken.connectivity[0] = 1;
  EXPECT_EQ(losslessMismatch(e.mesh, broken).rfind("it does not decode: ", 0), 0u) << losslessMismatch(e.mesh, broken);
  // Damage the decoder cannot see is still caught by the comparison.
  EncodedLevel cut = e.level;
  cut.geometry.resize(cut.geometry.size() / 2);
  EXPECT_NE(losslessMismatch(e.mesh, cut), "");
}

}  // namespace
}  // namespace gtn

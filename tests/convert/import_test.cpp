// The import dispatcher: what it tells the user before any one importer reads the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

#include "convert/import.h"
#include "test_util.h"

namespace gtn {
namespace {

// Every file of meshio's test corpus, cloned without Git LFS, is such a pointer; each importer used to
// call it a malformed file of its own format ("not well-formed XML", "its first word is 1936876918").
TEST(ImportDispatch, GitLfsPointerIsNamedAsSuch) {
  const std::string dir = test::tempDir("import-lfs-pointer");
  const std::string pointer =
      "version https://git-lfs.github.com/spec/v1\n"
      "oid sha256:3ecbf7b48edc448fcbe2d28aba387c5d77ec535c6ebbd2977325101afd7834e8\nsize 3331\n";
  for (const char* name : {"a.vtu", "a.vtk", "a.mesh", "a.meshb", "a.off", "a.1.ele", "a.xyz"}) {
    const std::string path = dir + "/" + name;
    test::writeFile(path, pointer);
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_FALSE(r.isOk()) << name;
    EXPECT_EQ(r.status().code(), StatusCode::kNotOurFile) << name;
    EXPECT_EQ(r.status().message().rfind(path + ": a Git LFS pointer", 0), 0u) << r.status().message();
  }
  // The second file of a PLOT3D pair too.
  test::writeFile(dir + "/g.xyz", "2 2 2\n0 1 0 1 0 1 0 1\n0 0 1 1 0 0 1 1\n0 0 0 0 1 1 1 1\n");
  auto r = importMesh({dir + "/g.xyz", dir + "/a.xyz"}, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find(dir + "/a.xyz: a Git LFS pointer"), std::string::npos) << r.status().message();
}

// A pipe (the shell's <(gunzip -c x.vtk.gz)) is named as such: its first bytes, read to tell its format,
// would be gone for its importer ("larger than the limit of 1 bytes" said nothing of that).
TEST(ImportDispatch, PipeIsNamedAsSuch) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const std::string text =
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n"
      "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n";
  ASSERT_EQ(::write(fds[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ::close(fds[1]);
  const std::string path = "/dev/fd/" + std::to_string(fds[0]);
  auto r = importMesh({path}, ImportOptions{});
  ::close(fds[0]);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kIo);
  EXPECT_EQ(r.status().message(), path +
                                      ": is a pipe, not a file: an input is read more than once (its first bytes "
                                      "tell its format); save it to a file first");
}

// Several inputs where the format takes one: the error names the extra input; of an unknown format,
// the first file's own error says why ("a unknown mesh is one file; got 2 inputs" named neither).
TEST(ImportDispatch, OneFileFormatsNameTheExtraInput) {
  const std::string dir = test::tempDir("import-extra");
  test::writeFile(dir + "/foo", "hi\n");
  test::writeFile(dir + "/bar", "hi\n");
  auto r = importMesh({dir + "/foo", dir + "/bar"}, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().message().rfind(dir + "/foo: cannot tell its format", 0), 0u) << r.status().message();
  r = importMesh({test::dataPath("vtk/spx.vtk"), dir + "/bar"}, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUsage);
  EXPECT_EQ(r.status().message().rfind(dir + "/bar: ", 0), 0u) << r.status().message();
  EXPECT_NE(r.status().message().find("spx.vtk is a legacy VTK mesh, which is one file"), std::string::npos)
      << r.status().message();
}

// The format of a file that does not exist (nothing to read) comes from its extension alone.
TEST(ImportDispatch, FormatFromTheExtension) {
  const std::string dir = test::tempDir("import_ext");
  const std::pair<const char*, InputFormat> cases[] = {
      {"a.vtu", InputFormat::kVtu},     {"a.vts", InputFormat::kVtu},     {"a.vtr", InputFormat::kVtu},
      {"a.vti", InputFormat::kVtu},     {"a.pvtu", InputFormat::kVtu},    {"a.pvts", InputFormat::kVtu},
      {"a.pvtr", InputFormat::kVtu},    {"a.pvti", InputFormat::kVtu},    {"a.VTK", InputFormat::kVtkLegacy},
      {"a.mesh", InputFormat::kMedit},  {"a.meshb", InputFormat::kMeshb}, {"a.off", InputFormat::kOff},
      {"a.node", InputFormat::kTetgen}, {"a.ele", InputFormat::kTetgen},  {"a.xyz", InputFormat::kPlot3d},
      {"a.q", InputFormat::kPlot3d},    {"a.gtn", InputFormat::kGtn},     {"a.stl", InputFormat::kUnknown}};
  for (const auto& [name, format] : cases)
    EXPECT_EQ(detectInputFormat(dir + "/" + name), format)
        << name << ": " << inputFormatName(detectInputFormat(dir + "/" + name));
}

// A tetrahedron that lists a point twice is no tetrahedron: dropped with its cell value and a warning
// (the encoder refused the whole file: "tetrahedron 1 repeats a vertex").
TEST(ImportDispatch, TetrahedraListingAPointTwiceAreDropped) {
  const std::string dir = test::tempDir("import-repeated");
  const std::string path = dir + "/r.vtk";
  test::writeFile(path,
                  "# vtk DataFile Version 3.0\nr\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n"
                  "0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\nCELLS 3 15\n4 0 1 2 3\n4 1 1 2 4\n4 1 3 2 4\n"
                  "CELL_TYPES 3\n10 10 10\nCELL_DATA 3\nSCALARS id int 1\nLOOKUP_TABLE default\n7 8 9\n");
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(r->mesh.numTets(), 2u);
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r->mesh.cell_fields[0].data<int32_t>()[0], 7);
  EXPECT_EQ(r->mesh.cell_fields[0].data<int32_t>()[1], 9);
  EXPECT_EQ(r->report.dropped_cells, 1u);
  EXPECT_EQ(r->report.zero_volume, 0u);
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_EQ(r->report.warnings[0], "1 tetrahedra that list a point twice (flat, no tetrahedra) dropped");
  EXPECT_EQ(test::runGtn("convert " + path + " -o " + dir + "/r.gtn").exit_code, 0);
}

}  // namespace
}  // namespace gtn

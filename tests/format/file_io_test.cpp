// Reading inputs and atomic outputs: a failed write leaves nothing behind and never touches the target.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <limits>

#include "convert/text_reader.h"
#include "format/file_io.h"
#include "test_util.h"

namespace gtn {
namespace {

TEST(FileIo, ReadErrorsNameTheFile) {
  const std::string dir = test::tempDir("fileio-read");
  auto r = readWholeFile(dir);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kIo);
  EXPECT_NE(r.status().message().find("directory"), std::string::npos);
  r = readWholeFile(dir + "/missing.node");
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find("missing.node"), std::string::npos);
  test::writeFile(dir + "/big", std::string(100, 'x'));
  EXPECT_FALSE(readWholeFile(dir + "/big", 10).isOk());
  ASSERT_TRUE(readWholeFile(dir + "/big").isOk());
  EXPECT_EQ(readWholeFile(dir + "/big").value().size(), 100u);
  r = readWholeFile("/dev/zero");  // endless: refused, not read until memory runs out
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find("/dev/zero: is a device"), std::string::npos) << r.status().message();
}

TEST(FileIo, FailedWriteKeepsTheOldFileAndLeavesNoTemporary) {
  const std::string dir = test::tempDir("fileio-atomic");
  const std::string target = dir + "/out.vtu";
  test::writeFile(target, "precious");
  Status st = writeFileAtomically(target, [](std::FILE* f) {
    std::fputs("half-written", f);
    return invalidData("the exporter failed midway");
  });
  EXPECT_FALSE(st.isOk());
  EXPECT_EQ(test::readFile(target), "precious");
  size_t entries = 0;
  for ([[maybe_unused]] auto& e : std::filesystem::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u);
  ASSERT_TRUE(writeBytesAtomically(target, "new", 3).isOk());
  EXPECT_EQ(test::readFile(target), "new");
}

// A long job asks before its work whether its output can be written: the temporary it would write
// is created and removed, and what writeFileAtomically refuses is refused the same way.
TEST(FileIo, OutputWritableIsAskedBeforeTheWork) {
  const std::string dir = test::tempDir("fileio-writable");
  EXPECT_TRUE(checkOutputWritable(dir + "/new.gtn").isOk());
  test::writeFile(dir + "/old.gtn", "kept");
  EXPECT_TRUE(checkOutputWritable(dir + "/old.gtn").isOk());
  EXPECT_EQ(test::readFile(dir + "/old.gtn"), "kept");
  size_t entries = 0;
  for ([[maybe_unused]] auto& e : std::filesystem::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u);  // no temporary left behind, nothing made for new.gtn
  EXPECT_TRUE(checkOutputWritable("-").isOk());
  const Status missing = checkOutputWritable(dir + "/no-such-dir/out.gtn");
  ASSERT_FALSE(missing.isOk());
  EXPECT_EQ(missing.code(), StatusCode::kIo);
  EXPECT_NE(missing.message().find(dir + "/no-such-dir/out.gtn: cannot create a temporary file beside it"),
            std::string::npos)
      << missing.message();
  const Status to_dir = checkOutputWritable(dir);
  ASSERT_FALSE(to_dir.isOk());
  EXPECT_NE(to_dir.message().find(dir + ": is a directory"), std::string::npos) << to_dir.message();

  // gtn convert asks first: an output it cannot write is reported before the input is even read.
  const test::RunResult r = test::runGtn("convert " + dir + "/missing-input.vtk -o " + dir + "/no-such-dir/out.gtn");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("no-such-dir/out.gtn: cannot create a temporary file beside it"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("missing-input.vtk"), std::string::npos) << r.err;
}

// A new file gets 0666 less the umask, as the shell's '>' gives it; a replaced file keeps its mode; a
// file the user may not write is not replaced (root may write any).
TEST(FileIo, OutputsKeepModesAndTheUmask) {
  const std::string dir = test::tempDir("fileio-modes");
  auto mode = [](const std::string& path) {
    struct stat sb;
    EXPECT_EQ(::stat(path.c_str(), &sb), 0) << path;
    return sb.st_mode & 0777;
  };
  const mode_t old_mask = ::umask(027);
  ASSERT_TRUE(writeBytesAtomically(dir + "/new.txt", "a", 1).isOk());
  EXPECT_EQ(mode(dir + "/new.txt"), 0640u);
  ::umask(0);
  ASSERT_TRUE(writeBytesAtomically(dir + "/open.txt", "a", 1).isOk());
  EXPECT_EQ(mode(dir + "/open.txt"), 0666u);
  ::umask(old_mask);
  ASSERT_EQ(::chmod((dir + "/new.txt").c_str(), 0600), 0);
  ASSERT_TRUE(writeBytesAtomically(dir + "/new.txt", "bb", 2).isOk());
  EXPECT_EQ(test::readFile(dir + "/new.txt"), "bb");
  EXPECT_EQ(mode(dir + "/new.txt"), 0600u);
  AtomicFileGroup g;
  ASSERT_TRUE(g.add(dir + "/open.txt", [](std::FILE* f) {
                 std::fputs("g", f);
                 return Status::ok();
               }).isOk());
  ASSERT_TRUE(g.commit().isOk());
  EXPECT_EQ(mode(dir + "/open.txt"), 0666u);
  ASSERT_EQ(::chmod((dir + "/new.txt").c_str(), 0444), 0);
  const Status st = writeBytesAtomically(dir + "/new.txt", "ccc", 3);
  if (::geteuid() != 0) {
    ASSERT_FALSE(st.isOk());
    EXPECT_NE(st.message().find("new.txt: is read-only (not replaced)"), std::string::npos) << st.message();
    EXPECT_EQ(test::readFile(dir + "/new.txt"), "bb");
    EXPECT_FALSE(AtomicFileGroup().add(dir + "/new.txt", [](std::FILE*) { return Status::ok(); }).isOk());
  } else {
    EXPECT_TRUE(st.isOk()) << st.message();
    EXPECT_EQ(mode(dir + "/new.txt"), 0444u);
  }
  size_t entries = 0;
  for ([[maybe_unused]] auto& e : std::filesystem::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 2u);  // no temporary left behind
}

TEST(FileIo, GroupCommitsAllOrNothing) {
  const std::string dir = test::tempDir("fileio-group");
  {
    AtomicFileGroup g;
    ASSERT_TRUE(g.add(dir + "/a.node", [](std::FILE* f) {
                   std::fputs("a", f);
                   return Status::ok();
                 }).isOk());
    ASSERT_FALSE(g.add(dir + "/a.ele", [](std::FILE*) { return invalidData("no"); }).isOk());
  }
  EXPECT_FALSE(test::fileExists(dir + "/a.node"));
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  AtomicFileGroup g;
  ASSERT_TRUE(g.add(dir + "/b.node", [](std::FILE* f) {
                 std::fputs("b", f);
                 return Status::ok();
               }).isOk());
  ASSERT_TRUE(g.commit().isOk());
  EXPECT_EQ(test::readFile(dir + "/b.node"), "b");
}

// Outputs that are not plain files: a symbolic link is followed (the link stays), a character device
// or FIFO is written in place (renaming over it destroyed it: `-o /dev/null` as root replaced the
// system's /dev/null), a directory is refused.
TEST(FileIo, LinksDevicesAndFifosAreNotReplaced) {
  const std::string dir = test::tempDir("fileio-special");
  test::writeFile(dir + "/real.txt", "old");
  ASSERT_EQ(symlink("real.txt", (dir + "/link.txt").c_str()), 0);
  ASSERT_TRUE(writeBytesAtomically(dir + "/link.txt", "new", 3).isOk());
  struct stat sb;
  ASSERT_EQ(lstat((dir + "/link.txt").c_str(), &sb), 0);
  EXPECT_TRUE(S_ISLNK(sb.st_mode));
  EXPECT_EQ(test::readFile(dir + "/real.txt"), "new");
  ASSERT_EQ(symlink("later.txt", (dir + "/dangling.txt").c_str()), 0);
  ASSERT_TRUE(writeBytesAtomically(dir + "/dangling.txt", "made", 4).isOk());
  EXPECT_EQ(test::readFile(dir + "/later.txt"), "made");
  EXPECT_TRUE(sameFile(dir + "/dangling.txt", dir + "/later.txt"));
  EXPECT_FALSE(sameFile(dir + "/real.txt", dir + "/later.txt"));

  // A FIFO with a reader: the bytes go through it, and it stays a FIFO.
  const std::string fifo = dir + "/pipe";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const int reader = open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  ASSERT_TRUE(writeBytesAtomically(fifo, "through", 7).isOk());
  char got[16] = {};
  EXPECT_EQ(read(reader, got, sizeof got), 7);
  EXPECT_STREQ(got, "through");
  close(reader);
  ASSERT_EQ(stat(fifo.c_str(), &sb), 0);
  EXPECT_TRUE(S_ISFIFO(sb.st_mode));
  EXPECT_FALSE(AtomicFileGroup().add(fifo, [](std::FILE*) { return Status::ok(); }).isOk());

  // A private null device (root only): written in place, still a device.
  const std::string null_dev = dir + "/null";
  if (mknod(null_dev.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0) {
    ASSERT_TRUE(writeBytesAtomically(null_dev, "gone", 4).isOk());
    ASSERT_EQ(stat(null_dev.c_str(), &sb), 0);
    EXPECT_TRUE(S_ISCHR(sb.st_mode));
  }
  const Status to_dir = writeBytesAtomically(dir, "x", 1);
  ASSERT_FALSE(to_dir.isOk());
  EXPECT_NE(to_dir.message().find(dir + ": is a directory"), std::string::npos) << to_dir.message();
}

TEST(TextReader, TokensNumbersCommentsAndLines) {
  TextReader r("x.node", "# header\n3  3\t0 1 # trailing\n\n0 1.5e-3 -2 +7\n");
  auto n = r.readInt("node count");
  ASSERT_TRUE(n.isOk());
  EXPECT_EQ(n.value(), 3);
  EXPECT_EQ(r.line(), 2u);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(r.readInt("field").isOk());
  ASSERT_TRUE(r.readInt("index").isOk());
  auto d = r.readDouble("x");
  ASSERT_TRUE(d.isOk());
  EXPECT_EQ(d.value(), 1.5e-3);
  EXPECT_EQ(r.line(), 4u);
  ASSERT_TRUE(r.readDouble("y").isOk());
  ASSERT_TRUE(r.readDouble("z").isOk());
  auto missing = r.readDouble("attribute");
  ASSERT_FALSE(missing.isOk());
  EXPECT_NE(missing.status().message().find("x.node:"), std::string::npos);
  EXPECT_NE(missing.status().message().find("attribute"), std::string::npos);
  TextReader bad("y.ele", "1 2\nfoo\n");
  ASSERT_TRUE(bad.readInt("a").isOk());
  ASSERT_TRUE(bad.readInt("b").isOk());
  auto v = bad.readInt("node index");
  ASSERT_FALSE(v.isOk());
  EXPECT_NE(v.status().message().find("y.ele:2:"), std::string::npos);
  EXPECT_NE(v.status().message().find("'foo'"), std::string::npos);
}

// A UTF-8 byte order mark is skipped; lines end with LF, CR LF or a lone CR (classic Mac OS), and
// a comment ends with its line whichever it is.
TEST(TextReader, ByteOrderMarkAndEveryLineEnding) {
  for (const char* eol : {"\n", "\r\n", "\r"}) {
    const std::string e = eol;
    const std::string text =
        "\xEF\xBB\xBF"
        "2 1 # count" +
        e + e + "7 8" + e + "9";  // outlives the reader
    TextReader r("m.node", text);
    std::string_view tok;
    ASSERT_TRUE(r.next(&tok));
    EXPECT_EQ(tok, "2");
    ASSERT_TRUE(r.nextOnLine(&tok));
    EXPECT_EQ(tok, "1");
    EXPECT_FALSE(r.nextOnLine(&tok)) << "the comment ends the line";
    ASSERT_TRUE(r.next(&tok));
    EXPECT_EQ(tok, "7");
    EXPECT_EQ(r.line(), 3u) << "line ending " << (e == "\r" ? "CR" : e == "\n" ? "LF" : "CR LF");
    r.skipLine();
    ASSERT_TRUE(r.next(&tok));
    EXPECT_EQ(tok, "9");
    EXPECT_EQ(r.line(), 4u);
  }
}

TEST(TextReader, ShortestRoundTripTextReadsBackBitExact) {
  const double values[] = {0.1, 1.0 / 3.0, 6.02214076e23, -4.9e-324, 123456789.123456789};
  for (double x : values) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    double y;
    ASSERT_TRUE(parseDouble(buf, &y));
    EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0) << buf;
  }
  float f;
  ASSERT_TRUE(parseFloat("0.1", &f));
  EXPECT_EQ(f, 0.1f);
  double z;
  EXPECT_FALSE(parseDouble("1.0x", &z));
  EXPECT_FALSE(parseDouble("", &z));
  // The largest finite value printed with fewer digits lies above it: it reads as that value (VTK's
  // legacy ASCII writer prints DBL_MAX as 1.7976931349e+308). Other overflows are refused.
  const double dmax = std::numeric_limits<double>::max();
  ASSERT_TRUE(parseDouble("1.7976931349e+308", &z));
  EXPECT_EQ(z, dmax);
  ASSERT_TRUE(parseDouble("-1.79769313486232E308", &z));
  EXPECT_EQ(z, -dmax);
  ASSERT_TRUE(parseDouble("+1.80e308", &z));
  EXPECT_EQ(z, dmax);
  EXPECT_FALSE(parseDouble("1.9e308", &z));
  EXPECT_FALSE(parseDouble("1.7976931349e+309", &z));
  EXPECT_FALSE(parseDouble("1.797693134863e308", &z));  // 13 digits: DBL_MAX rounds to ...862e308
  ASSERT_TRUE(parseFloat("3.403e38", &f));
  EXPECT_EQ(f, std::numeric_limits<float>::max());
  ASSERT_TRUE(parseFloat("-3.4028235e+38", &f));
  EXPECT_EQ(f, -std::numeric_limits<float>::max());
  EXPECT_FALSE(parseFloat("3.5e38", &f));
  EXPECT_FALSE(parseFloat("1e39", &f));
}

}  // namespace
}  // namespace gtn

#include "format/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "mesh/fresh_memory.h"

namespace gtn {

namespace {
std::string errnoText() { return std::strerror(errno); }

// Creates a temporary file next to `path` and returns its name and an open FILE*. Its mode is that of
// the file it will replace, or for a new file 0666 less the umask, as the shell's `>` gives (mkstemp
// made it 0600, and it was then set to 0644 whatever the umask said).
Status openTemporary(const std::string& path, std::string* tmp_name, std::FILE** file) {
  static std::atomic<uint64_t> serial{0};
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    const uint64_t n = (static_cast<uint64_t>(::getpid()) << 32) ^ (serial++ * 0x9E3779B97F4A7C15ull) ^
                       static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
    char suffix[24];
    std::snprintf(suffix, sizeof suffix, ".tmp-%06llx", static_cast<unsigned long long>(n & 0xFFFFFF));
    *tmp_name = path + suffix;
    fd = ::open(tmp_name->c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) return ioError(path + ": cannot create a temporary file beside it: " + errnoText());
  struct stat old;
  if (::stat(path.c_str(), &old) == 0 && S_ISREG(old.st_mode)) fchmod(fd, old.st_mode & 0777);
  *file = fdopen(fd, "wb");
  if (!*file) {
    close(fd);
    unlink(tmp_name->c_str());
    return ioError(path + ": cannot open temporary file: " + errnoText());
  }
  return Status::ok();
}

Status writeTemporary(const std::string& path, const std::function<Status(std::FILE*)>& write, std::string* tmp_name,
                      bool sync = true) {
  std::FILE* f = nullptr;
  GTN_RETURN_IF_ERROR(openTemporary(path, tmp_name, &f));
  Status st = write(f);
  if (st.isOk() && (std::fflush(f) != 0 || (sync && fsync(fileno(f)) != 0) || std::ferror(f)))
    st = ioError(path + ": write failed: " + errnoText());
  if (std::fclose(f) != 0 && st.isOk()) st = ioError(path + ": write failed: " + errnoText());
  if (!st.isOk()) unlink(tmp_name->c_str());
  return st;
}
}  // namespace

bool isRegularFile(const std::string& path) {
  struct stat sb;
  return ::stat(path.c_str(), &sb) == 0 && S_ISREG(sb.st_mode);
}

StatusOr<std::string> readWholeFile(const std::string& path, uint64_t max_bytes) {
  std::FILE* f = nullptr;
  if (path == "-") {
    f = stdin;
  } else {
    struct stat sb;
    if (::stat(path.c_str(), &sb) != 0) return ioError(path + ": cannot open: " + errnoText());
    if (S_ISDIR(sb.st_mode)) return ioError(path + ": is a directory, not a file");
    // A device has no end to read to (/dev/zero, /dev/urandom; a .p3d meta-file may name one).
    if (S_ISCHR(sb.st_mode) || S_ISBLK(sb.st_mode)) return ioError(path + ": is a device, not a file");
    f = std::fopen(path.c_str(), "rb");
    if (!f) return ioError(path + ": cannot open: " + errnoText());
  }
  std::string data;
  // A regular file's size is known: room for it at once (growing by doubling copied a 64 MB grid
  // file about twice over, onto fresh pages each time), its pages mapped in one call before they
  // are zeroed and read into. A file that grows meanwhile is read on.
  struct stat st;
  if (f != stdin && ::fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0 &&
      static_cast<uint64_t>(st.st_size) <= max_bytes) {
    data.reserve(static_cast<size_t>(st.st_size));
    populateForWrite(data.data(), static_cast<size_t>(st.st_size));
    data.resize(static_cast<size_t>(st.st_size));
    const size_t got = std::fread(data.data(), 1, data.size(), f);
    data.resize(got);
  }
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    if (data.size() + n > max_bytes) {
      if (f != stdin) std::fclose(f);
      return ioError(path + ": larger than the limit of " + std::to_string(max_bytes) + " bytes");
    }
    data.append(buf, n);
  }
  const bool failed = std::ferror(f) != 0;
  if (f != stdin) std::fclose(f);
  if (failed) return ioError(path + ": read error: " + errnoText());
  return data;
}

bool sameFile(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

namespace {
// Where an output named `path` goes: the file a symbolic link names (followed link by link, also
// when it does not exist yet), and what is there now.
enum class Target { kNew, kRegular, kInPlace, kRefused };
Target outputTarget(const std::string& path, std::string* target, std::string* why) {
  *target = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat sb;
    if (::lstat(target->c_str(), &sb) != 0) return Target::kNew;
    if (S_ISLNK(sb.st_mode)) {
      char buf[4096];
      const ssize_t n = ::readlink(target->c_str(), buf, sizeof buf - 1);
      if (n <= 0) break;
      const std::string link(buf, static_cast<size_t>(n));
      const size_t slash = target->find_last_of('/');
      *target = link[0] == '/' || slash == std::string::npos ? link : target->substr(0, slash + 1) + link;
      continue;
    }
    if (S_ISREG(sb.st_mode)) return Target::kRegular;
    if (S_ISCHR(sb.st_mode) || S_ISFIFO(sb.st_mode)) return Target::kInPlace;
    *why = S_ISDIR(sb.st_mode)   ? "is a directory"
           : S_ISBLK(sb.st_mode) ? "is a block device, not written"
                                 : "is not a file";
    return Target::kRefused;
  }
  *why = "is a chain of symbolic links that does not end";
  return Target::kRefused;
}

// A file the user may not write is not replaced (the rename would replace it all the same, as the
// directory allows it): a file made read-only is kept, as `cp` and the shell's `>` keep it.
Status checkReplaceable(const std::string& path, const std::string& target, Target kind) {
  if (kind == Target::kNew || ::access(target.c_str(), W_OK) == 0 || errno != EACCES) return Status::ok();
  return ioError(path + ": is read-only (not replaced)");
}

// The target writeFileAtomically writes for `path` and its kind, after the checks it makes before
// writing (a refused kind, a read-only file).
Status writableTarget(const std::string& path, std::string* target, Target* kind) {
  std::string why;
  *kind = outputTarget(path, target, &why);
  if (*kind == Target::kRefused) return ioError(path + ": " + why);
  return checkReplaceable(path, *target, *kind);
}
}  // namespace

Status writeFileAtomically(const std::string& path, const std::function<Status(std::FILE*)>& write, bool sync) {
  if (path == "-") {
    GTN_RETURN_IF_ERROR(write(stdout));
    if (std::fflush(stdout) != 0) return ioError("standard output: write failed: " + errnoText());
    return Status::ok();
  }
  std::string target;
  Target kind;
  GTN_RETURN_IF_ERROR(writableTarget(path, &target, &kind));
  if (kind == Target::kInPlace) {
    std::FILE* f = std::fopen(target.c_str(), "wb");
    if (!f) return ioError(path + ": cannot open for writing: " + errnoText());
    Status st = write(f);
    if (st.isOk() && (std::fflush(f) != 0 || std::ferror(f))) st = ioError(path + ": write failed: " + errnoText());
    if (std::fclose(f) != 0 && st.isOk()) st = ioError(path + ": write failed: " + errnoText());
    return st;
  }
  std::string tmp;
  GTN_RETURN_IF_ERROR(writeTemporary(target, write, &tmp, sync));
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const std::string why_not = errnoText();
    unlink(tmp.c_str());
    return ioError(path + ": cannot rename the finished temporary file into place: " + why_not);
  }
  return Status::ok();
}

Status checkOutputWritable(const std::string& path) {
  if (path == "-") return Status::ok();
  std::string target;
  Target kind;
  GTN_RETURN_IF_ERROR(writableTarget(path, &target, &kind));
  if (kind == Target::kInPlace) return Status::ok();
  std::string tmp;
  std::FILE* f = nullptr;
  GTN_RETURN_IF_ERROR(openTemporary(target, &tmp, &f));
  std::fclose(f);
  unlink(tmp.c_str());
  return Status::ok();
}

Status writeBytesAtomically(const std::string& path, const void* data, size_t size, bool sync) {
  return writeFileAtomically(
      path,
      [&](std::FILE* f) -> Status {
        if (size > 0 && std::fwrite(data, 1, size, f) != size) return ioError(path + ": write failed: " + errnoText());
        return Status::ok();
      },
      sync);
}

AtomicFileGroup::~AtomicFileGroup() {
  if (committed_) return;
  for (const auto& [tmp, final_name] : files_) unlink(tmp.c_str());
}

Status AtomicFileGroup::add(const std::string& path, const std::function<Status(std::FILE*)>& write) {
  std::string target, why;
  const Target kind = outputTarget(path, &target, &why);
  if (kind == Target::kInPlace) why = "is not a regular file (a group of files is written whole or not at all)";
  if (kind == Target::kRefused || kind == Target::kInPlace) return ioError(path + ": " + why);
  GTN_RETURN_IF_ERROR(checkReplaceable(path, target, kind));
  std::string tmp;
  GTN_RETURN_IF_ERROR(writeTemporary(target, write, &tmp));
  files_.emplace_back(tmp, target);
  return Status::ok();
}

Status AtomicFileGroup::commit() {
  for (const auto& [tmp, final_name] : files_) {
    if (std::rename(tmp.c_str(), final_name.c_str()) != 0)
      return ioError(final_name + ": cannot rename the finished temporary file into place: " + errnoText());
  }
  committed_ = true;
  return Status::ok();
}

}  // namespace gtn

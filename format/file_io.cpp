#include "format/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace gtn {

namespace {
std::string errnoText() { return std::strerror(errno); }

// Creates a temporary file next to `path` and returns its name and an open FILE*.
Status openTemporary(const std::string& path, std::string* tmp_name, std::FILE** file) {
  std::string templ = path + ".tmp-XXXXXX";
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  const int fd = mkstemp(buf.data());
  if (fd < 0) return ioError(path + ": cannot create a temporary file beside it: " + errnoText());
  fchmod(fd, 0644);
  *tmp_name = buf.data();
  *file = fdopen(fd, "wb");
  if (!*file) {
    close(fd);
    unlink(tmp_name->c_str());
    return ioError(path + ": cannot open temporary file: " + errnoText());
  }
  return Status::ok();
}

Status writeTemporary(const std::string& path, const std::function<Status(std::FILE*)>& write,
                      std::string* tmp_name, bool sync = true) {
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

Status writeFileAtomically(const std::string& path, const std::function<Status(std::FILE*)>& write, bool sync) {
  if (path == "-") {
    GTN_RETURN_IF_ERROR(write(stdout));
    if (std::fflush(stdout) != 0) return ioError("standard output: write failed: " + errnoText());
    return Status::ok();
  }
  std::string tmp;
  GTN_RETURN_IF_ERROR(writeTemporary(path, write, &tmp, sync));
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = errnoText();
    unlink(tmp.c_str());
    return ioError(path + ": cannot rename the finished temporary file into place: " + why);
  }
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
  std::string tmp;
  GTN_RETURN_IF_ERROR(writeTemporary(path, write, &tmp));
  files_.emplace_back(tmp, path);
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

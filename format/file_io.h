// Reading whole inputs and writing outputs atomically (temporary file in the target's directory,
// flushed, then renamed over the target): a failed run leaves no partial output.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mesh/status.h"

namespace gtn {

// Reads a regular file or a pipe (or "-" for standard input) whole. Errors name the file: missing, a
// directory, a device (which has no end), unreadable. `max_bytes` bounds what is read from a pipe.
StatusOr<std::string> readWholeFile(const std::string& path, uint64_t max_bytes = UINT64_MAX);

// True when `path` names an existing regular file.
bool isRegularFile(const std::string& path);

// True when both paths exist and name the same file (through links too).
bool sameFile(const std::string& a, const std::string& b);

// Writes `path` atomically: `write` receives a FILE* to a temporary file beside `path`; when it
// returns ok, the file is flushed, synced (unless `sync` is false: a cache, which a crash may lose
// but never leaves half written) and renamed to `path`; otherwise the temporary is removed.
// "-" writes to standard output directly. A symbolic link is followed (the file it names is
// replaced, the link stays). An existing character device or FIFO (/dev/null, /dev/stdout, a pipe)
// is written in place, as it cannot be replaced without destroying it; a directory, block device or
// socket is refused.
Status writeFileAtomically(const std::string& path, const std::function<Status(std::FILE*)>& write, bool sync = true);

// Whether writeFileAtomically could write `path` now, for a long job to ask before its work rather
// than fail at its end: the checks it makes before writing (a directory or block device refused, a
// read-only file kept), and a temporary file created beside the target and removed at once (a
// directory that is missing, read-only or full). "-", a character device and a FIFO pass.
Status checkOutputWritable(const std::string& path);

// Convenience for writing one buffer atomically.
Status writeBytesAtomically(const std::string& path, const void* data, size_t size, bool sync = true);

// Several outputs that must all appear or none (TetGen's .node/.ele/.face): each is written to a
// temporary; commit() renames all; the destructor removes the temporaries of an uncommitted group.
// Links are followed as by writeFileAtomically; a path that names anything but a regular file (or
// nothing) is refused.
class AtomicFileGroup {
 public:
  ~AtomicFileGroup();
  Status add(const std::string& path, const std::function<Status(std::FILE*)>& write);
  Status commit();

 private:
  std::vector<std::pair<std::string, std::string>> files_;  // temporary, final
  bool committed_ = false;
};

}  // namespace gtn

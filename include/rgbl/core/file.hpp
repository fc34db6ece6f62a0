#pragma once
// Writing files so that a reader never sees half of one, and the folders runs write into: every
// writer in rgbl goes through here.

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace rgbl {

// Calls write(stream) on a temporary file next to `file` (binary mode; a name of its own,
// <name>.<random>.part, so that concurrent writers never share one), then renames it over `file`,
// keeping the permissions of a file it replaces. Only a regular file is replaced this way:
//  - a symbolic link to a regular file: the file it points to is replaced, the link is kept;
//  - a FIFO, a device (/dev/null, /dev/stdout's pipe), a dangling link: written through, as a shell
//    redirection would (not atomic; a FIFO without a reader is an error, not a wait);
//  - a folder: an error.
// On failure (including an exception from `write`) removes the temporary and throws Error naming `file`.
void write_atomically(const std::filesystem::path& file, const std::function<void(std::ofstream&)>& write);

// A folder this process writes a set of outputs into: created when missing, checked to be writable
// (so that a run finds an unusable folder before it works, not after), and locked against other
// processes writing into it at the same time. The lock is flock(2) on the folder itself: no lock file
// to leave behind, and the kernel releases it however the process ends (exit, signal, crash).
class OutputFolder {
 public:
  // Throws Error naming the folder: cannot be created, not writable, or locked by another process.
  explicit OutputFolder(std::filesystem::path folder);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;  // the open folder holding the lock
};

// A fresh folder under the system's temporary directory, removed with everything in it on destruction.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const std::string& prefix = "rgbl");  // throws Error when it cannot be created
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace rgbl

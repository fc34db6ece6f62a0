#pragma once
// Writing files so that a reader never sees half of one, and the folders runs write into: every
// writer in rgbl goes through here. Reading an input file only once it is known to be a regular file
// this process may read: every reader of dataset, calibration, settings and vocabulary files checks it
// here first.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <span>
#include <string>
#include <string_view>

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
// The same with the bytes to write (e.g. an encoded image).
void write_atomically(const std::filesystem::path& file, std::span<const unsigned char> bytes);

// Removes the temporaries write_atomically leaves for `file` when its process is killed while writing
// (<name>.<random>.part next to it). Only for a folder no other process writes into (OutputFolder).
void remove_temporaries_of(const std::filesystem::path& file);

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

// Throws ParseError(file, 0, "<problem> (expected <what>)") unless `file` is a regular file that can be
// read: missing, a folder, not a regular file (a FIFO or device, whose reading may block forever) and
// "cannot read: permission denied" each get their own message.
void require_input_file(const std::filesystem::path& file, std::string_view what);

// Throws ParseError(dir, 0, ...) unless `dir` is a folder whose entries can be listed (missing, not a
// folder, "cannot read: permission denied").
void require_input_folder(const std::filesystem::path& dir, std::string_view what);

// require_input_file, then opens it for reading (binary or text).
std::ifstream open_input_file(const std::filesystem::path& file, std::string_view what, bool binary = false);

// The largest image rgbl decodes: 50 megapixels (8K video is 33). A bigger image would take gigabytes
// once decoded, so its header is refused before decoding.
inline constexpr std::uint64_t kMaxImagePixels = 50'000'000;

// require_input_file, a PNG or JPEG by its first bytes (ParseError otherwise: the only formats
// rgbl/io/image.hpp decodes), and for a PNG (the datasets' format) a header of at most
// kMaxImagePixels pixels.
void require_image_file(const std::filesystem::path& file, std::string_view what);

}  // namespace rgbl

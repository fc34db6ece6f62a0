#pragma once
// Writing a file so that a reader never sees half of it: every writer in rgbl goes through here.

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace rgbl {

// Calls write(stream) on a temporary file next to `file` (binary mode), then renames it into place;
// on failure removes the temporary and throws Error naming `file`.
void write_atomically(const std::filesystem::path& file, const std::function<void(std::ofstream&)>& write);

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

#pragma once

#include "rgbl/core/file.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rgbl::test {

// A fresh folder under the system temp dir, removed with its contents on destruction, with a helper
// to put files in it.
class TempDir {
 public:
  const std::filesystem::path& path() const { return folder_.path(); }

  std::filesystem::path write(const std::string& name, const std::string& contents) const {
    const auto file = path() / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << contents;
    return file;
  }

 private:
  TemporaryFolder folder_{"rgbl-test"};
};

// The whole file as a string (empty when it cannot be read).
inline std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace rgbl::test

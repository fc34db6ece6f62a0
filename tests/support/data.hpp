#pragma once
// Finding the real KITTI excerpt for tests: $RGBL_DATA_DIR, else ../shared/data beside the sources.
// Where it is absent a test says "skipped: no data" (CTest then reports it as skipped). CI sets
// RGBL_REQUIRE_DATA=1 so that a missing data folder fails instead of silently skipping.

#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

namespace rgbl::test {

inline std::filesystem::path data_root() {
  if (const char* env = std::getenv("RGBL_DATA_DIR"); env != nullptr && *env != '\0') return env;
  return RGBL_DEFAULT_DATA_DIR;
}

// Path of `relative` below the data root, or nullopt (after reporting the skip) when it is absent.
inline std::optional<std::filesystem::path> find_data(const std::filesystem::path& relative) {
  const auto path = data_root() / relative;
  if (std::filesystem::exists(path)) return path;
  const char* required = std::getenv("RGBL_REQUIRE_DATA");
  if (required != nullptr && std::string(required) == "1") {
    FAIL("RGBL_REQUIRE_DATA=1 but " << path.string() << " does not exist");
  }
  WARN("skipped: no data (" << path.string() << " not found; set RGBL_DATA_DIR)");
  return std::nullopt;
}

inline std::optional<std::filesystem::path> kitti_seq04() { return find_data("kitti/odometry/sequences/04"); }

}  // namespace rgbl::test

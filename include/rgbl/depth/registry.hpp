#pragma once
// Depth sources created by name. A registry is a plain value: start from with_builtins() (lidar,
// precomputed, stereo, stereo_sparse, rgbd) and add your own factories; nothing is global.

#include "rgbl/depth/depth_source.hpp"
#include "rgbl/depth/sources.hpp"

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace rgbl {

using DepthSourceFactory = std::function<std::unique_ptr<DepthSource>(const DepthSourceSettings&)>;

class DepthSourceRegistry {
 public:
  // An empty registry.
  DepthSourceRegistry() = default;
  // lidar, precomputed, stereo, stereo_sparse, rgbd.
  static DepthSourceRegistry with_builtins();

  // Adds or replaces the factory for `name`. Throws ConfigError("depth.source") for an empty name or
  // factory.
  void add(std::string name, DepthSourceFactory factory);
  bool contains(std::string_view name) const;
  std::vector<std::string> names() const;  // sorted

  // Validates the settings and creates the source. An unknown name throws ConfigError("depth.source")
  // listing the known names.
  std::unique_ptr<DepthSource> create(std::string_view name, const DepthSourceSettings& settings) const;

 private:
  std::map<std::string, DepthSourceFactory, std::less<>> factories_;
};

}  // namespace rgbl

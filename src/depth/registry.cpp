#include "rgbl/depth/registry.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>

namespace rgbl {

DepthSourceRegistry DepthSourceRegistry::with_builtins() {
  DepthSourceRegistry registry;
  registry.add("lidar", make_lidar_source);
  registry.add("precomputed", make_precomputed_source);
  registry.add("stereo", make_stereo_source);
  registry.add("stereo_sparse", make_stereo_sparse_source);
  registry.add("rgbd", make_rgbd_source);
  return registry;
}

void DepthSourceRegistry::add(std::string name, DepthSourceFactory factory) {
  require(!name.empty(), "depth.source", "a non-empty source name");
  require(static_cast<bool>(factory), "depth.source", "a factory for the source");
  factories_.insert_or_assign(std::move(name), std::move(factory));
}

bool DepthSourceRegistry::contains(std::string_view name) const { return factories_.find(name) != factories_.end(); }

std::vector<std::string> DepthSourceRegistry::names() const {
  std::vector<std::string> out;
  out.reserve(factories_.size());
  for (const auto& entry : factories_) out.push_back(entry.first);
  return out;
}

std::unique_ptr<DepthSource> DepthSourceRegistry::create(std::string_view name, const DepthSourceSettings& settings) const {
  const auto found = factories_.find(name);
  if (found == factories_.end()) {
    throw ConfigError("depth.source", fmt::format("one of: {} (got '{}')", fmt::join(names(), ", "), name));
  }
  settings.validate();
  return found->second(settings);
}

}  // namespace rgbl

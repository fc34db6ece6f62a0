#include "rgbl/depth/registry.hpp"

#include "rgbl/core/error.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace rgbl {

void DepthSourceContext::validate() const {
  calibration.camera.validate();
  require(std::isfinite(stereo_baseline) && stereo_baseline >= 0.0, "stereo_baseline", "a finite baseline >= 0 m");
}

std::pair<std::string_view, std::string_view> split_depth_spec(std::string_view spec) {
  const auto colon = spec.find(':');
  if (colon == std::string_view::npos) return {spec, {}};
  return {spec.substr(0, colon), spec.substr(colon + 1)};
}

void DepthSourceRegistry::add(std::string name, DepthSourceEntry entry) {
  require(!name.empty() && name.find(':') == std::string::npos, "depth.source", "a non-empty source name without ':'");
  require(static_cast<bool>(entry.create), "depth.source", "a factory for the source");
  if (entry.usage.empty()) entry.usage = name;
  entries_.insert_or_assign(std::move(name), std::move(entry));
}

bool DepthSourceRegistry::contains(std::string_view name) const { return entries_.find(name) != entries_.end(); }

std::vector<std::string> DepthSourceRegistry::names() const {
  std::vector<std::string> out;
  out.reserve(entries_.size());
  for (const auto& entry : entries_) out.push_back(entry.first);
  return out;
}

std::string DepthSourceRegistry::usage() const {
  std::vector<std::string> all;
  for (const auto& entry : entries_) all.push_back(entry.second.usage);
  return fmt::format("{}", fmt::join(all, ", "));
}

const DepthSourceEntry& DepthSourceRegistry::entry(std::string_view spec) const {
  const auto name = split_depth_spec(spec).first;
  const auto found = entries_.find(name);
  if (found == entries_.end()) {
    throw ConfigError("--depth", fmt::format("one of {}; not '{}'", usage(), spec));
  }
  return found->second;
}

std::unique_ptr<DepthSource> DepthSourceRegistry::create(std::string_view spec, const DepthSourceContext& context) const {
  const DepthSourceEntry& e = entry(spec);
  context.validate();
  auto source = e.create(split_depth_spec(spec).second, context);
  if (!source) throw ConfigError("--depth", fmt::format("a source: the factory of '{}' returned none", spec));
  return source;
}

}  // namespace rgbl

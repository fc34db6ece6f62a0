#pragma once
// Depth sources created by name. Each entry describes itself: what it reads from a frame, how its
// `--depth name[:argument]` argument reads, and how to create it. A registry is a plain value: start
// from builtin_depth_sources() (rgbl/depth/sources.hpp) or empty, add your own; nothing is global.
//
//   registry.add("mono_net", {{}, "mono_net[:<scale>]", [](std::string_view arg, const DepthSourceContext& c) {
//     return std::make_unique<MonoNetSource>(c.calibration, arg.empty() ? 1.0 : std::stod(std::string(arg)));
//   }});
//   auto source = registry.create("mono_net:0.5", context);

#include "rgbl/depth/depth_source.hpp"

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rgbl {

struct DepthSourceEntry {
  DepthSourceNeeds needs;
  std::string usage;  // the spec's grammar for messages, e.g. "precomputed:<folder of uint16 PNGs>"
  // Creates the source from the argument after the colon (empty when none). Throws ConfigError naming
  // "--depth" for an argument it cannot read, or its option key for a bad option.
  std::function<std::unique_ptr<DepthSource>(std::string_view argument, const DepthSourceContext& context)> create;
};

// "name:argument" -> {name, argument}; no colon: {spec, ""}.
std::pair<std::string_view, std::string_view> split_depth_spec(std::string_view spec);

class DepthSourceRegistry {
 public:
  // Adds or replaces the entry for `name`. Throws ConfigError("depth.source") for an empty name, a
  // name with a colon, or an entry without a factory.
  void add(std::string name, DepthSourceEntry entry);
  bool contains(std::string_view name) const;
  std::vector<std::string> names() const;  // sorted
  std::string usage() const;               // every entry's usage, comma separated

  // The entry of spec's name. Throws ConfigError("--depth") listing the known sources.
  const DepthSourceEntry& entry(std::string_view spec) const;

  // Validates the context and creates the source for `spec` (name[:argument]).
  std::unique_ptr<DepthSource> create(std::string_view spec, const DepthSourceContext& context) const;

 private:
  std::map<std::string, DepthSourceEntry, std::less<>> entries_;
};

}  // namespace rgbl

#pragma once
// Named stress scenarios of the synthetic street, each a complete SyntheticOptions with exact ground
// truth: `rgbl demo --scenario NAME`, `rgbl_sim --scenario NAME`. The seed draws the street, the
// actors and all noise; the scenario fixes what is being stressed (docs/synthetic.md, "Scenarios").

#include "rgbl/sim/synthetic.hpp"

#include <cstdint>
#include <string_view>
#include <vector>

namespace rgbl {

struct ScenarioInfo {
  std::string_view name;
  std::string_view description;  // one line
  int default_frames = 60;
};

// Every scenario, in a fixed order ("plain" first).
std::vector<ScenarioInfo> scenarios();

// The options of scenario `name` with this seed and frame count (0 = the scenario's default).
// Throws ConfigError naming "scenario" for an unknown name (the message lists the known ones).
SyntheticOptions scenario_options(std::string_view name, std::uint64_t seed = 1, int frames = 0);

}  // namespace rgbl

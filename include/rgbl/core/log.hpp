#pragma once
// rgbl logs through one named spdlog logger ("rgbl"). Applications choose its sinks and level by
// registering their own logger under that name (or calling set_logger) before using the library;
// otherwise a stderr logger at level "info" is created on first use.

#include <spdlog/logger.h>

#include <memory>

namespace rgbl {

inline constexpr const char* kLoggerName = "rgbl";

std::shared_ptr<spdlog::logger> logger();

// Replaces the library logger; its name is forced to "rgbl".
void set_logger(std::shared_ptr<spdlog::logger> new_logger);

}  // namespace rgbl

#include "rgbl/core/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <mutex>

namespace rgbl {
namespace {
std::mutex& creation_mutex() {
  static std::mutex m;
  return m;
}
}  // namespace

std::shared_ptr<spdlog::logger> logger() {
  if (auto existing = spdlog::get(kLoggerName)) return existing;
  std::scoped_lock lock(creation_mutex());
  if (auto existing = spdlog::get(kLoggerName)) return existing;
  auto created = std::make_shared<spdlog::logger>(
      kLoggerName, std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  created->set_level(spdlog::level::info);
  spdlog::register_logger(created);
  return created;
}

void set_logger(std::shared_ptr<spdlog::logger> new_logger) {
  std::scoped_lock lock(creation_mutex());
  spdlog::drop(kLoggerName);
  if (!new_logger) return;
  if (new_logger->name() != kLoggerName) {
    new_logger = new_logger->clone(kLoggerName);
  }
  spdlog::register_logger(std::move(new_logger));
}

}  // namespace rgbl

#include "rgbl/core/error.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/core/timer.hpp"

#include <catch2/catch.hpp>
#include <spdlog/sinks/ostream_sink.h>

#include <sstream>

TEST_CASE("ParseError names file and line") {
  const rgbl::ParseError e("calib.txt", 3, "expected 12 numbers after 'P2:', found 11");
  CHECK(std::string(e.what()) == "calib.txt:3: expected 12 numbers after 'P2:', found 11");
  CHECK(e.line() == 3);
  const rgbl::ParseError whole("scan.bin", 0, "size 17 bytes is not a multiple of 16");
  CHECK(std::string(whole.what()) == "scan.bin: size 17 bytes is not a multiple of 16");
}

TEST_CASE("ConfigError names the key") {
  CHECK_THROWS_WITH(rgbl::require(false, "projection.max_depth", "a depth > 0"),
                    "invalid option 'projection.max_depth': expected a depth > 0");
  CHECK_NOTHROW(rgbl::require(true, "k", "x"));
}

TEST_CASE("library logger can be redirected by the application") {
  std::ostringstream captured;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(captured);
  rgbl::set_logger(std::make_shared<spdlog::logger>("app", sink));
  rgbl::logger()->warn("hello {}", 42);
  CHECK(rgbl::logger()->name() == "rgbl");
  CHECK(captured.str().find("hello 42") != std::string::npos);
  rgbl::set_logger(nullptr);  // back to the default stderr logger
  CHECK(rgbl::logger() != nullptr);
}

TEST_CASE("stopwatch measures non-negative monotonic time") {
  rgbl::Stopwatch watch;
  const double a = watch.elapsed_ms();
  const double b = watch.elapsed_ms();
  CHECK(a >= 0.0);
  CHECK(b >= a);
}

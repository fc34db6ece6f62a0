#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/core/timer.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <spdlog/sinks/ostream_sink.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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
  const rgbl::ConfigError e("frames", ">= 1");
  CHECK(e.key() == "frames");
  CHECK(e.expected() == ">= 1");  // an application can re-key it with its own option name
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

TEST_CASE("input files: only readable regular files, each problem with its own message") {
  const rgbl::TemporaryFolder dir;
  const auto file = dir.path() / "calib.txt";
  std::ofstream(file) << "P0: 1\n";
  CHECK_NOTHROW(rgbl::require_input_file(file, "a calibration"));
  CHECK_NOTHROW(rgbl::open_input_file(file, "a calibration"));
  const auto message = [](const std::filesystem::path& f) -> std::string {
    try {
      rgbl::require_input_file(f, "a calibration");
    } catch (const rgbl::ParseError& e) {
      CHECK(e.file() == f);
      return e.what();
    }
    return "no error";
  };
  CHECK_THAT(message(dir.path() / "nope.txt"), Catch::Matchers::Contains("missing (expected a calibration)"));
  CHECK_THAT(message(dir.path()), Catch::Matchers::Contains("is a directory"));
  // a FIFO would block the reader forever: refused without opening it
  const auto fifo = dir.path() / "fifo.txt";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_THAT(message(fifo), Catch::Matchers::Contains("is not a regular file"));
  CHECK_THROWS_AS(rgbl::open_input_file(fifo, "a calibration"), rgbl::ParseError);
  CHECK_THROWS_WITH(rgbl::require_input_folder(file, "a dataset"), Catch::Matchers::Contains("not a folder"));
  CHECK_NOTHROW(rgbl::require_input_folder(dir.path(), "a dataset"));
  if (::geteuid() != 0) {  // root reads everything
    std::filesystem::permissions(file, std::filesystem::perms::none);
    CHECK_THAT(message(file), Catch::Matchers::Contains("cannot read: permission denied"));
  }
}

TEST_CASE("image files: a PNG header larger than kMaxImagePixels is refused before decoding") {
  const rgbl::TemporaryFolder dir;
  const auto png = [&](std::uint32_t width, std::uint32_t height) {
    const auto file = dir.path() / fmt::format("{}x{}.png", width, height);
    std::string bytes = "\x89PNG\r\n\x1a\n";
    bytes += std::string("\0\0\0\x0dIHDR", 8);
    for (const std::uint32_t v : {width, height}) {
      for (int shift = 24; shift >= 0; shift -= 8) bytes += static_cast<char>((v >> shift) & 0xff);
    }
    bytes += std::string(9, '\0');  // depth, colour type, ..., CRC: the decoder's business
    std::ofstream(file, std::ios::binary) << bytes;
    return file;
  };
  CHECK_THROWS_WITH(rgbl::require_image_file(png(16000, 16000), "an image"),
                    Catch::Matchers::Contains("16000x16000.png: image is 16000x16000 (256 megapixels), more than "
                                              "rgbl reads (50 megapixels"));
  CHECK_NOTHROW(rgbl::require_image_file(png(1226, 370), "an image"));
  CHECK_NOTHROW(rgbl::require_image_file(png(7000, 7000), "an image"));  // 49 megapixels
}

// rgbl: the command-line front end. Subcommands are in <name>_command.cpp (see command.hpp).
#include "command.hpp"
#include "interrupt.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/version.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <vector>

namespace {

// Prints the exception in flight as one "error: ..." line; returns its exit code.
int print_error(const std::exception_ptr& error) {
  try {
    if (!error) {
      std::fputs("error: internal failure (std::terminate)\n", stderr);
      return 1;
    }
    std::rethrow_exception(error);
  } catch (const rgbl::cli::Interrupted& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return e.exit_code();
  } catch (const cv::Exception& e) {
    fmt::print(stderr, "error: OpenCV failed in {}: {} (an input rgbl does not check yet; please report it)\n",
               e.func, e.err);
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
  } catch (...) {
    std::fputs("error: unknown failure\n", stderr);
  }
  return 1;
}

// Last resort for an exception no handler can catch (one escaping a thread, or thrown while another
// unwinds): the same one `error:` line and exit 1 as main's handlers, not an abort signal.
[[noreturn]] void report_uncaught() { std::_Exit(print_error(std::current_exception())); }

int check_stdout(int code) {
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  if (flushed && std::ferror(stdout) == 0) return code;
  const int error = errno;
  fmt::print(stderr, "error: cannot write to standard output{}\n",
             error != 0 ? fmt::format(" ({})", std::strerror(error)) : std::string());
  return code == 0 ? 1 : code;
}

int run(int argc, char** argv) {
  CLI::App app{"rgbl: LiDAR-enhanced visual SLAM (RGB-L) on KITTI and TUM data, and trajectory evaluation."};
  app.require_subcommand(1, 1);
  app.footer("Run `rgbl <command> --help` for a command's options.");
  app.set_version_flag("--version", RGBL_VERSION_STRING);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "Only print warnings and errors from the library");
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Also print the library's debug messages (e.g. why a frame was judged lost)");

  const std::vector<rgbl::cli::Command> commands{
      rgbl::cli::add_run_command(app),
      rgbl::cli::add_depth_command(app),
      rgbl::cli::add_demo_command(app),
      rgbl::cli::add_info_command(app),
      rgbl::cli::add_eval_command(app),
      rgbl::cli::add_vocab_command(app),
  };

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  auto logger = std::make_shared<spdlog::logger>(rgbl::kLoggerName, sink);
  logger->set_pattern("%^%l%$: %v");
  logger->set_level(quiet ? spdlog::level::warn : verbose ? spdlog::level::debug : spdlog::level::info);
  rgbl::set_logger(logger);

  try {
    for (const auto& command : commands) {
      if (command.app->parsed()) return command.run();
    }
    std::fputs("error: no command given (see rgbl --help)\n", stderr);
    return 2;
  } catch (...) {
    return print_error(std::current_exception());
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::set_terminate(report_uncaught);
  // a closed pipe on stdout (or a FIFO's reader gone) is an EPIPE error to report, not a silent death
  std::signal(SIGPIPE, SIG_IGN);
  const int code = run(argc, argv);
  return check_stdout(code);
}

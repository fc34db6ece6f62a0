#pragma once
// Ctrl-C (SIGINT) and SIGTERM while a command does long work (generating a street, tracking): the
// first signal is only recorded, for the command to see at its next check (between frames), so that
// it can write what it has and exit with 128 + the signal (130, 143); a second one ends the process
// at once, as without a scope. Outside a scope the default handling applies.

#include <stdexcept>
#include <string>

#include <signal.h>

namespace rgbl::cli {

// Thrown by InterruptScope::throw_if_interrupted; main() prints it and exits with exit_code().
class Interrupted : public std::runtime_error {
 public:
  Interrupted(const std::string& what, int exit_code) : std::runtime_error(what), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

class InterruptScope {
 public:
  InterruptScope();   // installs the handlers (one scope at a time)
  ~InterruptScope();  // restores the previous ones
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

  int signal() const;  // the signal received in this scope, 0 if none
  bool interrupted() const { return signal() != 0; }
  int exit_code() const { return 128 + signal(); }
  std::string signal_name() const;  // "SIGINT", "SIGTERM"
  // Throws Interrupted("interrupted by SIGINT <while>", 130) when a signal came.
  void throw_if_interrupted(const std::string& while_doing) const;

 private:
  struct sigaction previous_int_ {};
  struct sigaction previous_term_ {};
};

}  // namespace rgbl::cli

#include "interrupt.hpp"

#include <fmt/format.h>

#include <csignal>

namespace rgbl::cli {
namespace {

// The one piece of global state: what the handler may touch (a sig_atomic_t it sets).
volatile std::sig_atomic_t received_signal = 0;

extern "C" void on_signal(int signal) {
  if (received_signal != 0) {
    // a second signal: the user insists, end now with the default action (both calls are async-signal-safe)
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return;
  }
  received_signal = signal;
}

}  // namespace

InterruptScope::InterruptScope() {
  received_signal = 0;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // reads of the loader thread go on undisturbed
  sigaction(SIGINT, &action, &previous_int_);
  sigaction(SIGTERM, &action, &previous_term_);
}

InterruptScope::~InterruptScope() {
  sigaction(SIGINT, &previous_int_, nullptr);
  sigaction(SIGTERM, &previous_term_, nullptr);
}

int InterruptScope::signal() const { return received_signal; }

std::string InterruptScope::signal_name() const {
  switch (signal()) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    default: return fmt::format("signal {}", signal());
  }
}

void InterruptScope::throw_if_interrupted(const std::string& while_doing) const {
  if (interrupted()) throw Interrupted(fmt::format("interrupted by {} {}", signal_name(), while_doing), exit_code());
}

}  // namespace rgbl::cli

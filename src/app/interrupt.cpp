#include "app/interrupt.hpp"

#include <csignal>

namespace mmpm {
namespace {

volatile std::sig_atomic_t g_pending = 0;

extern "C" void note_interrupt(int sig) {
  g_pending = sig;
}

}  // namespace

void catch_interrupts() {
  struct sigaction action {};
  action.sa_handler = note_interrupt;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: the handler runs once, the next signal takes the default
  // action (a user pressing Ctrl-C twice means it). SA_RESTART: a signal
  // arriving during a write does not make it fail with EINTR.
  action.sa_flags = SA_RESETHAND | SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int pending_interrupt() {
  return int(g_pending);
}

const char* signal_name(int sig) {
  switch (sig) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

}  // namespace mmpm

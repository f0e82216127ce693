// Ctrl-C (SIGINT) and a batch system's SIGTERM before its SIGKILL end
// `mmpm run` and `mmpm sweep` between two steps instead of mid-write: the
// run writes a checkpoint (whatever output.checkpoint_minutes says), leaves
// its run.h5.partial for `mmpm run --restart DIR`, and exits with 128 +
// the signal's number, the shell's convention. A second signal of the same
// kind ends the process at once, as if no handler were installed.
#pragma once

namespace mmpm {

// Installs the handlers for SIGINT and SIGTERM (once per process).
void catch_interrupts();

// The signal that asked the process to stop, or 0.
int pending_interrupt();

// "SIGINT", "SIGTERM", or "a signal".
const char* signal_name(int sig);

}  // namespace mmpm

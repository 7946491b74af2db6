#pragma once
// SIGINT, SIGTERM and SIGHUP end the CLI cleanly: every temporary output is removed
// (remove_pending_outputs) and the process exits with 128 + the signal's number (130, 143, 129),
// leaving the previous outputs as they were. The signals are blocked in every thread and taken by
// one thread of the CLI's own (sigwait), so the cleanup runs in an ordinary thread, not inside a
// signal handler. The library installs nothing: this is the program's choice.
namespace lidarsurf::cli {

/// Call first in main(), before any other thread exists (the mask is inherited).
void handle_interrupts();
/// True once a signal is being handled; the main thread then waits for the exit instead of
/// reporting the failed commit that the cleanup caused.
bool interrupted();
/// From now on a signal ends the process with 0: its work is done and written (e.g. fuse --serve
/// showing the final map until Ctrl-C).
void finish_on_interrupt();
/// Blocks for good (the signal thread ends the process): for the main thread when interrupted().
[[noreturn]] void wait_for_exit();

}  // namespace lidarsurf::cli

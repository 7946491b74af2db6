#include "interrupt.hpp"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <thread>

#include "lidarsurf/io/atomic_file.hpp"

namespace lidarsurf::cli {
namespace {

std::atomic<bool> g_interrupted{false};
std::atomic<bool> g_finished{false};

sigset_t interrupt_signals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    return set;
}

}  // namespace

void handle_interrupts() {
    const sigset_t set = interrupt_signals();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::thread([set] {
        int sig = 0;
        while (sigwait(&set, &sig) != 0) {
        }
        g_interrupted = true;
        if (g_finished) {
            std::fflush(stdout);
            ::_exit(0);
        }
        const std::size_t removed = remove_pending_outputs();
        char msg[160];
        const int n = std::snprintf(msg, sizeof msg, "lidarsurf: interrupted by %s; %zu unfinished output%s removed, earlier outputs untouched\n",
                                    sigabbrev_np(sig) ? sigabbrev_np(sig) : "a signal", removed, removed == 1 ? "" : "s");
        if (n > 0) [[maybe_unused]] const ssize_t w = ::write(STDERR_FILENO, msg, static_cast<std::size_t>(n));
        std::fflush(stdout);
        ::_exit(128 + sig);
    }).detach();
}

bool interrupted() { return g_interrupted.load(); }

void finish_on_interrupt() { g_finished = true; }

void wait_for_exit() {
    for (;;) ::pause();
}

}  // namespace lidarsurf::cli

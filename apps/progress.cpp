#include "progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace lidarsurf::cli {
namespace {

bool stderr_is_terminal() {
    const char* term = std::getenv("TERM");
    return ::isatty(STDERR_FILENO) == 1 && !(term && std::strcmp(term, "dumb") == 0);
}

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

Progress::Progress(std::string what, std::string unit, std::size_t total, bool quiet)
    : what_(std::move(what)), unit_(std::move(unit)), total_(std::max<std::size_t>(total, 1)), quiet_(quiet),
      terminal_(stderr_is_terminal()), start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

void Progress::update(std::size_t done, const std::string& detail) {
    if (quiet_) return;
    const auto now = std::chrono::steady_clock::now();
    if (terminal_) {
        if (done < total_ && drawn_ && now - last_draw_ < std::chrono::milliseconds(100)) return;  // 10 redraws a second at most
    } else {
        if (done < next_line_ && done < total_) return;
        next_line_ = done + std::max<std::size_t>(1, total_ / 10);
    }
    last_draw_ = now;
    draw(done, detail, false);
}

void Progress::finish(const std::string& detail) {
    if (quiet_) return;
    if (terminal_) {
        draw(total_, detail, true);
    } else if (next_line_ <= total_) {
        draw(total_, detail, true);
    }
}

void Progress::draw(std::size_t done, const std::string& detail, bool last) {
    const double elapsed = seconds(std::chrono::steady_clock::now() - start_);
    const double share = static_cast<double>(std::min(done, total_)) / static_cast<double>(total_);
    char eta[48] = "";
    if (!last && done > 0 && done < total_) std::snprintf(eta, sizeof eta, ", %.0f s left", elapsed * (1.0 - share) / share);
    const std::string tail = detail.empty() ? "" : "; " + detail;
    if (terminal_) {
        constexpr int kWidth = 24;
        const int filled = static_cast<int>(share * kWidth + 0.5);
        std::fprintf(stderr, "\r\033[K%s [%.*s%*s] %zu/%zu %s (%.0f %%), %.1f s%s%s%s", what_.c_str(), filled, "########################",
                     kWidth - filled, "", std::min(done, total_), total_, unit_.c_str(), 100.0 * share, elapsed, eta, tail.c_str(),
                     last ? "\n" : "");
    } else {
        std::fprintf(stderr, "%s: %zu/%zu %s (%.0f %%), %.1f s%s%s\n", what_.c_str(), std::min(done, total_), total_, unit_.c_str(),
                     100.0 * share, elapsed, eta, tail.c_str());
    }
    std::fflush(stderr);
    drawn_ = true;
}

}  // namespace lidarsurf::cli

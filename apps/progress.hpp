#pragma once
// Progress of a long command (simulate, fuse, benchmark) on stderr: a bar redrawn in place when
// stderr is a terminal, plain lines at every tenth of the work otherwise (logs, CI), nothing with
// --quiet.
#include <chrono>
#include <cstddef>
#include <string>

namespace lidarsurf::cli {

class Progress {
public:
    /// `what` names the command ("fuse"), `unit` the items counted ("frames").
    Progress(std::string what, std::string unit, std::size_t total, bool quiet);
    /// `done` items of the total are done; `detail` is shown after the count.
    void update(std::size_t done, const std::string& detail = "");
    /// Ends the bar's line (a terminal) or prints the last line.
    void finish(const std::string& detail = "");

private:
    void draw(std::size_t done, const std::string& detail, bool last);

    std::string what_, unit_;
    std::size_t total_;
    bool quiet_, terminal_;
    std::size_t next_line_ = 0;  // plain lines: the next count that prints one
    std::chrono::steady_clock::time_point start_, last_draw_;
    bool drawn_ = false;
};

}  // namespace lidarsurf::cli

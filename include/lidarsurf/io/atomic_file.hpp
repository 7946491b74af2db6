#pragma once
// Writes a file through a temporary in the same directory, renamed over the target only when the
// content is complete, so a failure never leaves a half-written or truncated output.
#include <filesystem>
#include <fstream>

namespace lidarsurf {

class AtomicFile {
public:
    /// Opens a temporary next to `target`. Throws IoError if the directory is not writable.
    explicit AtomicFile(std::filesystem::path target);
    /// Removes the temporary if commit() was not reached.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ostream& stream() { return out_; }
    /// Flushes, checks the stream and renames the temporary onto the target. Throws IoError.
    void commit();

private:
    std::filesystem::path target_, temp_;
    std::ofstream out_;
    bool committed_ = false;
};

}  // namespace lidarsurf

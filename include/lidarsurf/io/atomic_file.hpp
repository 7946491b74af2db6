#pragma once
// Outputs that are complete or absent. A regular file is written through a temporary in the same
// directory and renamed over the target only when the content is complete, so a failure never
// leaves a half-written or truncated output. A symbolic link is written through: the file it
// names gets the new content and the link stays. A target that is not a regular file (a FIFO, a
// terminal, /dev/stdout, /dev/null) is written directly: there is nothing to rename over.
//
// Every temporary still open is listed, so that a program interrupted by a signal can remove them
// all before it exits (remove_pending_outputs(); the CLI calls it from its signal thread).
#include <filesystem>
#include <fstream>

namespace lidarsurf {

class AtomicFile {
public:
    /// Opens a temporary next to `target` (next to the file it names, for a symbolic link).
    /// Throws IoError if the name is empty or the directory is not writable.
    explicit AtomicFile(std::filesystem::path target);
    /// Removes the temporary if commit() was not reached.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ostream& stream() { return out_; }
    /// Flushes, checks the stream and renames the temporary onto the target. Throws IoError.
    void commit();

    /// Where the content goes: the target, or the file a symbolic link at the target names.
    const std::filesystem::path& destination() const { return destination_; }
    /// Whether the target is written directly (not a regular file: FIFO, device, terminal).
    bool direct() const { return direct_; }

private:
    std::filesystem::path target_, destination_, temp_;
    std::ofstream out_;
    bool direct_ = false;
    bool committed_ = false;
};

/// A directory that appears whole or not at all: its content is written under a temporary
/// sibling (path()) and commit() puts it in place, replacing an existing directory at the target
/// in one step (the old one is then removed). The destructor removes the temporary if commit()
/// was not reached.
class AtomicDirectory {
public:
    /// Creates the temporary directory. Throws IoError if the parent is missing or not writable.
    explicit AtomicDirectory(std::filesystem::path target);
    ~AtomicDirectory();
    AtomicDirectory(const AtomicDirectory&) = delete;
    AtomicDirectory& operator=(const AtomicDirectory&) = delete;

    /// The temporary directory to write into.
    const std::filesystem::path& path() const { return temp_; }
    /// Moves the temporary onto the target. Throws IoError.
    void commit();

private:
    std::filesystem::path target_, temp_;
    bool committed_ = false;
};

/// Removes every temporary file and directory that an AtomicFile or AtomicDirectory of this
/// process still holds, and makes their commit() fail from then on. Thread-safe; meant for a
/// program's own signal-handling thread (not a signal handler: it allocates). Returns how many
/// were removed.
std::size_t remove_pending_outputs();

/// The name of the temporary beside `target` for this process: NAME.tmp.PID.N, with NAME cut so
/// that the whole fits the file system's name limit (255 bytes).
std::filesystem::path temporary_name(const std::filesystem::path& target);

}  // namespace lidarsurf

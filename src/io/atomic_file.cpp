#include "lidarsurf/io/atomic_file.hpp"

#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <list>
#include <mutex>
#include <system_error>

#include "lidarsurf/core/errors.hpp"

namespace fs = std::filesystem;

namespace lidarsurf {

namespace {

// The temporaries this process holds, for remove_pending_outputs(). Once that has run
// (`closed`), no commit may put a temporary in place: the process is on its way out.
struct PendingOutputs {
    std::mutex mutex;
    std::list<std::pair<fs::path, bool>> entries;  // path, is a directory
    bool closed = false;
};
PendingOutputs& pending() {
    static PendingOutputs p;
    return p;
}
void add_pending(const fs::path& path, bool directory) {
    PendingOutputs& p = pending();
    std::lock_guard lock(p.mutex);
    if (p.closed) throw IoError(path.string() + ": the program is being interrupted; nothing more is written");
    p.entries.emplace_back(path, directory);
}

// Takes `path` off the list (the caller holds the mutex); true if it was listed, that is, not
// removed by remove_pending_outputs() meanwhile.
bool drop_pending(PendingOutputs& p, const fs::path& path) {
    for (auto it = p.entries.begin(); it != p.entries.end(); ++it)
        if (it->first == path) {
            p.entries.erase(it);
            return true;
        }
    return false;
}

// A path names a stream rather than a file to replace: /dev/stdout, /dev/fd/N, /proc/self/fd/N.
bool is_stream_path(const fs::path& path) {
    const std::string s = path.lexically_normal().string();
    return s.starts_with("/dev/") || s.starts_with("/proc/");
}

// The file a chain of symbolic links at `path` ends at (the path itself when it is no link).
fs::path follow_links(fs::path path) {
    std::error_code ec;
    for (int hops = 0; fs::is_symlink(fs::symlink_status(path, ec)); ++hops) {
        if (hops == 40) throw IoError(path.string() + ": too many levels of symbolic links");
        const fs::path link = fs::read_symlink(path, ec);
        if (ec) throw IoError(path.string() + ": cannot read the symbolic link (" + ec.message() + ")");
        path = link.is_absolute() ? link : path.parent_path() / link;
    }
    return path;
}

}  // namespace

fs::path temporary_name(const fs::path& target) {
    static std::atomic<unsigned> counter{0};
    constexpr std::size_t kNameMax = 255;
    const std::string suffix = ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    std::string name = target.filename().string();
    if (name.size() + suffix.size() > kNameMax) {
        std::size_t keep = kNameMax - suffix.size();
        while (keep > 0 && (static_cast<unsigned char>(name[keep]) & 0xC0) == 0x80) --keep;  // not inside a UTF-8 character
        name.resize(keep);
    }
    return target.parent_path() / (name + suffix);
}

AtomicFile::AtomicFile(fs::path target) : target_(std::move(target)) {
    if (target_.empty()) throw IoError("the output file name is empty");
    if (target_.filename().string().size() > 255) throw IoError(target_.string() + ": file name too long (over 255 bytes)");
    std::error_code ec;
    const fs::file_status st = fs::status(target_, ec);  // follows links
    if (fs::is_directory(st)) throw IoError(target_.string() + ": is a directory");
    if (is_stream_path(target_) || (fs::exists(st) && !fs::is_regular_file(st))) {
        // A FIFO, a terminal, a device: written as it is, nothing to rename over.
        direct_ = true;
        destination_ = target_;
        out_.open(target_, std::ios::binary | std::ios::trunc);
        if (!out_) throw IoError(target_.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
        return;
    }
    destination_ = follow_links(target_);
    temp_ = temporary_name(destination_);
    add_pending(temp_, false);
    out_.open(temp_, std::ios::binary | std::ios::trunc);
    if (!out_) {
        const int err = errno;
        std::lock_guard lock(pending().mutex);
        drop_pending(pending(), temp_);
        throw IoError(target_.string() + ": cannot write (" +
                      (err == ENAMETOOLONG ? std::string("file name too long")
                       : err == ENOENT     ? std::string("directory missing")
                                           : std::strerror(err)) +
                      ")");
    }
}

AtomicFile::~AtomicFile() {
    if (committed_ || direct_) return;
    out_.close();
    PendingOutputs& p = pending();
    std::lock_guard lock(p.mutex);
    std::error_code ec;
    if (drop_pending(p, temp_)) fs::remove(temp_, ec);
}

void AtomicFile::commit() {
    out_.flush();
    const bool ok = static_cast<bool>(out_);
    out_.close();
    if (!ok || out_.fail()) throw IoError(target_.string() + ": write failed (disk full?)");
    if (direct_) {
        committed_ = true;
        return;
    }
    PendingOutputs& p = pending();
    std::lock_guard lock(p.mutex);
    if (p.closed) throw IoError(target_.string() + ": the program is being interrupted; the output is not written");
    std::error_code ec;
    fs::rename(temp_, destination_, ec);
    if (ec) throw IoError(target_.string() + ": cannot rename the finished file into place: " + ec.message());
    drop_pending(p, temp_);
    committed_ = true;
}

AtomicDirectory::AtomicDirectory(fs::path target) : target_(std::move(target)) {
    if (target_.empty()) throw IoError("the output directory name is empty");
    std::error_code ec;
    if (fs::exists(target_, ec) && !fs::is_directory(target_, ec)) throw IoError(target_.string() + ": exists and is not a directory");
    const fs::path parent = fs::absolute(target_, ec).parent_path();
    fs::create_directories(parent, ec);
    if (ec) throw IoError(parent.string() + ": cannot create the directory (" + ec.message() + ")");
    temp_ = temporary_name(fs::absolute(target_).lexically_normal());
    add_pending(temp_, true);
    if (!fs::create_directory(temp_, ec) || ec) {
        std::lock_guard lock(pending().mutex);
        drop_pending(pending(), temp_);
        throw IoError(target_.string() + ": cannot create a directory beside it (" + (ec ? ec.message() : "exists") + ")");
    }
}

AtomicDirectory::~AtomicDirectory() {
    if (committed_) return;
    PendingOutputs& p = pending();
    std::lock_guard lock(p.mutex);
    std::error_code ec;
    if (drop_pending(p, temp_)) fs::remove_all(temp_, ec);
}

void AtomicDirectory::commit() {
    PendingOutputs& p = pending();
    std::unique_lock lock(p.mutex);
    if (p.closed) throw IoError(target_.string() + ": the program is being interrupted; the output is not written");
    std::error_code ec;
    if (!fs::exists(target_, ec)) {
        fs::rename(temp_, target_, ec);
        if (ec) throw IoError(target_.string() + ": cannot move the finished directory into place: " + ec.message());
        drop_pending(p, temp_);
        committed_ = true;
        return;
    }
    // Swap in one step: the target then holds the new content, the temporary the old one, which
    // stays listed (a signal from here on removes it) until it is removed below.
    if (::renameat2(AT_FDCWD, temp_.c_str(), AT_FDCWD, target_.c_str(), RENAME_EXCHANGE) != 0) {
        if (errno != EINVAL && errno != ENOSYS)
            throw IoError(target_.string() + ": cannot replace the directory (" + std::strerror(errno) + ")");
        // A file system without the exchange: the old directory is moved aside, then the new one in.
        const fs::path aside = temporary_name(fs::absolute(target_).lexically_normal());
        fs::rename(target_, aside, ec);
        if (ec) throw IoError(target_.string() + ": cannot replace the directory (" + ec.message() + ")");
        fs::rename(temp_, target_, ec);
        if (ec) {
            fs::rename(aside, target_, ec);
            throw IoError(target_.string() + ": cannot move the finished directory into place");
        }
        fs::rename(aside, temp_, ec);  // the old content where the listed temporary was
    }
    committed_ = true;
    lock.unlock();
    fs::remove_all(temp_, ec);
    lock.lock();
    drop_pending(p, temp_);
}

std::size_t remove_pending_outputs() {
    PendingOutputs& p = pending();
    std::lock_guard lock(p.mutex);
    p.closed = true;
    std::size_t removed = 0;
    for (const auto& [path, directory] : p.entries) {
        std::error_code ec;
        removed += directory ? fs::remove_all(path, ec) > 0 : fs::remove(path, ec);
    }
    p.entries.clear();
    return removed;
}

}  // namespace lidarsurf

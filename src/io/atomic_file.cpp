#include "lidarsurf/io/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <system_error>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

namespace {
std::filesystem::path temp_name(const std::filesystem::path& target) {
    static std::atomic<unsigned> counter{0};
    std::filesystem::path tmp = target;
    tmp += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    return tmp;
}
}  // namespace

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)), temp_(temp_name(target_)) {
    std::error_code ec;
    if (std::filesystem::is_directory(target_, ec)) throw IoError(target_.string() + ": is a directory");
    out_.open(temp_, std::ios::binary | std::ios::trunc);
    if (!out_) throw IoError(target_.string() + ": cannot write (directory missing or not writable)");
}

AtomicFile::~AtomicFile() {
    if (!committed_) {
        out_.close();
        std::error_code ec;
        std::filesystem::remove(temp_, ec);
    }
}

void AtomicFile::commit() {
    out_.flush();
    const bool ok = static_cast<bool>(out_);
    out_.close();
    if (!ok || out_.fail()) throw IoError(target_.string() + ": write failed (disk full?)");
    std::error_code ec;
    std::filesystem::rename(temp_, target_, ec);
    if (ec) throw IoError(target_.string() + ": cannot rename the finished file into place: " + ec.message());
    committed_ = true;
}

}  // namespace lidarsurf

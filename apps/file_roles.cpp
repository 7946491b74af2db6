#include "file_roles.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <optional>
#include <utility>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/atomic_file.hpp"

namespace fs = std::filesystem;

namespace lidarsurf::cli {
namespace {

// (device, inode) of what `path` names, through links; none when it does not exist.
std::optional<std::pair<dev_t, ino_t>> identity(const fs::path& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return std::nullopt;
    return std::pair{st.st_dev, st.st_ino};
}

// The absolute path with links and dot segments resolved as far as it exists.
fs::path resolved(const fs::path& path) {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
    return ec ? fs::absolute(path, ec).lexically_normal() : p.lexically_normal();
}

bool is_within(const fs::path& inner, const fs::path& outer) {
    const fs::path rel = resolved(inner).lexically_relative(resolved(outer));
    return !rel.empty() && *rel.begin() != "..";
}

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

}  // namespace

void FileRoles::input(const fs::path& path) { inputs_.push_back(path); }

void FileRoles::input_tree(const fs::path& dir) {
    std::error_code ec;
    for (fs::recursive_directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec), end; !ec && it != end;
         it.increment(ec)) {
        if (it.depth() >= 2) it.disable_recursion_pending();
        if (it->is_regular_file(ec)) inputs_.push_back(it->path());
    }
}

void FileRoles::input_sequence(const fs::path& dir) {
    std::error_code ec;
    for (const fs::path& d : {dir, dir / "velodyne", dir / "gt", dir / "objects"})
        for (fs::directory_iterator it(d, ec), end; !ec && it != end; it.increment(ec))
            if (it->is_regular_file(ec)) inputs_.push_back(it->path());
}

void FileRoles::output(const fs::path& path, const std::string& flag) { outputs_.push_back({path, flag, false}); }

void FileRoles::output_directory(const fs::path& path, const std::string& flag) { outputs_.push_back({path, flag, true}); }

void FileRoles::check() const {
    for (const Output& o : outputs_) {
        if (o.path.empty()) throw InvalidArgument(o.flag + ": the file name is empty");
        if (o.path.filename().string().size() > 255)
            throw InvalidArgument(o.flag + ": the file name is longer than 255 bytes (" + std::to_string(o.path.filename().string().size()) + ")");
    }
    // An output that is an input, found by identity (hard links, symbolic links, other spellings).
    for (const Output& o : outputs_) {
        if (o.directory) {
            for (const fs::path& in : inputs_)
                if (is_within(in, o.path) || resolved(in) == resolved(o.path))
                    throw InvalidArgument(o.flag + " " + quoted(o.path) + " holds the input " + quoted(in) + "; refusing to replace it");
            continue;
        }
        const auto out_id = identity(o.path);
        if (!out_id) continue;
        for (const fs::path& in : inputs_)
            if (identity(in) == out_id)
                throw InvalidArgument(o.flag + " " + quoted(o.path) + " is the input " + quoted(in) + "; refusing to overwrite it");
    }
    // Two outputs naming one file (or a file inside an output directory).
    for (std::size_t i = 0; i < outputs_.size(); ++i)
        for (std::size_t j = i + 1; j < outputs_.size(); ++j) {
            const Output &a = outputs_[i], &b = outputs_[j];
            const auto ia = identity(a.path), ib = identity(b.path);
            const bool same = (ia && ia == ib) || resolved(a.path) == resolved(b.path) ||
                              (a.directory && is_within(b.path, a.path)) || (b.directory && is_within(a.path, b.path));
            if (same) throw InvalidArgument(a.flag + " and " + b.flag + " name the same file " + quoted(b.path));
        }
    // Writable, found now rather than after the work.
    std::error_code ec;
    for (const Output& o : outputs_) {
        const fs::file_status st = fs::status(o.path, ec);
        if (o.directory) {
            if (fs::exists(st) && !fs::is_directory(st)) throw IoError(o.path.string() + ": exists and is not a directory");
            if (fs::is_directory(st) && !fs::is_empty(o.path, ec) && !fs::exists(o.path / "sensor.json", ec))
                throw InvalidArgument(o.flag + " " + quoted(o.path) +
                                      " is a directory that lidarsurf did not write (no sensor.json); refusing to replace it: name a new or empty directory");
            const fs::path parent = fs::absolute(o.path, ec).parent_path();
            const fs::path probe_dir = fs::exists(parent, ec) ? parent : fs::path();
            if (!probe_dir.empty() && ::access(probe_dir.c_str(), W_OK) != 0)
                throw IoError(o.path.string() + ": cannot write in " + probe_dir.string());
            continue;
        }
        if (fs::exists(st) && !fs::is_regular_file(st) && !fs::is_directory(st)) continue;  // FIFO, device: written directly
        AtomicFile probe(o.path);  // IoError now rather than after the work; never committed
    }
}

}  // namespace lidarsurf::cli

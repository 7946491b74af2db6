#pragma once
// Which files a command reads and which it writes, checked together before any work: an output
// never names an input (compared by file identity, through links, for every output flag), two
// outputs never name one file, and every output can be written.
#include <filesystem>
#include <string>
#include <vector>

namespace lidarsurf::cli {

class FileRoles {
public:
    /// A file the command reads.
    void input(const std::filesystem::path& path);
    /// Every file under `dir`, two levels deep (a peers' directory of NAME/NNNNNN.ply).
    void input_tree(const std::filesystem::path& dir);
    /// The files of a sequence in the KITTI layout: those in `dir` itself (poses.txt, calib.txt,
    /// scene.ply, ...) and in its velodyne/, gt/ and objects/.
    void input_sequence(const std::filesystem::path& dir);
    /// A file the command writes, named by the option `flag` (for messages). An empty name is an error.
    void output(const std::filesystem::path& path, const std::string& flag);
    /// A directory the command writes whole (AtomicDirectory): no input may lie inside it, and an
    /// existing one is replaced only if it is empty or was written by `lidarsurf simulate`.
    void output_directory(const std::filesystem::path& path, const std::string& flag);

    /// Throws InvalidArgument (an output is an input, two outputs are one file, an empty name, a
    /// directory that is not ours to replace) or IoError (an output cannot be written).
    void check() const;

private:
    struct Output {
        std::filesystem::path path;
        std::string flag;
        bool directory = false;
    };
    std::vector<std::filesystem::path> inputs_;
    std::vector<Output> outputs_;
};

}  // namespace lidarsurf::cli

// Outputs that are complete or absent (io/atomic_file.hpp): links written through, streams
// written directly, long names, directories replaced whole, and the temporaries a signal thread
// removes. Expected states come from the file system (stat, readlink, file contents).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "test_util.hpp"

using namespace lidarsurf;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::size_t temporaries_in(const fs::path& dir) {
    std::size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir)) n += e.path().filename().string().find(".tmp.") != std::string::npos;
    return n;
}

void write_atomically(const fs::path& target, const std::string& text) {
    AtomicFile f(target);
    f.stream() << text;
    f.commit();
}

TEST(AtomicFile, WritesThroughASymbolicLinkAndKeepsIt) {
    const test::TempDir d("atomic_link");
    fs::create_directories(d / "real");
    std::ofstream(d / "real" / "mesh.ply") << "old";
    fs::create_symlink("real/mesh.ply", d / "link.ply");                  // relative target
    fs::create_symlink(d / "link.ply", d / "chain.ply");                  // a link to a link
    fs::create_symlink(d / "real" / "new.ply", d / "dangling.ply");        // target not there yet
    write_atomically(d / "chain.ply", "new");
    write_atomically(d / "dangling.ply", "fresh");
    EXPECT_TRUE(fs::is_symlink(d / "link.ply"));
    EXPECT_TRUE(fs::is_symlink(d / "chain.ply"));
    EXPECT_TRUE(fs::is_symlink(d / "dangling.ply"));
    EXPECT_EQ(slurp(d / "real" / "mesh.ply"), "new");
    EXPECT_EQ(slurp(d / "real" / "new.ply"), "fresh");
    EXPECT_EQ(temporaries_in(d) + temporaries_in(d / "real"), 0u);
    fs::remove_all(d);
}

TEST(AtomicFile, WritesAFifoAndADeviceDirectly) {
    const test::TempDir d("atomic_fifo");
    const fs::path fifo = d / "out.ply";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::string got;
    std::thread reader([&] { got = slurp(fifo); });
    write_atomically(fifo, "through the pipe");
    reader.join();
    EXPECT_EQ(got, "through the pipe");
    EXPECT_TRUE(fs::is_fifo(fifo));
    write_atomically("/dev/null", "gone");
    EXPECT_TRUE(fs::is_character_file("/dev/null"));
    EXPECT_EQ(temporaries_in(d), 0u);
    fs::remove_all(d);
}

TEST(AtomicFile, TemporaryNameFitsTheNameLimit) {
    const test::TempDir d("atomic_long");
    const std::string name = std::string(250, 'a') + ".ply";  // 254 bytes: the name limit is 255
    write_atomically(d / name, "long");
    EXPECT_EQ(slurp(d / name), "long");
    // A cut that falls inside a two-byte character (é) moves back to the character's start.
    for (const std::string& target : {name, std::string(236, 'b') + "\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9.ply"}) {
        const std::string tmp = temporary_name(d / target).filename().string();
        EXPECT_LE(tmp.size(), 255u) << tmp;
        const auto last = static_cast<unsigned char>(tmp[tmp.find(".tmp.") - 1]);
        EXPECT_TRUE(last < 0x80 || (last & 0xC0) == 0x80) << "the cut leaves no UTF-8 character half";
    }
    EXPECT_THROW(AtomicFile(d / (std::string(256, 'c'))), IoError);  // the name itself is too long
    EXPECT_THROW(AtomicFile(fs::path()), IoError);
    EXPECT_EQ(temporaries_in(d), 0u);
    fs::remove_all(d);
}

TEST(AtomicDirectory, AppearsWholeAndReplacesAnOldOneInOneStep) {
    const test::TempDir d("atomic_dir");
    const fs::path target = d / "seq";
    {
        AtomicDirectory out(target);
        std::ofstream(out.path() / "a.txt") << "first";
        EXPECT_FALSE(fs::exists(target));  // nothing at the target until the commit
        out.commit();
    }
    EXPECT_EQ(slurp(target / "a.txt"), "first");
    {
        AtomicDirectory out(target);
        std::ofstream(out.path() / "b.txt") << "second";
        EXPECT_EQ(slurp(target / "a.txt"), "first");  // the old one is intact until the commit
        out.commit();
    }
    EXPECT_FALSE(fs::exists(target / "a.txt"));
    EXPECT_EQ(slurp(target / "b.txt"), "second");
    {
        AtomicDirectory abandoned(target);  // no commit: removed, the target kept
        std::ofstream(abandoned.path() / "c.txt") << "never";
    }
    EXPECT_EQ(slurp(target / "b.txt"), "second");
    EXPECT_EQ(temporaries_in(d), 0u);
    fs::remove_all(d);
}

// What the CLI's signal thread does: every temporary of the process goes, the finished outputs
// stay, and nothing is committed afterwards. In a child process: the registry stays closed for
// good once it has run.
TEST(AtomicFile, RemovePendingOutputsRemovesEveryTemporaryAndStopsCommits) {
    const test::TempDir d("atomic_pending");
    write_atomically(d / "done.ply", "finished");
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        int failures = 0;
        auto expect = [&failures](bool ok) { failures += !ok; };
        AtomicFile open_file(d / "half.ply");
        open_file.stream() << "half";
        AtomicDirectory open_dir(d / "seq");
        std::ofstream(open_dir.path() / "x.bin") << "x";
        expect(temporaries_in(d) == 2);
        expect(remove_pending_outputs() == 2);
        expect(temporaries_in(d) == 0);
        auto throws_io = [](auto&& f) {
            try {
                f();
            } catch (const IoError&) {
                return true;
            }
            return false;
        };
        expect(throws_io([&] { open_file.commit(); }));
        expect(throws_io([&] { open_dir.commit(); }));
        expect(throws_io([&] { AtomicFile later(d / "later.ply"); }));
        ::_exit(failures);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "failed checks in the child";
    EXPECT_EQ(temporaries_in(d), 0u);
    EXPECT_FALSE(fs::exists(d / "half.ply"));
    EXPECT_FALSE(fs::exists(d / "seq"));
    EXPECT_FALSE(fs::exists(d / "later.ply"));
    EXPECT_EQ(slurp(d / "done.ply"), "finished");
    fs::remove_all(d);
}

}  // namespace

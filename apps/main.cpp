// lidarsurf command-line tool. The only place where library exceptions become messages and
// exit codes: 0 success, 1 internal error, 2 bad arguments, 3 bad input data, 4 file system error,
// 5 over the memory budget (--max-memory-mb).
#include <cstdio>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "allocator_tuning.hpp"
#include "cli_common.hpp"
#include "commands.hpp"
#include "interrupt.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/version.hpp"

using namespace lidarsurf;

using namespace lidarsurf::cli;

// A message as the terminal should show it: bytes that a file or an argument put into it and that
// a terminal would act on (escape sequences, carriage returns, other control bytes) are printed
// as \xNN.
std::string printable(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (u < 0x20 || u == 0x7f) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", u);
            out += buf;
        } else {
            out += c;
        }
    }
    return out;
}

int fail(const char* kind, std::string_view message, int code) {
    if (interrupted()) wait_for_exit();  // the signal thread removed the outputs and ends the process
    std::fprintf(stderr, "lidarsurf: %s: %s\n", kind, printable(message).c_str());
    return code;
}

int main(int argc, char** argv) {
    handle_interrupts();  // before any other thread exists
    // Frame after frame (fuse, bench): freed memory kept for reuse, the heap in huge pages
    // (allocator_tuning.hpp; the library itself never changes the process's allocator).
    const AllocatorTuning allocator = tune_allocator();
    CLI::App app{"lidarsurf " LIDARSURF_VERSION_STRING " - surface reconstruction from lidar scans (Roldao et al., ITSC 2019)"};
    app.require_subcommand(1);
    app.set_version_flag("--version", LIDARSURF_VERSION_STRING);

    ReconstructCommandOptions ro;
    auto* rc = add_reconstruct_command(app, ro);
    EvaluateOptions eo;
    auto* ev = add_evaluate_command(app, eo);
    SimulateOptions so;
    auto* sc = add_simulate_command(app, so);
    RenderOptions rdo;
    auto* rd = add_render_command(app, rdo);
    BenchmarkOptions bo;
    auto* bm = add_benchmark_command(app, bo);
    BenchOptions bno;
    auto* bn = add_bench_command(app, bno);
    FuseOptions fo;
    auto* fu = add_fuse_command(app, fo);
    ViewOptions vo;
    auto* vw = add_view_command(app, vo);
    MapBenchmarkOptions mo;
    auto* mb = add_map_benchmark_command(app, mo);
    InfoOptions io;
    auto* in = add_info_command(app, io);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    try {
        if (*rc) return run_reconstruct(ro);
        if (*ev) return run_evaluate(eo);
        if (*sc) return run_simulate(so);
        if (*rd) return run_render(rdo);
        if (*bm) return run_benchmark(bo);
        if (*bn) {
            bno.allocator = allocator.describe();
            return run_bench(bno);
        }
        if (*fu) return run_fuse(fo);
        if (*vw) return run_view(vo);
        if (*mb) return run_map_benchmark(mo);
        if (*in) return run_info(io);
    } catch (const Error& e) {
        return fail("error", e.what(), exit_code(e));
    } catch (const std::bad_alloc&) {
        return fail("error", "out of memory: the system refused an allocation; use a larger voxel size, split the input, or set --max-memory-mb", 5);
    } catch (const std::length_error& e) {
        return fail("error", std::string("out of memory: a size beyond what can be allocated (") + e.what() + ")", 5);
    } catch (const std::exception& e) {
        return fail("internal error", e.what(), 1);
    }
    return 1;
}

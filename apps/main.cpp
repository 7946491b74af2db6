// lidarsurf command-line tool. The only place where library exceptions become messages and
// exit codes: 0 success, 1 internal error, 2 bad arguments, 3 bad input data, 4 file system error,
// 5 over the memory budget (--max-memory-mb).
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.hpp"
#include "allocator_tuning.hpp"
#include "commands.hpp"
#include "file_roles.hpp"
#include "interrupt.hpp"

#include "lidarsurf/baselines/imls.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/holdout.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/eval/report.hpp"
#include "lidarsurf/eval/ring_holdout.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/io/point_writer.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/version.hpp"

namespace fs = std::filesystem;
using namespace lidarsurf;

namespace {

using namespace lidarsurf::cli;


int run_reconstruct(const std::string& input, const std::string& output, const std::string& mesh_format_name,
                    const ReconstructOptions& o) {
    const Method m = resolve_method(o);
    FileRoles files;
    files.input(input);
    files.output(output, "-o");
    files.check();
    const MeshFormat mesh_format = mesh_format_for(output, parse_mesh_format(mesh_format_name));  // .stl: exit 2 now

    auto t0 = std::chrono::steady_clock::now();
    const PointCloud cloud = read_points(input, m.read);
    const double read_ms = ms_since(t0);
    std::string summary;
    const Mesh mesh = run_method(m, cloud, summary);
    t0 = std::chrono::steady_clock::now();
    write_mesh(mesh, output, mesh_format);
    std::fprintf(report_stream(output), "%s: %s; %s; read %.1f ms, write %.1f ms -> %s\n", input.c_str(), method_name(m).c_str(), summary.c_str(), read_ms,
                ms_since(t0), output.c_str());
    return 0;
}

struct EvaluateOptions {
    std::vector<std::string> inputs;
    std::string json, mesh_out, gt_format = "auto";
    int gt_bin_fields = 4;
    double holdout = 0, gt_spacing = 0.02;
    bool holdout_rings = false;
    std::string ring_field = "auto";
    std::uint64_t seed = 1;
    EvaluationConfig eval;
    RingHoldoutConfig rings;
    bool max_range_given = false;
    std::string ring_option;  // --ring-field or --range-bin when given: they need --holdout-rings
    bool json_given = false, mesh_out_given = false;  // an option given with an empty name is an error
};


// Ground truth as points: a point file, or a mesh (.obj, or .ply with faces) sampled densely.
std::vector<Eigen::Vector3d> read_ground_truth(const std::string& path, const EvaluateOptions& o) {
    const std::string ext = extension_of(path);
    if (o.gt_format == "auto" && (ext == ".obj" || ext == ".ply")) {
        Mesh gt = read_mesh(path);
        if (!gt.triangles.empty()) return sample_surface(gt, o.gt_spacing, 20'000'000, o.seed);
        return std::move(gt.vertices);
    }
    PointReadOptions read;
    read.format = parse_point_format(o.gt_format);
    read.bin_fields = o.gt_bin_fields;
    PointCloud cloud = read_points(path, read);
    const std::size_t dropped = drop_non_finite(cloud);
    if (dropped) std::fprintf(stderr, "lidarsurf: %zu non-finite ground-truth points dropped\n", dropped);
    return std::move(cloud.points);
}

// --ring-field: "auto" (the fifth value of 5-value .bin records, where nuScenes stores the ring;
// the point order otherwise), "order", or the index of the value in .bin records.
int ring_field_of(const std::string& name, const std::string& path, const PointReadOptions& read) {
    if (name == "order") return -1;
    if (name == "auto") {
        const bool bin = read.format == PointFormat::KittiBin || (read.format == PointFormat::Auto && extension_of(path) == ".bin");
        return bin && read.bin_fields == 5 ? 4 : -1;
    }
    int index = -1;
    const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), index);
    if (ec != std::errc{} || end != name.data() + name.size())
        throw InvalidArgument("--ring-field must be auto, order or the index of a .bin value (got '" + name + "')");
    return index;
}

// The ring hold-out (eval/ring_holdout.hpp): the even rings are reconstructed with the
// reconstruct options, the odd rings within --max-range (default 30 m) are measured.
int run_ring_holdout(EvaluateOptions& o, const ReconstructOptions& ro) {
    if (o.inputs.size() != 1) throw InvalidArgument("evaluate --holdout-rings takes one scan (got " + std::to_string(o.inputs.size()) + " inputs)");
    Method m = resolve_method(ro);
    RingHoldoutConfig& rc = o.rings;
    rc.origin = m.sensor;
    rc.threads = m.config.threads;
    if (o.max_range_given) rc.max_range = o.eval.max_range;
    rc.validate();
    m.read.ring_field = ring_field_of(o.ring_field, o.inputs[0], m.read);
    PointCloud cloud = read_points(o.inputs[0], m.read);
    const std::size_t dropped = drop_non_finite(cloud);
    std::string summary;
    const RingHoldoutResult r = ring_holdout(cloud, [&](const PointCloud& even) { return run_method(m, even, summary); }, rc);
    std::printf("%s: %s; ring hold-out: %zu rings (%s), %zu points of even rings reconstructed, %zu of odd rings held out, "
                "%zu non-finite dropped\n  %s\n  mesh: %zu triangles\n%s",
                o.inputs[0].c_str(), method_name(m).c_str(), r.rings, m.read.ring_field >= 0 ? "ring field" : "point order", r.reconstructed,
                r.held_out, dropped, summary.c_str(), r.mesh_triangles, format_table(r).c_str());
    if (o.json_given) write_text(o.json, to_json(r));
    return 0;
}

int run_evaluate(EvaluateOptions& o, const ReconstructOptions& ro) {
    EvaluationConfig& ec = o.eval;
    ec.seed = o.seed;
    if (!std::isfinite(o.gt_spacing) || o.gt_spacing <= 0) throw InvalidArgument("--gt-spacing must be finite and > 0");
    FileRoles files;
    for (const std::string& in : o.inputs) files.input(in);
    if (o.json_given) files.output(o.json, "--json");
    if (o.mesh_out_given) files.output(o.mesh_out, "--mesh-out");
    files.check();
    if (o.mesh_out_given) mesh_format_for(o.mesh_out);  // an unknown extension: exit 2 now
    if (!o.holdout_rings && !o.ring_option.empty()) throw InvalidArgument(o.ring_option + " is for --holdout-rings");
    if (o.mesh_out_given && o.holdout == 0 && !o.holdout_rings)
        throw InvalidArgument("--mesh-out writes the mesh of the kept points of --holdout; evaluate MESH GT makes no mesh");
    if (o.holdout_rings) {
        if (o.holdout != 0) throw InvalidArgument("give --holdout or --holdout-rings, not both");
        if (o.mesh_out_given) throw InvalidArgument("--mesh-out is for --holdout");
        return run_ring_holdout(o, ro);
    }
    Mesh mesh;
    std::vector<Eigen::Vector3d> gt;
    std::string header;
    if (o.holdout != 0) {
        if (o.inputs.size() != 1) throw InvalidArgument("evaluate --holdout takes one scan (got " + std::to_string(o.inputs.size()) + " inputs)");
        const Method m = resolve_method(ro);
        ec.origin = m.sensor;
        ec.threads = m.config.threads;
        ec.validate();
        PointCloud cloud = read_points(o.inputs[0], m.read);
        const std::size_t dropped = drop_non_finite(cloud);
        const HoldoutSplit split = split_holdout(cloud, o.holdout, o.seed);
        std::string summary;
        mesh = run_method(m, split.kept, summary);
        gt = split.held_out.points;
        char buf[256];
        std::snprintf(buf, sizeof buf, "hold-out %.3g (seed %llu): %zu points reconstructed, %zu held out, %zu non-finite dropped",
                      o.holdout, static_cast<unsigned long long>(o.seed), split.kept.points.size(), gt.size(), dropped);
        header = o.inputs[0] + ": " + method_name(m) + "; " + buf + "\n  " + summary + "\n";
        if (o.mesh_out_given) write_mesh(mesh, o.mesh_out);
    } else {
        if (o.inputs.size() != 2)
            throw InvalidArgument("evaluate takes MESH GT (or --holdout FRACTION SCAN); got " + std::to_string(o.inputs.size()) + " input(s)");
        ec.origin = parse_vec3(ro.origin, "--origin");
        ec.threads = ro.config.threads;
        ec.validate();
        mesh = read_mesh(o.inputs[0]);
        gt = read_ground_truth(o.inputs[1], o);
        header = o.inputs[0] + " against " + o.inputs[1] + "\n";
    }
    const EvaluationResult result = evaluate(mesh, gt, ec);
    std::printf("%s%s", header.c_str(), format_table(result).c_str());
    if (o.json_given) write_text(o.json, to_json(result));
    return 0;
}

}  // namespace

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

    ReconstructOptions ro;
    std::string input, output, mesh_format = "auto";
    auto* rc = app.add_subcommand("reconstruct", "Reconstruct a triangle mesh from one lidar scan");
    rc->footer(
        "Examples:\n"
        "  lidarsurf reconstruct 000000.bin -o mesh.ply\n"
        "  lidarsurf reconstruct scan.pcd -o mesh.obj --mode cn --k 3 --origin 0,0,1.73\n"
        "  lidarsurf reconstruct sweep.bin --bin-fields 5 -o mesh.ply --voxel-size 0.1 --threads 2\n"
        "  lidarsurf reconstruct 000000.bin -o imls.ply --method imls\n");
    rc->add_option("input", input, "Input point cloud (.bin KITTI, .ply, .pcd, .xyz/.csv/.txt)")->required();
    rc->add_option("-o,--output", output, "Output mesh (.ply binary by default, .obj)")->required();
    rc->add_option("--mesh-format", mesh_format, "Output format: auto | ply | ply-ascii | obj")->capture_default_str();
    add_reconstruct_options(rc, ro);

    EvaluateOptions eo;
    auto* ev = app.add_subcommand("evaluate", "Measure a mesh against ground truth, or a method on a scan by hold-out");
    ev->footer(
        "Examples:\n"
        "  lidarsurf evaluate mesh.ply gt.bin --origin 0,0,0 --max-range 50 --json metrics.json\n"
        "  lidarsurf evaluate mesh.ply scene.obj          (a ground-truth mesh is sampled)\n"
        "  lidarsurf evaluate --holdout 0.5 000000.bin --seed 7 --method imls\n"
        "  lidarsurf evaluate --holdout-rings 000000.bin\n"
        "  lidarsurf evaluate --holdout-rings sweep.bin --bin-fields 5       (nuScenes: the 5th value is the ring)\n"
        "With --holdout the scan is split at random, one part is reconstructed with the reconstruct\n"
        "options and the held-out part is the ground truth. With --holdout-rings the even rings are\n"
        "reconstructed and the odd-ring points within --max-range (default 30 m) are measured against\n"
        "the mesh (docs/evaluation.md).\n");
    ev->add_option("inputs", eo.inputs, "MESH GT, or SCAN with --holdout or --holdout-rings")->required()->expected(1, 2);
    ev->add_option("--holdout", eo.holdout, "Hold out this fraction of SCAN as ground truth, in (0, 1)");
    ev->add_flag("--holdout-rings", eo.holdout_rings, "Reconstruct SCAN's even rings, measure its odd-ring points against the mesh");
    ev->add_option("--ring-field", eo.ring_field,
                   "With --holdout-rings: where the rings come from: auto (the 5th value of --bin-fields 5 records, else the "
                   "point order), order (a ring ends where the azimuth restarts, KITTI), or the index of the .bin value")
        ->capture_default_str()
        ->each([&eo](const std::string&) { eo.ring_option = "--ring-field"; });
    ev->add_option("--range-bin", eo.rings.range_bin, "With --holdout-rings: width of the range bins, metres")
        ->capture_default_str()
        ->each([&eo](const std::string&) { eo.ring_option = "--range-bin"; });
    ev->add_option("--seed", eo.seed, "Seed of the hold-out split and of the surface sampling")->capture_default_str();
    ev->add_option("--max-range", eo.eval.max_range, "Evaluate only within this range of --origin (0 = all; --holdout-rings: 30)")
        ->capture_default_str()
        ->each([&eo](const std::string&) { eo.max_range_given = true; });
    ev->add_option("--threshold", eo.eval.threshold, "Precision/recall/F-score threshold, metres")->capture_default_str();
    ev->add_option("--delta", eo.eval.delta, "Report the share of vertices within delta of GT (Fig. 6b)")->capture_default_str();
    ev->add_option("--sample-spacing", eo.eval.sample_spacing, "Mean spacing of the points sampled on the mesh, metres")->capture_default_str();
    ev->add_option("--gt-spacing", eo.gt_spacing, "Sample spacing of a ground-truth mesh, metres")->capture_default_str();
    ev->add_option("--gt-format", eo.gt_format, "Ground-truth format: auto | bin | ply | pcd | xyz")->capture_default_str();
    ev->add_option("--gt-bin-fields", eo.gt_bin_fields, "float32 values per point in a .bin ground truth")->capture_default_str();
    ev->add_option("--json", eo.json, "Also write the metrics as JSON to this file")->each([&eo](const std::string&) { eo.json_given = true; });
    ev->add_option("--mesh-out", eo.mesh_out, "With --holdout: write the reconstructed mesh here")->each([&eo](const std::string&) {
        eo.mesh_out_given = true;
    });
    add_reconstruct_options(ev, ro);

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

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    try {
        if (*rc) return run_reconstruct(input, output, mesh_format, ro);
        if (*ev) return run_evaluate(eo, ro);
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

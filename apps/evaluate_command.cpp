// lidarsurf evaluate: a mesh against ground truth (points, or a mesh sampled), or a method on a
// scan by hold-out: random (--holdout) or the odd rings (--holdout-rings, eval/ring_holdout.hpp).
#include <charconv>
#include <cmath>
#include <cstdio>

#include "commands.hpp"
#include "file_roles.hpp"
#include "lidarsurf/eval/holdout.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/eval/report.hpp"
#include "lidarsurf/eval/ring_holdout.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"

namespace lidarsurf::cli {

CLI::App* add_evaluate_command(CLI::App& app, EvaluateOptions& o) {
    CLI::App* ev = app.add_subcommand("evaluate", "Measure a mesh against ground truth, or a method on a scan by hold-out");
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
    ev->add_option("inputs", o.inputs, "MESH GT, or SCAN with --holdout or --holdout-rings")->required()->expected(1, 2);
    ev->add_option("--holdout", o.holdout, "Hold out this fraction of SCAN as ground truth, in (0, 1)");
    ev->add_flag("--holdout-rings", o.holdout_rings, "Reconstruct SCAN's even rings, measure its odd-ring points against the mesh");
    ev->add_option("--ring-field", o.ring_field,
                   "With --holdout-rings: where the rings come from: auto (the 5th value of --bin-fields 5 records, else the "
                   "point order), order (a ring ends where the azimuth restarts, KITTI), or the index of the .bin value")
        ->capture_default_str()
        ->each([&o](const std::string&) { o.ring_option = "--ring-field"; });
    ev->add_option("--range-bin", o.rings.range_bin, "With --holdout-rings: width of the range bins, metres")
        ->capture_default_str()
        ->each([&o](const std::string&) { o.ring_option = "--range-bin"; });
    ev->add_option("--seed", o.seed, "Seed of the hold-out split and of the surface sampling")->capture_default_str();
    ev->add_option("--max-range", o.eval.max_range, "Evaluate only within this range of --origin (0 = all; --holdout-rings: 30)")
        ->capture_default_str()
        ->each([&o](const std::string&) { o.max_range_given = true; });
    ev->add_option("--threshold", o.eval.threshold, "Precision/recall/F-score threshold, metres")->capture_default_str();
    ev->add_option("--delta", o.eval.delta, "Report the share of vertices within delta of GT (Fig. 6b)")->capture_default_str();
    ev->add_option("--sample-spacing", o.eval.sample_spacing, "Mean spacing of the points sampled on the mesh, metres")->capture_default_str();
    ev->add_option("--gt-spacing", o.gt_spacing, "Sample spacing of a ground-truth mesh, metres")->capture_default_str();
    ev->add_option("--gt-format", o.gt_format, "Ground-truth format: auto | bin | ply | pcd | xyz")->capture_default_str();
    ev->add_option("--gt-bin-fields", o.gt_bin_fields, "float32 values per point in a .bin ground truth")->capture_default_str();
    ev->add_option("--json", o.json, "Also write the metrics as JSON to this file")->each([&o](const std::string&) { o.json_given = true; });
    ev->add_option("--mesh-out", o.mesh_out, "With --holdout: write the reconstructed mesh here")->each([&o](const std::string&) {
        o.mesh_out_given = true;
    });
    add_reconstruct_options(ev, o.reconstruct);

    return ev;
}

namespace {

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
int run_ring_holdout(EvaluateOptions& o) {
    if (o.inputs.size() != 1) throw InvalidArgument("evaluate --holdout-rings takes one scan (got " + std::to_string(o.inputs.size()) + " inputs)");
    Method m = resolve_method(o.reconstruct);
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

}  // namespace

int run_evaluate(EvaluateOptions o) {
    const ReconstructOptions& ro = o.reconstruct;
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
        return run_ring_holdout(o);
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


}  // namespace lidarsurf::cli

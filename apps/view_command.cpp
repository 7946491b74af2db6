// lidarsurf view: one self-contained HTML file that shows a mesh in any browser, offline: the
// mesh and optionally the input points as base64 arrays in the page, three.js and the viewer's
// script inlined (viewer/, embedded at build time by cmake/embed_viewer.cmake).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "file_roles.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/io/recording.hpp"
#include "viewer_page.hpp"

namespace fs = std::filesystem;

namespace lidarsurf::cli {
namespace {

std::string base64(const void* data, std::size_t bytes) {
    static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const auto* in = static_cast<const unsigned char*>(data);
    std::string out;
    out.reserve((bytes + 2) / 3 * 4);
    for (std::size_t i = 0; i < bytes; i += 3) {
        const unsigned a = in[i], b = i + 1 < bytes ? in[i + 1] : 0u, c = i + 2 < bytes ? in[i + 2] : 0u;
        const unsigned triple = (a << 16) | (b << 8) | c;
        out += kDigits[(triple >> 18) & 63];
        out += kDigits[(triple >> 12) & 63];
        out += i + 1 < bytes ? kDigits[(triple >> 6) & 63] : '=';
        out += i + 2 < bytes ? kDigits[triple & 63] : '=';
    }
    return out;
}

template <typename T>
std::string base64(const std::vector<T>& v) {
    return base64(v.data(), v.size() * sizeof(T));
}

}  // namespace

CLI::App* add_view_command(CLI::App& app, ViewOptions& o) {
    auto* v = app.add_subcommand("view", "Write a mesh as one self-contained HTML file that opens offline in any browser");
    v->footer(
        "Examples:\n"
        "  lidarsurf view mesh.ply                               (writes mesh.html)\n"
        "  lidarsurf view mesh.ply -o scan.html --points scan.bin --colour level\n"
        "In the page: orbit with the left button, pan with the right one (or shift), zoom with the wheel;\n"
        "the panel colours by height, neighbourhood level k', confidence (magenta: below tau, inferred surface),\n"
        "intensity (grey over its 2nd-98th percentiles) or normal, and toggles the wireframe and\n"
        "the input points. The URL's hash sets them too: mesh.html#colour=level&wireframe=1&points=1.\n");
    v->add_option("input", o.input, "Mesh (.ply, .obj)")->required();
    v->add_option("-o,--output", o.output, "Output page (.html; default: the mesh's name with .html)");
    v->add_option("--points", o.points, "Also show these points (any format or recording reconstruct reads; the mesh's frame)");
    v->add_option("--max-points", o.max_points, "Show at most this many of them (every n-th)")->capture_default_str();
    v->add_option("--scan,--message", o.points_scan, "With --points REC (a recording): its scan to show, from 0")->capture_default_str()->check(CLI::NonNegativeNumber);
    add_recording_options(v, o.recording);
    v->add_option("--colour,--color", o.colour, "Colouring when the page opens: height | level | confidence | intensity | normal | grey")
        ->capture_default_str();
    v->add_option("--title", o.title, "Title of the page (default: the mesh's file name)");
    o.tau = ReconstructionConfig{}.tau;
    v->add_option("--tau", o.tau,
                  "The tau the mesh was made with: colouring by confidence shows the vertices below it (inferred surface: bridges "
                  "between scan rings) in magenta")
        ->capture_default_str();
    return v;
}

int run_view(const ViewOptions& o) {
    require_viewer();
    if (o.colour != "height" && o.colour != "level" && o.colour != "confidence" && o.colour != "intensity" && o.colour != "normal" &&
        o.colour != "grey")
        throw InvalidArgument("--colour must be height, level, confidence, intensity, normal or grey (got '" + o.colour + "')");
    if (o.max_points < 1) throw InvalidArgument("--max-points must be >= 1");
    if (!std::isfinite(o.tau) || o.tau <= 0) throw InvalidArgument("--tau must be finite and > 0");
    const fs::path output = o.output.empty() ? fs::path(o.input).replace_extension(".html") : fs::path(o.output);
    const std::string ext = extension_of(output);
    if (ext != ".html" && ext != ".htm") throw InvalidArgument("view writes an HTML page: give -o a .html file (got '" + output.string() + "')");
    FileRoles files;
    files.input(o.input);
    if (!o.points.empty()) files.input(o.points);
    files.output(output, "-o");
    files.check();

    const Mesh mesh = read_mesh(o.input);
    if (mesh.triangles.empty()) throw InvalidInput(o.input + ": the mesh has no triangle to show");
    // Positions in float32 about the bounding box's centre: a UTM-sized offset would eat the
    // float's digits.
    Eigen::Vector3d lo = mesh.vertices.front(), hi = lo;
    for (const auto& p : mesh.vertices) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    std::vector<float> positions;
    positions.reserve(3 * mesh.vertices.size());
    for (const auto& p : mesh.vertices)
        for (int a = 0; a < 3; ++a) positions.push_back(static_cast<float>(p[a] - centre[a]));
    std::vector<std::uint32_t> indices;
    indices.reserve(3 * mesh.triangles.size());
    for (const auto& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());
    std::vector<float> cloud;
    std::size_t shown = 0;
    if (!o.points.empty()) {
        PointCloud pts = is_recording(o.points) ? read_recorded_scan(o.points, static_cast<std::size_t>(o.points_scan), recording_options(o.recording)).cloud
                                                : read_points(o.points);
        drop_non_finite(pts);
        const std::size_t step = std::max<std::size_t>(1, (pts.points.size() + static_cast<std::size_t>(o.max_points) - 1) /
                                                              static_cast<std::size_t>(o.max_points));
        for (std::size_t i = 0; i < pts.points.size(); i += step, ++shown)
            for (int a = 0; a < 3; ++a) cloud.push_back(static_cast<float>(pts.points[i][a] - centre[a]));
    }
    const std::string title = o.title.empty() ? fs::path(o.input).filename().string() : o.title;
    nlohmann::json data;
    data["title"] = title;
    data["colour"] = o.colour;
    data["centre"] = {centre.x(), centre.y(), centre.z()};
    data["vertices"] = base64(positions);
    data["triangles"] = base64(indices);
    data["levels"] = mesh.levels.size() == mesh.vertices.size() ? base64(mesh.levels) : "";
    data["confidence"] = mesh.confidence.size() == mesh.vertices.size() ? base64(mesh.confidence) : "";
    data["intensity"] = mesh.intensity.size() == mesh.vertices.size() ? base64(mesh.intensity) : "";
    data["tau"] = o.tau;
    data["points"] = base64(cloud);
    const std::string page = viewer_page(data);
    write_text(output.string(), page);
    std::printf("view: %zu vertices, %zu triangles%s -> %s (%.1f MB, opens offline in a browser)\n", mesh.vertices.size(),
                mesh.triangles.size(), shown ? (", " + std::to_string(shown) + " points").c_str() : "", output.c_str(),
                static_cast<double>(page.size()) / 1e6);
    return 0;
}

}  // namespace lidarsurf::cli

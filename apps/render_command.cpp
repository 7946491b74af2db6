// lidarsurf render: a PNG picture of a mesh (Embree ray casting, perspective camera).
#include <cstdio>

#include "commands.hpp"
#include "file_roles.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/viz/png_writer.hpp"
#include "lidarsurf/viz/render.hpp"

namespace lidarsurf::cli {

CLI::App* add_render_command(CLI::App& app, RenderOptions& o) {
    auto* r = app.add_subcommand("render", "Render a mesh to a PNG picture");
    r->footer(
        "Examples:\n"
        "  lidarsurf render mesh.ply -o mesh.png\n"
        "  lidarsurf render mesh.ply -o levels.png --colour level --eye -20,-15,12 --target 5,0,-1\n");
    r->add_option("input", o.input, "Mesh (.ply, .obj)")->required();
    r->add_option("-o,--output", o.output, "Output picture (.png)")->required();
    r->add_option("--colour,--color", o.colour, "height | level (k', meshes from reconstruct) | intensity (meshes of points with one) | grey")->capture_default_str();
    r->add_option("--width", o.width, "Width in pixels")->capture_default_str();
    r->add_option("--height", o.height, "Height in pixels")->capture_default_str();
    r->add_option("--eye", o.eye, "Camera position x,y,z (default: above and behind the mesh's median)");
    r->add_option("--target", o.target, "Point looked at x,y,z (default: the mesh's median vertex)");
    r->add_option("--fov", o.fov, "Horizontal field of view, degrees")->capture_default_str();
    return r;
}

int run_render(const RenderOptions& o) {
    viz::RenderConfig cfg;
    cfg.width = o.width;
    cfg.height = o.height;
    cfg.fov_deg = o.fov;
    cfg.colouring = viz::parse_colouring(o.colour);
    if (!o.eye.empty()) cfg.eye = parse_vec3(o.eye, "--eye");
    if (!o.target.empty()) cfg.target = parse_vec3(o.target, "--target");
    cfg.validate();
    if (extension_of(o.output) != ".png") throw InvalidArgument("render writes PNG: give -o a .png file");
    FileRoles files;
    files.input(o.input);
    files.output(o.output, "-o");
    files.check();
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh mesh = read_mesh(o.input);
    const Image img = viz::render(mesh, cfg);
    write_png(img, o.output);
    std::printf("rendered %zu triangles at %dx%d in %.0f ms -> %s\n", mesh.triangles.size(), img.width, img.height, ms_since(t0),
                o.output.c_str());
    return 0;
}

}  // namespace lidarsurf::cli

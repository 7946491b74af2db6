// pybind11 bindings of lidarsurf: numpy in, numpy out, the C++ ReconstructionConfig bound as
// lidarsurf.Config (defaults defined once, in C++). The GIL is released while C++ runs; library
// exceptions become ValueError (bad parameters or data) or OSError (files).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <span>
#include <sstream>

#include "lidarsurf/baselines/imls.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/eval/report.hpp"
#include "lidarsurf/eval/ring_holdout.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/viz/live_stream.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/version.hpp"
#include "numpy_views.hpp"

namespace py = pybind11;
using namespace lidarsurf;

namespace lidarsurf {
void bind_tiles(py::module_& m);   // tiles.cpp
void bind_config(py::module_& m);  // config.cpp
namespace python {
void bind_mesh(py::module_& m);           // mesh.cpp
void bind_reconstructor(py::module_& m);  // reconstructor.cpp
void bind_recording(py::module_& m);      // recording.cpp
}  // namespace python
}  // namespace lidarsurf

namespace {

using namespace lidarsurf::python;

// The method `reconstruct` and `ring_holdout` run: config (or the defaults) and the method's name
// as the CLI's --method takes it, validated.
MethodConfig method_of(std::optional<ReconstructionConfig> config, const std::optional<std::string>& method) {
    MethodConfig m;
    m.config = config.value_or(ReconstructionConfig{});
    m.imls = method && *method == "imls";
    if (method && *method == "paper") m.config.make_paper_literal();  // the paper as written, in config's mode
    else if (method && !m.imls && *method != "default") m.config.mode = parse_mode(*method);  // InvalidArgument names the choices
    m.config.validate();
    m.imls_config = ImlsConfig::matching(m.config, m.config.threads);
    m.validate();
    return m;
}

Mesh reconstruct_py(const py::handle& points, const std::vector<double>& origin, std::optional<ReconstructionConfig> config,
                    std::optional<std::string> method) {
    const PointArray view = points_view(points, "points");
    const Eigen::Vector3d sensor = as_vec3(origin, "origin");
    const MethodConfig m = method_of(std::move(config), method);
    py::gil_scoped_release release;
    return reconstruct_with(m, as_span(view), sensor);  // the array read in place
}

// Ring numbers from Python: None, or a 1-D array of whole numbers in [0, kMaxRing], one per point.
std::vector<std::uint16_t> rings_of(const py::handle& rings, std::size_t points) {
    if (rings.is_none()) return {};
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(rings);
    if (!a || a.ndim() != 1) throw InvalidArgument("rings must be a 1-D array of ring numbers");
    if (static_cast<std::size_t>(a.shape(0)) != points)
        throw InvalidArgument("rings has " + std::to_string(a.shape(0)) + " entries for " + std::to_string(points) + " points");
    std::vector<std::uint16_t> out(points);
    for (std::size_t i = 0; i < points; ++i) {
        const std::optional<std::uint16_t> ring = ring_number(a.data()[i]);
        if (!ring) throw InvalidArgument("rings must be whole numbers in [0, " + std::to_string(kMaxRing) + "]");
        out[i] = *ring;
    }
    return out;
}

PointCloud cloud_of(const py::handle& points) {
    const PointArray view = points_view(points, "points");
    const auto span = as_span(view);
    PointCloud cloud;
    cloud.points.assign(span.begin(), span.end());
    return cloud;
}

py::array_t<std::uint16_t> rings_to_numpy(const std::vector<std::uint16_t>& rings) {
    py::array_t<std::uint16_t> out(static_cast<py::ssize_t>(rings.size()));
    std::copy(rings.begin(), rings.end(), out.mutable_data());
    return out;
}

}  // namespace

PYBIND11_MODULE(_lidarsurf, m) {
    m.doc() = "lidarsurf: surface reconstruction from lidar scans (Roldao et al., ITSC 2019).";
    m.attr("__version__") = LIDARSURF_VERSION_STRING;

    // Exceptions: bad parameters or data -> ValueError, files -> OSError, over the memory budget
    // -> MemoryError, with the C++ message.
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const IoError& e) {
            PyErr_SetString(PyExc_OSError, e.what());
        } catch (const ResourceLimit& e) {
            PyErr_SetString(PyExc_MemoryError, e.what());
        } catch (const Error& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });

    bind_config(m);

    python::bind_mesh(m);
    python::bind_reconstructor(m);
    python::bind_recording(m);

    m.def("points_view", [](const py::handle& points) { return points_view(points, "points"); }, py::arg("points"),
          "The (N, 3) float64 C-contiguous array reconstruct() reads: the input itself when it already is one (no copy).");

    m.def("reconstruct", &reconstruct_py, py::arg("points"), py::arg("origin") = std::vector<double>{0, 0, 0},
          py::arg("config") = py::none(), py::arg("method") = py::none(),
          "Reconstruct a mesh from an (N, 3) float32/float64 array of points seen from `origin` (the sensor).\n"
          "config: a Config (lidarsurf's defaults when None). method: None or 'default' (config as it is), 'paper' (the\n"
          "paper as written in config's mode, as Config.paper()), a mode name ('an+gc', 'an', 'cn+gc', 'cn') overriding\n"
          "config.mode, or 'imls' for the paper's IMLS baseline with the matching settings. The CLI's --method takes the same names.\n"
          "Raises ValueError on a bad parameter or non-finite points.");

    m.def(
        "read_points",
        [](const std::string& path, const std::string& format, int bin_fields) {
            PointReadOptions o;
            o.format = parse_point_format(format);
            o.bin_fields = bin_fields;
            PointCloud cloud;
            {
                py::gil_scoped_release release;
                cloud = read_points(path, o);
            }
            return points_to_numpy(std::move(cloud.points));
        },
        py::arg("path"), py::arg("format") = "auto", py::arg("bin_fields") = 4,
        "Read a point cloud (KITTI .bin, .ply, .pcd, .xyz/.csv/.txt) as an (N, 3) float64 array. Non-finite points are kept.");

    m.def(
        "read_rings",
        [](const std::string& path, int ring_field, int bin_fields) {
            PointReadOptions o;
            o.format = PointFormat::KittiBin;
            o.bin_fields = bin_fields;
            o.ring_field = ring_field;
            PointCloud cloud;
            {
                py::gil_scoped_release release;
                cloud = read_points(path, o);
            }
            return rings_to_numpy(cloud.rings);
        },
        py::arg("path"), py::arg("ring_field") = 4, py::arg("bin_fields") = 5,
        "The ring of every point of a .bin scan that stores it, as a uint16 array in the order of read_points: value\n"
        "`ring_field` of records of `bin_fields` float32 (nuScenes: 4 of 5). ValueError for a value that is not a whole\n"
        "number in [0, 4095].");
    m.def(
        "rings_from_order",
        [](const py::handle& points) {
            const PointArray view = points_view(points, "points");
            std::vector<std::uint16_t> rings;
            {
                py::gil_scoped_release release;
                rings = rings_from_order(as_span(view));  // the array read in place
            }
            return rings_to_numpy(rings);
        },
        py::arg("points"),
        "The ring of every point of a scan stored ring after ring (KITTI's HDL-64E order), from the point order: a ring\n"
        "ends where the azimuth passes the last point's again or turns back by more than 20 degrees. uint16 array,\n"
        "rings numbered 0, 1, ... in order. ValueError for a scan not stored that way.");
    m.def(
        "_ring_holdout_json",
        [](const py::handle& points, const py::handle& rings, const std::vector<double>& origin, std::optional<ReconstructionConfig> config,
           std::optional<std::string> method, double max_range, double range_bin) {
            PointCloud cloud = cloud_of(points);
            cloud.rings = rings_of(rings, cloud.points.size());
            RingHoldoutConfig c;
            c.origin = as_vec3(origin, "origin");
            c.max_range = max_range;
            c.range_bin = range_bin;
            const MethodConfig chosen = method_of(std::move(config), method);
            c.threads = chosen.config.threads;
            py::gil_scoped_release release;
            return to_json(ring_holdout(cloud, [&](const PointCloud& even) { return reconstruct_with(chosen, even, c.origin); }, c));
        },
        py::arg("points"), py::arg("rings"), py::arg("origin"), py::arg("config"), py::arg("method"), py::arg("max_range"),
        py::arg("range_bin"), "The ring hold-out as JSON text (use lidarsurf.ring_holdout).");

    m.def(
        "read_mesh",
        [](const std::string& path) {
            py::gil_scoped_release release;
            return read_mesh(path);
        },
        py::arg("path"), "Read a triangle mesh (.ply or .obj).");

    m.def(
        "read_poses",
        [](const std::string& path, std::optional<std::string> calib) {
            std::vector<Eigen::Isometry3d> poses;
            {
                py::gil_scoped_release release;
                poses = read_poses(path);
                if (calib) poses = lidar_poses(poses, read_calib_tr(*calib));
            }
            py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
            auto a = out.mutable_unchecked<3>();
            for (std::size_t i = 0; i < poses.size(); ++i)
                for (int r = 0; r < 4; ++r)
                    for (int c = 0; c < 4; ++c) a(static_cast<py::ssize_t>(i), r, c) = poses[i].matrix()(r, c);
            return out;
        },
        py::arg("path"), py::arg("calib") = py::none(),
        "Read a KITTI poses file (one 3x4 row-major pose a line) as an (N, 4, 4) float64 array. With `calib`, a KITTI "
        "calib.txt, the poses (KITTI's published ones are the left camera's) become the lidar's: Tr^-1 P Tr. For "
        "Reconstructor.integrate_from(points @ R.T + t, viewpoint=t).");

    m.def(
        "decode_live_message",
        [](const py::bytes& data) {
            live_stream::Message msg;
            {
                const std::string_view bytes = data;  // the bytes object stays alive while the GIL is released
                py::gil_scoped_release release;
                msg = live_stream::decode({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()});
            }
            py::dict d;
            const std::uint32_t flags = msg.header.flags;
            d["scans"] = msg.header.scans;
            d["reset"] = (flags & live_stream::kReset) != 0;
            d["final"] = (flags & live_stream::kFinal) != 0;
            d["more"] = (flags & live_stream::kMore) != 0;
            d["origin"] = py::make_tuple(msg.header.origin.x(), msg.header.origin.y(), msg.header.origin.z());
            py::array_t<double> pose({py::ssize_t{4}, py::ssize_t{4}});
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) pose.mutable_at(r, c) = msg.header.pose.matrix()(r, c);
            d["pose"] = pose;
            py::array_t<double> trajectory({static_cast<py::ssize_t>(msg.trajectory.size()), py::ssize_t{3}});
            for (std::size_t i = 0; i < msg.trajectory.size(); ++i)
                for (int a = 0; a < 3; ++a) trajectory.mutable_at(static_cast<py::ssize_t>(i), a) = msg.trajectory[i][a];
            d["trajectory"] = trajectory;
            py::list removed, changed;
            for (const VoxelKey& k : msg.removed) removed.append(py::make_tuple(k.x(), k.y(), k.z()));
            for (MeshBlock& b : msg.changed) changed.append(py::make_tuple(py::make_tuple(b.key.x(), b.key.y(), b.key.z()), std::move(b.mesh)));
            d["removed"] = removed;
            d["changed"] = changed;
            return d;
        },
        py::arg("data"),
        "Decode one message of the live view's stream (what `lidarsurf fuse --serve` sends at ws://HOST:PORT/live, one "
        "binary WebSocket message per update; docs/live_view.md) as a dict: 'scans' fused so far; 'reset' (drop every "
        "block first), 'final' (the drive has ended: the blocks now make the final mesh), 'more' (the update goes on in "
        "the next message); 'origin'; 'pose' (4x4, the sensor's, world); 'trajectory' ((N, 3) sensor positions not sent "
        "before); 'removed' [key]; 'changed' [(key, Mesh)], as MeshDelta has them. Raises ValueError for bytes that are "
        "not such a message.");

    m.def(
        "encode_live_message",
        [](std::uint32_t scans, const std::array<double, 3>& origin, const py::array_t<double, py::array::c_style | py::array::forcecast>& pose,
           const py::array_t<double, py::array::c_style | py::array::forcecast>& trajectory, const std::vector<std::array<int, 3>>& removed,
           const std::vector<std::pair<std::array<int, 3>, Mesh>>& changed, bool reset, bool final, bool more) {
            if (pose.ndim() != 2 || pose.shape(0) != 4 || pose.shape(1) != 4) throw InvalidArgument("encode_live_message: pose must be 4x4");
            if (trajectory.size() > 0 && (trajectory.ndim() != 2 || trajectory.shape(1) != 3))
                throw InvalidArgument("encode_live_message: trajectory must be (N, 3)");
            live_stream::Header h;
            h.scans = scans;
            h.flags = (reset ? live_stream::kReset : 0u) | (final ? live_stream::kFinal : 0u) | (more ? live_stream::kMore : 0u);
            h.origin = {origin[0], origin[1], origin[2]};
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 4; ++c) h.pose.matrix()(r, c) = pose.at(r, c);
            std::vector<Eigen::Vector3d> points;
            for (py::ssize_t i = 0; trajectory.size() > 0 && i < trajectory.shape(0); ++i) points.emplace_back(trajectory.at(i, 0), trajectory.at(i, 1), trajectory.at(i, 2));
            std::vector<VoxelKey> keys;
            for (const auto& k : removed) keys.emplace_back(k[0], k[1], k[2]);
            std::vector<std::string> bodies;
            for (const auto& [k, mesh] : changed) {
                mesh.check();
                bodies.push_back(live_stream::encode_block(MeshBlock{VoxelKey(k[0], k[1], k[2]), mesh}, h.origin));
            }
            std::vector<const std::string*> blocks;
            for (const std::string& b : bodies) blocks.push_back(&b);
            return py::bytes(live_stream::encode_message(h, points, keys, blocks));
        },
        py::arg("scans"), py::arg("origin"), py::arg("pose"), py::arg("trajectory"), py::arg("removed"), py::arg("changed"), py::kw_only(),
        py::arg("reset") = false, py::arg("final") = false, py::arg("more") = false,
        "Encode one message of the live view's stream, as `lidarsurf fuse --serve` sends it (docs/live_view.md): what "
        "decode_live_message reads back, for a producer of your own. `origin` (3 floats: the world point positions are "
        "relative to), `pose` (4x4, the sensor's, world), `trajectory` ((N, 3) sensor positions), `removed` [key], "
        "`changed` [(key, Mesh)]. Returns bytes. Raises ValueError for a malformed mesh or a block past 65,535 vertices.");

    m.def(
        "_evaluate_json",
        [](const Mesh& mesh, const py::handle& gt, const std::vector<double>& origin, double max_range, double threshold, double delta,
           std::uint64_t seed) {
            const PointArray view = points_view(gt, "gt_points");
            EvaluationConfig c;
            c.origin = as_vec3(origin, "origin");
            c.max_range = max_range;
            c.threshold = threshold;
            c.delta = delta;
            c.seed = seed;
            const auto span = as_span(view);
            const std::vector<Eigen::Vector3d> pts(span.begin(), span.end());
            py::gil_scoped_release release;
            return to_json(evaluate(mesh, pts, c));
        },
        py::arg("mesh"), py::arg("gt_points"), py::arg("origin"), py::arg("max_range"), py::arg("threshold"), py::arg("delta"),
        py::arg("seed"), "Metrics of `mesh` against `gt_points` as JSON text (use lidarsurf.evaluate).");

    m.def(
        "simd_level", [] { return std::string(to_string(simd_level())); },
        "The vector instructions the fast path uses: 'sse2', 'avx2' or 'avx512' (the widest this CPU has, unless\n"
        "set_simd_level lowered it), or 'portable' in a build without SIMD. Every level gives the same mesh, bit for bit.");
    m.def(
        "simd_levels",
        [] {
            std::vector<std::string> out;
            for (SimdLevel level : available_simd_levels()) out.emplace_back(to_string(level));
            return out;
        },
        "The levels this build and CPU can run, narrowest first (set_simd_level takes any of them).");
    m.def(
        "set_simd_level", [](const std::string& level) { set_simd_level(simd_level_from_string(level.c_str())); }, py::arg("level"),
        "Use the vector instructions `level` ('sse2', 'avx2', 'avx512') from now on, in every thread: to compare speeds, or to\n"
        "check that a level gives the same mesh. ValueError for a level this build or CPU lacks. Not while a reconstruction runs.");
    m.def(
        "simulate",
        [](const std::string& scene, std::uint64_t seed, bool ground_truth) {
            if (scene != "demo") throw InvalidArgument("unknown scene '" + scene + "' (available: demo)");
            PointCloud cloud;
            {
                py::gil_scoped_release release;
                cloud = sim::simulate_scan(sim::AnalyticScene::demo(),
                                           ground_truth ? sim::SensorModel::ground_truth() : sim::SensorModel::hdl64(),
                                           Eigen::Vector3d::Zero(), seed);
            }
            return points_to_numpy(std::move(cloud.points));
        },
        py::arg("scene") = "demo", py::arg("seed") = 1, py::arg("ground_truth") = false,
        "Simulate an HDL-64E scan of a built-in scene from the origin, as an (N, 3) array; ground_truth=True gives\n"
        "the co-located noise-free 316-beam scan used as ground truth.");

    bind_tiles(m);
}

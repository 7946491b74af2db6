// Bindings of tiles/tiles.hpp: a map fused in tiles, the pieces lidarsurf.fuse_tiles (tiles.py)
// hands to Dask workers. The plan travels as an array of scan reaches (picklable), not as an object.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/io/recorded_drive.hpp"
#include "lidarsurf/io/recorded_poses.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/tiles/tiles.hpp"
#include "lidarsurf/pipeline.hpp"

namespace py = pybind11;

namespace lidarsurf {
namespace {

// One row per scan: viewpoint (3), radius, box min (3), box max (3), has a first point, first point (3),
// whether it says which rays returned nothing.
constexpr py::ssize_t kReachColumns = 15;

// How a recording's scans are found: the trajectory (a TUM or KITTI file with its times, or
// "recording": the bag's /tf or pose_topic), the scans' topic and the Ouster metadata or Velodyne
// calibration. Travels to the workers as a dict of strings (picklable).
struct RecordingSource {
    std::string poses = "recording", times, topic, metadata, pose_topic, fixed_frame, sensor_frame;
    bool deskew = true;

    static std::optional<RecordingSource> from(const py::object& o) {
        if (o.is_none()) return std::nullopt;
        const py::dict d = o.cast<py::dict>();
        RecordingSource r;
        for (auto [key, value] : d) {
            const std::string k = key.cast<std::string>();
            if (k == "deskew") r.deskew = value.cast<bool>();
            else if (k == "poses") r.poses = value.is_none() ? std::string("recording") : value.cast<std::string>();
            else if (k == "times") r.times = value.is_none() ? "" : value.cast<std::string>();
            else if (k == "topic") r.topic = value.is_none() ? "" : value.cast<std::string>();
            else if (k == "metadata") r.metadata = value.is_none() ? "" : value.cast<std::string>();
            else if (k == "pose_topic") r.pose_topic = value.cast<std::string>();
            else if (k == "fixed_frame") r.fixed_frame = value.cast<std::string>();
            else if (k == "sensor_frame") r.sensor_frame = value.cast<std::string>();
            else throw InvalidArgument("recording: unknown key '" + k + "'");
        }
        return r;
    }
    RecordedDrive open(const std::string& path) const {
        RecordedDriveOptions o;
        o.recording.topic = topic;
        o.recording.metadata = metadata;
        o.deskew = deskew;
        RecordedPosesOptions p;
        p.pose_topic = pose_topic;
        p.fixed_frame = fixed_frame;
        p.sensor_frame = sensor_frame;
        Trajectory trajectory = poses == "recording" ? read_recorded_poses(path, p, o.recording).trajectory : read_trajectory(poses, times);
        return RecordedDrive(path, std::move(trajectory), o);
    }
};

// The sequence's scans `frames` in the world frame: a KITTI layout (poses as `lidarsurf fuse`
// finds them), or a recording's scans within its trajectory's span, de-skewed (as `fuse` takes
// them), read in order (the recording streamed); with the rays that returned nothing as `fuse`
// finds them (the recording's, or a simulated drive's sensor pattern).
struct Sequence {
    std::optional<KittiSequence> seq;
    std::optional<RecordedDrive> drive;
    std::optional<BeamPattern> pattern;
    std::vector<Eigen::Isometry3d> poses;
    std::vector<std::size_t> frames;

    Sequence(const std::string& dir, std::vector<std::size_t> f, const std::optional<RecordingSource>& recording) : frames(std::move(f)) {
        std::size_t available = 0;
        if (recording) {
            drive.emplace(recording->open(dir));
            available = drive->size();
            for (std::size_t k = 0; k < available; ++k) poses.push_back(drive->pose(k));
        } else {
            seq.emplace(KittiSequence{dir});
            available = seq->frame_count();
            poses = read_sequence_poses(find_sequence_poses(seq->dir, {}, {}));
            pattern = sim::drive_pattern(seq->sensor());
        }
        for (std::size_t i : frames)
            if (i >= available || i >= poses.size())
                throw InvalidArgument(dir + ": frame " + std::to_string(i) + " has no scan or no pose (" + std::to_string(available) +
                                      " scans, " + std::to_string(poses.size()) + " poses)");
    }
    /// `no_return`, when given, receives the directions (world) of its rays that returned nothing.
    std::vector<Eigen::Vector3d> scan(std::size_t n, std::vector<Eigen::Vector3f>* no_return = nullptr) { return cloud(n, no_return).points; }
    // Scan n in the world frame, with its intensities when it has them.
    PointCloud cloud(std::size_t n, std::vector<Eigen::Vector3f>* no_return = nullptr) {
        if (drive) return drive->world_scan(frames[n], no_return);
        PointCloud cloud = read_points(seq->scan(frames[n]));
        const Eigen::Isometry3d& pose = poses[frames[n]];
        if (no_return) *no_return = pattern ? empty_rays(*pattern, cloud.points, pose.linear()) : std::vector<Eigen::Vector3f>{};
        for (Eigen::Vector3d& p : cloud.points) p = pose * p;  // NaN stays NaN
        return cloud;
    }
    Eigen::Vector3d viewpoint(std::size_t n) const { return drive ? Eigen::Vector3d(poses[frames[n]] * drive->origin()) : poses[frames[n]].translation(); }
};

// Several drives of one world frame fused as one sequence, one after the other (as `lidarsurf fuse
// A B` takes them): from Python, a sequence and its frames and recording, or lists of them.
struct Drives {
    std::vector<std::unique_ptr<Sequence>> drives;
    std::vector<std::size_t> first;  // the scan of the whole sequence each drive starts at
    std::size_t scans = 0;

    Drives(const py::object& sequence, const py::object& frames, const py::object& recording) {
        const bool several = !py::isinstance<py::str>(sequence);
        const auto dirs = several ? sequence.cast<std::vector<std::string>>() : std::vector<std::string>{sequence.cast<std::string>()};
        const auto per_drive = several ? frames.cast<std::vector<std::vector<std::size_t>>>()
                                       : std::vector<std::vector<std::size_t>>{frames.cast<std::vector<std::size_t>>()};
        std::vector<py::object> sources;
        if (several && !recording.is_none()) sources = recording.cast<std::vector<py::object>>();
        else sources.assign(dirs.size(), recording);
        if (per_drive.size() != dirs.size() || sources.size() != dirs.size())
            throw InvalidArgument("several drives: one list of frames and one recording (or None) per drive");
        for (std::size_t d = 0; d < dirs.size(); ++d) {
            const auto source = RecordingSource::from(sources[d]);
            py::gil_scoped_release release;
            first.push_back(scans);
            drives.push_back(std::make_unique<Sequence>(dirs[d], per_drive[d], source));
            scans += per_drive[d].size();
        }
    }
    PointCloud cloud(std::size_t n, std::vector<Eigen::Vector3f>* no_return) {
        const std::size_t d = static_cast<std::size_t>(std::upper_bound(first.begin(), first.end(), n) - first.begin()) - 1;
        return drives[d]->cloud(n - first[d], no_return);
    }
};

// What a tile's task returns: its mesh's counts, its grid's, and the seconds its fusion took.
py::dict tile_counts(std::size_t triangles, std::size_t vertices, const ReconstructionSummary& s) {
    py::dict out;
    out["triangles"] = triangles;
    out["vertices"] = vertices;
    out["voxels"] = s.voxels;
    out["carved_voxels"] = s.carved_voxels;
    out["seconds"] = s.seconds_total();
    return out;
}

py::array_t<double> reaches_array(const std::vector<ScanReach>& reaches) {
    py::array_t<double> out({static_cast<py::ssize_t>(reaches.size()), kReachColumns});
    auto a = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < reaches.size(); ++i) {
        const ScanReach& r = reaches[i];
        const auto row = static_cast<py::ssize_t>(i);
        const Eigen::Vector3d lo = r.box.isEmpty() ? Eigen::Vector3d::Zero() : r.box.min();
        const Eigen::Vector3d hi = r.box.isEmpty() ? Eigen::Vector3d::Zero() : r.box.max();
        const Eigen::Vector3d first = r.first_point.value_or(Eigen::Vector3d::Zero());
        const double v[kReachColumns] = {r.viewpoint.x(), r.viewpoint.y(), r.viewpoint.z(), r.radius, lo.x(), lo.y(), lo.z(), hi.x(), hi.y(),
                                         hi.z(), r.first_point ? 1.0 : 0.0, first.x(), first.y(), first.z(), r.empty_rays ? 1.0 : 0.0};
        for (py::ssize_t c = 0; c < kReachColumns; ++c) a(row, c) = v[c];
    }
    return out;
}

std::vector<ScanReach> reaches_from(const py::array_t<double, py::array::c_style | py::array::forcecast>& array) {
    if (array.ndim() != 2 || array.shape(1) != kReachColumns)
        throw InvalidArgument("scan reaches must be an (N, " + std::to_string(kReachColumns) + ") array (sequence_reaches())");
    const auto a = array.unchecked<2>();
    std::vector<ScanReach> out(static_cast<std::size_t>(array.shape(0)));
    for (py::ssize_t i = 0; i < array.shape(0); ++i) {
        ScanReach& r = out[static_cast<std::size_t>(i)];
        r.viewpoint = {a(i, 0), a(i, 1), a(i, 2)};
        r.radius = a(i, 3);
        r.empty_rays = a(i, 14) != 0;
        if (a(i, 10) != 0) {
            r.box = Eigen::AlignedBox3d(Eigen::Vector3d(a(i, 4), a(i, 5), a(i, 6)), Eigen::Vector3d(a(i, 7), a(i, 8), a(i, 9)));
            r.first_point = Eigen::Vector3d(a(i, 11), a(i, 12), a(i, 13));
        }
    }
    return out;
}

}  // namespace

void bind_tiles(py::module_& m) {
    py::class_<TileConfig>(m, "TileConfig",
                           "How a map is cut into tiles (fuse_tiles, `lidarsurf fuse --tile-size`): square tiles of tile_size metres in "
                           "the world's x-y plane, each searched halo_cubes cubes beyond its edge, fused in squares of group x group "
                           "tiles that share one pass over the scans.")
        .def(py::init([](double tile_size, int halo_cubes, int group) {
                 TileConfig c{tile_size, halo_cubes, group};
                 c.validate();
                 return c;
             }),
             py::arg("tile_size") = TileConfig{}.tile_size, py::arg("halo_cubes") = TileConfig{}.halo_cubes, py::arg("group") = TileConfig{}.group,
             "Raises ValueError on a bad value.")
        .def_readwrite("tile_size", &TileConfig::tile_size, "Side of the square tiles, metres (CLI --tile-size).")
        .def_readwrite("halo_cubes", &TileConfig::halo_cubes, "Cubes the surface search of a tile reaches beyond it (CLI --tile-halo-cubes).")
        .def_readwrite("group", &TileConfig::group,
                       "Tiles fused in one pass over the scans, squares of this many tiles a side: each scan read and seen as a "
                       "range image once per group, memory holding a group (CLI --tile-group; one Dask task per group).")
        .def("validate", &TileConfig::validate, "Raise ValueError naming the bad field.")
        .def(py::pickle([](const TileConfig& c) { return py::make_tuple(c.tile_size, c.halo_cubes, c.group); },
                        [](const py::tuple& t) {
                            TileConfig c{t[0].cast<double>(), t[1].cast<int>(), t[2].cast<int>()};
                            c.validate();
                            return c;
                        }))
        .def("__repr__", [](const TileConfig& c) {
            std::ostringstream o;
            o << "TileConfig(tile_size=" << c.tile_size << ", halo_cubes=" << c.halo_cubes << ", group=" << c.group << ")";
            return o.str();
        });

    m.def(
        "sequence_frames",
        [](const std::string& sequence, int first, int frames, int step, const py::object& recording) {
            const auto source = RecordingSource::from(recording);
            std::size_t count = 0;
            {
                py::gil_scoped_release release;
                count = source ? source->open(sequence).size() : KittiSequence{sequence}.frame_count();
            }
            return select_frames(count, first, frames, step, sequence);
        },
        py::arg("sequence"), py::arg("first") = 0, py::arg("frames") = 0, py::arg("step") = 1, py::arg("recording") = py::none(),
        "The frames of a sequence (KITTI layout) that `lidarsurf fuse` takes with --first, --frames and --step: from "
        "`first`, every `step`-th, at most `frames` (0: to the last). Raises OSError without velodyne/, ValueError for "
        "a gap in its numbering or a bad range. With `recording` (a dict: poses, times, topic, metadata, pose_topic, "
        "fixed_frame, sensor_frame, deskew), `sequence` is a recording and the frames count its scans within the trajectory.");

    m.def(
        "sequence_reaches",
        [](const std::string& sequence, const std::vector<std::size_t>& frames, const py::object& recording, bool empty_rays) {
            std::vector<ScanReach> reaches;
            const auto source = RecordingSource::from(recording);
            {
                py::gil_scoped_release release;
                Sequence s(sequence, frames, source);
                std::vector<Eigen::Vector3f> no_return;
                for (std::size_t n = 0; n < frames.size(); ++n) {
                    const std::vector<Eigen::Vector3d> points = s.scan(n, empty_rays ? &no_return : nullptr);
                    reaches.push_back(scan_reach(points, s.viewpoint(n), empty_rays && !no_return.empty()));
                }
            }
            return reaches_array(reaches);
        },
        py::arg("sequence"), py::arg("frames"), py::arg("recording") = py::none(), py::arg("empty_rays") = true,
        "The reach of each scan `frames` of a sequence (KITTI layout, poses as `lidarsurf fuse` finds them; a recording "
        "with `recording`, as sequence_frames takes it): an (N, 15) "
        "array, one row per scan (viewpoint, farthest return, box of its points, its first point, whether it says which rays "
        "returned nothing: a recording's, a simulated drive's sensor.json; looked for unless `empty_rays` is False), what a TilePlan is made "
        "of. Reading a sequence's scans once, in pieces on many workers if it is long.");

    py::class_<TilePlan>(m, "TilePlan",
                         "Which tiles a sequence's map has and which scans each takes (tiles/tiles.hpp), from the scans' reaches "
                         "(sequence_reaches), a Config and a TileConfig.")
        .def(py::init([](const py::array_t<double, py::array::c_style | py::array::forcecast>& reaches, const ReconstructionConfig& config,
                         const TileConfig& tiles) { return TilePlan(reaches_from(reaches), config, tiles); }),
             py::arg("reaches"), py::arg("config"), py::arg("tiles"),
             "Raises ValueError for a bad config (the paper as written, min_component_triangles) or a sequence without a point.")
        .def_property_readonly(
            "tiles", [](const TilePlan& p) {
                std::vector<std::pair<int, int>> out;
                for (const TileKey& t : p.tiles()) out.emplace_back(t.x, t.y);
                return out;
            },
            "The tiles that can own a triangle, as (x, y) keys: tile (x, y) covers [x, x + 1) * tile_size by [y, y + 1) * tile_size.")
        .def_property_readonly(
            "groups", [](const TilePlan& p) {
                std::vector<std::vector<std::pair<int, int>>> out;
                for (const std::vector<TileKey>& g : p.groups()) {
                    out.emplace_back();
                    for (const TileKey& t : g) out.back().emplace_back(t.x, t.y);
                }
                return out;
            },
            "The tiles in groups of TileConfig.group x group, each fused in one pass over the scans (fuse_tile_group): lists of (x, y) keys.")
        .def(
            "scans_of", [](const TilePlan& p, std::pair<int, int> t) { return p.scans_of({t.first, t.second}); }, py::arg("tile"),
            "How many scans the tile integrates (the others it counts only).")
        .def_property_readonly("ray_reach", &TilePlan::ray_reach, "The sequence's longest ray, metres: how far a scan reaches the tiles around it.")
        .def_property_readonly(
            "grid_origin", [](const TilePlan& p) { return std::vector<double>{p.grid_origin().x(), p.grid_origin().y(), p.grid_origin().z()}; },
            "The whole map's lattice origin, which every tile takes.");

    m.def(
        "fuse_tile",
        [](const std::string& sequence, const std::vector<std::size_t>& frames, const py::array_t<double, py::array::c_style | py::array::forcecast>& reaches,
           const ReconstructionConfig& config, const TileConfig& tiles, std::pair<int, int> tile, const std::string& output,
           const py::object& recording, const std::string& mesh_format) {
            const MeshFormat format = parse_mesh_format(mesh_format);
            std::vector<ScanReach> r = reaches_from(reaches);
            const auto source = RecordingSource::from(recording);
            ReconstructionSummary s;
            std::size_t triangles = 0, vertices = 0;
            {
                py::gil_scoped_release release;
                const TilePlan plan(std::move(r), config, tiles);
                if (plan.scan_count() != frames.size()) throw InvalidArgument("fuse_tile: one reach per frame");
                Sequence seq(sequence, frames, source);
                const bool empty_rays = config.carve && config.carve_empty_range > 0;
                const Mesh mesh = fuse_tile(
                    plan, {tile.first, tile.second},
                    [&](std::size_t n, std::vector<Eigen::Vector3f>& no_return) { return seq.cloud(n, empty_rays ? &no_return : nullptr); }, &s);
                triangles = mesh.triangles.size(), vertices = mesh.vertices.size();
                if (!output.empty() && triangles > 0) write_mesh(mesh, output, format);
            }
            return tile_counts(triangles, vertices, s);
        },
        py::arg("sequence"), py::arg("frames"), py::arg("reaches"), py::arg("config"), py::arg("tiles"), py::arg("tile"), py::arg("output"),
        py::arg("recording") = py::none(), py::arg("mesh_format") = "auto",
        "Fuse and mesh one tile of a sequence's map (a recording's with `recording`, as sequence_frames takes it) and write its mesh to `output` atomically (whole or not at all; "
        "`mesh_format` as write_mesh's: auto, ply, ply-ascii, obj, glb, glb-draco; "
        "nothing for a tile without a triangle): the "
        "task fuse_tiles gives a worker. Returns a dict of counts (triangles, vertices, voxels, carved_voxels) and seconds.");

    m.def(
        "fuse_tile_group",
        [](const py::object& sequence, const py::object& frames, const py::array_t<double, py::array::c_style | py::array::forcecast>& reaches,
           const ReconstructionConfig& config, const TileConfig& tiles, const std::vector<std::pair<int, int>>& group,
           const std::vector<std::string>& outputs, const py::object& recording, const std::string& mesh_format) {
            const MeshFormat format = parse_mesh_format(mesh_format);
            if (outputs.size() != group.size()) throw InvalidArgument("fuse_tile_group: one output per tile");
            std::vector<ScanReach> r = reaches_from(reaches);
            Drives drives(sequence, frames, recording);
            struct Counts {
                std::size_t triangles = 0, vertices = 0;
                ReconstructionSummary summary;
            };
            std::map<TileKey, Counts> counts;
            std::map<TileKey, std::string> path;
            std::vector<TileKey> keys;
            for (std::size_t i = 0; i < group.size(); ++i) {
                keys.push_back({group[i].first, group[i].second});
                path[keys.back()] = outputs[i];
            }
            TilePassStats pass;
            {
                py::gil_scoped_release release;
                const TilePlan plan(std::move(r), config, tiles);
                if (plan.scan_count() != drives.scans) throw InvalidArgument("fuse_tile_group: one reach per frame");
                const bool empty_rays = config.carve && config.carve_empty_range > 0;
                pass = fuse_tiles(
                    plan, keys,
                    [&](std::size_t n, std::vector<Eigen::Vector3f>& no_return) { return drives.cloud(n, empty_rays ? &no_return : nullptr); },
                    [&](const TileKey& key, Mesh&& mesh, const ReconstructionSummary& s) {
                        const std::string& output = path.at(key);
                        if (!output.empty() && !mesh.triangles.empty()) write_mesh(mesh, output, format);
                        counts[key] = {mesh.triangles.size(), mesh.vertices.size(), s};
                    });
            }
            py::list out;
            for (const TileKey& key : keys) {
                const Counts& c = counts[key];
                out.append(tile_counts(c.triangles, c.vertices, c.summary));
            }
            py::dict stats;
            stats["scans_read"] = pass.scans_read;
            stats["seconds_read"] = pass.seconds_read;
            stats["seconds_range_images"] = pass.seconds_image;
            return py::make_tuple(out, stats);
        },
        py::arg("sequence"), py::arg("frames"), py::arg("reaches"), py::arg("config"), py::arg("tiles"), py::arg("group"), py::arg("outputs"),
        py::arg("recording") = py::none(), py::arg("mesh_format") = "auto",
        "Fuse and mesh a group of tiles (TilePlan.groups) in one pass over the scans, each scan read once, and write each tile's mesh "
        "to its `outputs` path as fuse_tile does: the task fuse_tiles gives a worker. Several drives of one world frame: `sequence` a "
        "list of them, `frames` a list of their frames, `recording` None or a list (one per drive); `reaches` are theirs, in that order. Returns (a list of fuse_tile's dicts, one per "
        "tile in `group`'s order; a dict of the pass's scans_read, seconds_read and seconds_range_images).");
}

}  // namespace lidarsurf

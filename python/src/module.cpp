// pybind11 bindings of lidarsurf: numpy in, numpy out, the C++ ReconstructionConfig bound as
// lidarsurf.Config (defaults defined once, in C++). The GIL is released while C++ runs; library
// exceptions become ValueError (bad parameters or data) or OSError (files).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

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
#include "lidarsurf/io/live_stream.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/version.hpp"

namespace py = pybind11;
using namespace lidarsurf;

namespace lidarsurf {
void bind_tiles(py::module_& m);  // tiles.cpp
}

namespace {

using PointArray = py::array_t<double, py::array::c_style>;

// The (N, 3) float64 C-contiguous view the C++ code reads. A float64 C-contiguous input is used
// as it is (no copy); float32 or non-contiguous inputs are converted once.
PointArray points_view(const py::handle& obj, const char* what) {
    py::array arr = py::array::ensure(obj);
    if (!arr) throw InvalidArgument(std::string(what) + " must be an array-like of shape (N, 3)");
    // float32 and float64 only: numpy's longdouble, float16 and complex types are refused, not converted.
    if (arr.dtype().kind() != 'f' || (arr.dtype().itemsize() != 4 && arr.dtype().itemsize() != 8))
        throw InvalidArgument(std::string(what) + " must be a float32 or float64 array (got dtype " + std::string(py::str(arr.dtype())) + ")");
    if (arr.ndim() != 2 || arr.shape(1) != 3) {
        std::ostringstream shape;
        for (py::ssize_t i = 0; i < arr.ndim(); ++i) shape << (i ? ", " : "") << arr.shape(i);
        throw InvalidArgument(std::string(what) + " must have shape (N, 3) (got (" + shape.str() + "))");
    }
    PointArray view = PointArray::ensure(arr);
    const double* d = view.data();
    std::size_t bad = 0;
    for (py::ssize_t i = 0; i < view.size(); ++i) bad += !std::isfinite(d[i]);
    if (bad)
        throw InvalidInput(std::string(what) + " contain " + std::to_string(bad) +
                           " non-finite values; drop those rows first, e.g. p[np.isfinite(p).all(axis=1)]");
    return view;
}

std::span<const Eigen::Vector3d> as_span(const PointArray& a) {
    return {reinterpret_cast<const Eigen::Vector3d*>(a.data()), static_cast<std::size_t>(a.shape(0))};
}

Eigen::Vector3d as_vec3(const std::vector<double>& v, const char* what) {
    if (v.size() != 3) throw InvalidArgument(std::string(what) + " must have 3 values");
    return {v[0], v[1], v[2]};
}

// An array that refuses writes: a view into a Mesh, whose arrays Python must not change under it.
py::array read_only(py::array a) {
    a.attr("setflags")(py::arg("write") = false);
    return a;
}

// Read-only numpy array over a std::vector owned by `owner` (kept alive by the array's base).
template <typename T, int Cols>
py::array vector_view(const std::vector<T>& v, const py::object& owner) {
    if constexpr (Cols == 1) {
        return read_only(py::array_t<T>({static_cast<py::ssize_t>(v.size())}, {static_cast<py::ssize_t>(sizeof(T))}, v.data(), owner));
    } else {
        using Scalar = typename T::Scalar;
        return read_only(py::array_t<Scalar>({static_cast<py::ssize_t>(v.size()), static_cast<py::ssize_t>(Cols)},
                                             {static_cast<py::ssize_t>(sizeof(T)), static_cast<py::ssize_t>(sizeof(Scalar))},
                                             reinterpret_cast<const Scalar*>(v.data()), owner));
    }
}

py::array_t<double> points_to_numpy(std::vector<Eigen::Vector3d>&& pts) {
    auto* owned = new std::vector<Eigen::Vector3d>(std::move(pts));
    py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<Eigen::Vector3d>*>(p); });
    return py::array_t<double>({static_cast<py::ssize_t>(owned->size()), py::ssize_t{3}},
                               {static_cast<py::ssize_t>(sizeof(Eigen::Vector3d)), static_cast<py::ssize_t>(sizeof(double))},
                               reinterpret_cast<const double*>(owned->data()), free_when_done);
}

// The method `reconstruct` and `ring_holdout` run: config (or the defaults) and the method's name
// as the CLI's --method takes it, validated.
MethodConfig method_of(std::optional<ReconstructionConfig> config, const std::optional<std::string>& method) {
    MethodConfig m;
    m.config = config.value_or(ReconstructionConfig{});
    m.imls = method && *method == "imls";
    if (method && *method == "paper") m.config.make_paper_literal();  // the paper as written, in config's mode
    else if (method && !m.imls && *method != "default") m.config.mode = parse_mode(*method);  // InvalidArgument names the choices
    m.config.validate();
    m.imls_config = ImlsConfig::matching(m.config);
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

// A Reconstructor shared between Python threads: one call at a time (the C++ object is not
// thread-safe). The GIL is released before the lock is taken, so a long extraction in one thread
// neither blocks other Python code nor deadlocks a thread waiting for the lock.
struct SharedReconstructor {
    SharedReconstructor(const ReconstructionConfig& config, const Eigen::Vector3d& origin) : rec(config, origin) {}
    Reconstructor rec;
    std::mutex mutex;
};

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

    py::class_<ReconstructionConfig>(m, "Config",
                                     "Reconstruction parameters: the C++ ReconstructionConfig, with the paper's defaults "
                                     "(alpha 0.2 m, tau 0.2, N_min 10, k_max 5) and lidarsurf's guards on; Config.paper() "
                                     "is the paper as written. validate() raises ValueError on a bad value.")
        .def(py::init<>(), "The default configuration: the paper's parameters with lidarsurf's guards on.")
        .def_static(
            "paper", [](const std::string& mode) { return ReconstructionConfig::paper(parse_mode(mode)); }, py::arg("mode") = "an+gc",
            "The paper's method as written in `mode`: no planarity or thickness guard, no truncation, every defined cube "
            "meshed, interpolated vertices.")
        .def("make_paper_literal", &ReconstructionConfig::make_paper_literal,
             "Turn every guard off as Config.paper() does, keeping the other fields.")
        .def_readwrite("voxel_size", &ReconstructionConfig::voxel_size, "Voxel size alpha, metres.")
        .def_readwrite("tau", &ReconstructionConfig::tau, "Gaussian confidence threshold tau of Eq. (3).")
        .def_readwrite("n_min", &ReconstructionConfig::n_min, "N_min of Eq. (1): minimum points in a neighbourhood.")
        .def_readwrite("k_max", &ReconstructionConfig::k_max, "Largest neighbourhood level of the adaptive modes.")
        .def_readwrite("k", &ReconstructionConfig::k, "Neighbourhood level of the constant modes.")
        .def_property(
            "mode", [](const ReconstructionConfig& c) { return std::string(to_string(c.mode)); },
            [](ReconstructionConfig& c, const std::string& s) { c.mode = parse_mode(s); },
            "Neighbourhood strategy: 'an+gc' (default), 'an', 'cn+gc' or 'cn'.")
        .def_readwrite("min_planarity", &ReconstructionConfig::min_planarity,
                       "Reject neighbourhoods with lambda2 < min_planarity * lambda1 (0 = off, as the paper).")
        .def_readwrite("max_thickness", &ReconstructionConfig::max_thickness,
                       "Reject neighbourhoods with sqrt(lambda3) above this many voxels (0 = off, as the paper).")
        .def_readwrite("slab_from_level", &ReconstructionConfig::slab_from_level,
                       "Slab fallback: a vertex whose cube H^k (k >= 2) has N_min points but no plane tries horizontal slabs "
                       "(H^k cut to the two voxel layers beside it along z) from this level up (0 = off, as the paper).")
        .def_readwrite("slab_radial_extension", &ReconstructionConfig::slab_radial_extension,
                       "Radial slabs: the slabs reach this many voxels further on each side along the horizontal axis on "
                       "which the vertex is further from the sensor, across the scan rings (0 = square slabs).")
        .def_readwrite("bridge_reach", &ReconstructionConfig::bridge_reach,
                       "Bridges (single scans, AN+GC): a vertex no level defines is defined by the plane of the scan rings "
                       "on both sides of it, within k_max + bridge_reach voxels along the beam, when they agree; its "
                       "confidence stays below tau, marking inferred surface (0 = off, as the paper).")
        .def_readwrite("bridge_range", &ReconstructionConfig::bridge_range,
                       "Bridges are tried only within this horizontal distance (metres) of the sensor.")
        .def_readwrite("snap_to_plane", &ReconstructionConfig::snap_to_plane,
                       "Move each mesh vertex onto the plane of the nearer lattice vertex of its edge (False: interpolate).")
        .def_readwrite("min_component_triangles", &ReconstructionConfig::min_component_triangles,
                       "Drop connected mesh pieces with fewer triangles (0 keeps all).")
        .def_readwrite("truncation_voxels", &ReconstructionConfig::truncation_voxels, "TSDF truncation in voxels (0 = none).")
        .def_readwrite("seeded_surface", &ReconstructionConfig::seeded_surface,
                       "Keep only the surface connected to the data (False: every cube with defined corners).")
        .def_readwrite("seed_dilation", &ReconstructionConfig::seed_dilation, "Seed cubes within this many cubes of an occupied voxel.")
        .def_readwrite("carve", &ReconstructionConfig::carve,
                       "Sequences (integrate with a viewpoint): remove voxels that later rays went through, the trails of "
                       "moving objects (False: keep every point; a single scan is never carved).")
        .def_readwrite("carve_margin_voxels", &ReconstructionConfig::carve_margin_voxels,
                       "Carving: a ray counts only if it returned this many voxels behind the voxel's surface.")
        .def_readwrite("carve_min_scans", &ReconstructionConfig::carve_min_scans,
                       "Carving: scans that must see through a voxel (and more than hit it) before it is removed.")
        .def_readwrite("carve_range", &ReconstructionConfig::carve_range,
                       "Carving: the voxels within this distance (metres) of each scan's sensor are tested against it.")
        .def_readwrite("carve_stale_scans", &ReconstructionConfig::carve_stale_scans,
                       "Carving: a planar voxel no scan has hit for this many scans is tested by the returns near it, not only "
                       "by its plane (0: never).")
        .def_readwrite("live_growth", &ReconstructionConfig::live_growth,
                       "Live mesh: a block is meshed again when the points within live_reach_blocks of it changed (inserted or carved) by this fraction, or at once when one of its own voxels was carved.")
        .def_readwrite("live_range", &ReconstructionConfig::live_range,
                       "Live mesh: blocks farther than this (metres) from the last viewpoint wait until it comes back near them.")
        .def_readwrite("live_reach_blocks", &ReconstructionConfig::live_reach_blocks,
                       "Live mesh: a block depends on the changes (points, removed voxels) within this many 8-voxel blocks of it.")
        .def_readwrite("live_halo_cubes", &ReconstructionConfig::live_halo_cubes,
                       "Live mesh: the surface search of the blocks being meshed reaches this many cubes beyond them.")
        .def_readwrite("threads", &ReconstructionConfig::threads, "Worker threads; 0 = all cores.")
        .def_readwrite("max_memory_mb", &ReconstructionConfig::max_memory_mb,
                       "Memory budget in MiB; a reconstruction estimated to need more raises MemoryError.")
        .def("validate", &ReconstructionConfig::validate, "Raise ValueError naming the first bad field.")
        .def("__repr__", [](const ReconstructionConfig& c) {
            std::ostringstream o;
            o << "Config(voxel_size=" << c.voxel_size << ", tau=" << c.tau << ", n_min=" << c.n_min << ", k_max=" << c.k_max
              << ", k=" << c.k << ", mode='" << to_string(c.mode) << "', min_planarity=" << c.min_planarity
              << ", max_thickness=" << c.max_thickness << ", slab_from_level=" << c.slab_from_level
              << ", slab_radial_extension=" << c.slab_radial_extension << ", bridge_reach=" << c.bridge_reach << ", bridge_range=" << c.bridge_range
              << ", truncation_voxels=" << c.truncation_voxels
              << ", snap_to_plane=" << (c.snap_to_plane ? "True" : "False") << ", min_component_triangles=" << c.min_component_triangles
              << ", seeded_surface=" << (c.seeded_surface ? "True" : "False")
              << ", seed_dilation=" << c.seed_dilation << ", carve=" << (c.carve ? "True" : "False")
              << ", carve_margin_voxels=" << c.carve_margin_voxels << ", carve_min_scans=" << c.carve_min_scans << ", carve_range=" << c.carve_range << ", carve_stale_scans=" << c.carve_stale_scans
              << ", live_growth=" << c.live_growth << ", live_range=" << c.live_range << ", live_reach_blocks=" << c.live_reach_blocks
              << ", live_halo_cubes=" << c.live_halo_cubes << ", threads=" << c.threads << ")";
            return o.str();
        });

    py::class_<Mesh>(m, "Mesh", "Triangle mesh. Array attributes are read-only views into the mesh (no copy; np.array(a) for a copy).")
        .def(py::init([](const py::handle& vertices, const py::handle& triangle_array) {
                 const PointArray v = points_view(vertices, "vertices");
                 const py::array given = py::array::ensure(triangle_array);
                 if (!given) throw InvalidArgument("triangles must be an array of integer vertex indices");
                 // Indices are integers: a float array (3.7?) is refused, not truncated. An empty one may be of any type.
                 const char kind = given.dtype().kind();
                 if (given.size() > 0 && kind != 'i' && kind != 'u')
                     throw InvalidArgument(std::string("triangles must hold integer vertex indices (got dtype kind '") + kind + "')");
                 const auto triangles = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(given);
                 if (!triangles || triangles.ndim() != 2 || triangles.shape(1) != 3) throw InvalidArgument("triangles must have shape (T, 3)");
                 Mesh mesh;
                 const auto span = as_span(v);
                 mesh.vertices.assign(span.begin(), span.end());
                 for (py::ssize_t t = 0; t < triangles.shape(0); ++t) {
                     std::array<std::uint32_t, 3> tri{};
                     for (int j = 0; j < 3; ++j) {
                         const std::int64_t i = triangles.at(t, j);
                         if (i < 0 || i >= static_cast<std::int64_t>(mesh.vertices.size()))
                             throw InvalidInput("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(i) + " of " +
                                                std::to_string(mesh.vertices.size()));
                         tri[static_cast<std::size_t>(j)] = static_cast<std::uint32_t>(i);
                     }
                     mesh.triangles.push_back(tri);
                 }
                 return mesh;
             }),
             py::arg("vertices"), py::arg("triangles"), "A mesh from (V, 3) vertices and (T, 3) vertex indices (copied).")
        .def_property_readonly(
            "vertices", [](py::object self) { return vector_view<Eigen::Vector3d, 3>(self.cast<const Mesh&>().vertices, self); },
            "(V, 3) float64 vertex positions, metres.")
        .def_property_readonly(
            "triangles",
            [](py::object self) {
                const auto& t = self.cast<const Mesh&>().triangles;
                return read_only(py::array_t<std::uint32_t>({static_cast<py::ssize_t>(t.size()), py::ssize_t{3}},
                                                            {static_cast<py::ssize_t>(sizeof(t[0])), static_cast<py::ssize_t>(sizeof(std::uint32_t))},
                                                            reinterpret_cast<const std::uint32_t*>(t.data()), self));
            },
            "(T, 3) uint32 vertex indices, counter-clockwise seen from the sensor side.")
        .def_property_readonly(
            "normals", [](py::object self) { return vector_view<Eigen::Vector3f, 3>(self.cast<const Mesh&>().normals, self); },
            "(V, 3) float32 per-vertex normals (empty when absent).")
        .def_property_readonly(
            "levels", [](py::object self) { return vector_view<std::uint8_t, 1>(self.cast<const Mesh&>().levels, self); },
            "(V,) uint8 neighbourhood level k' per vertex (empty when absent).")
        .def_property_readonly(
            "confidence", [](py::object self) { return vector_view<float, 1>(self.cast<const Mesh&>().confidence, self); },
            "(V,) float32 Gaussian confidence of Eq. (3) per vertex (empty when absent).")
        .def(
            "save",
            [](const Mesh& mesh, const std::string& path, const std::string& format) {
                const MeshFormat f = parse_mesh_format(format);
                py::gil_scoped_release release;
                write_mesh(mesh, path, f);
            },
            py::arg("path"), py::arg("format") = "auto",
            "Write the mesh atomically: .ply (binary) by default, .obj by extension; format 'ply', 'ply-ascii' or 'obj'.")
        .def("__repr__", [](const Mesh& mesh) {
            return "Mesh(" + std::to_string(mesh.vertices.size()) + " vertices, " + std::to_string(mesh.triangles.size()) + " triangles)";
        });

    py::class_<MeshDelta>(m, "MeshDelta",
                          "What one Reconstructor.update_mesh() changed in the live mesh: apply `removed` then `changed` to a "
                          "dict {key: Mesh} kept from the earlier updates, in order, to hold the live mesh.")
        .def_property_readonly(
            "changed",
            [](py::object self) {
                // The meshes are views into the delta (kept alive by them), not copies made at each access.
                py::list out;
                for (const MeshBlock& b : self.cast<const MeshDelta&>().changed)
                    out.append(py::make_tuple(py::make_tuple(b.key.x(), b.key.y(), b.key.z()),
                                              py::cast(&b.mesh, py::return_value_policy::reference_internal, self)));
                return out;
            },
            "[(key, Mesh)]: the blocks whose triangles changed, each with its whole new mesh (world coordinates, numpy "
            "arrays, read-only views kept valid by the Mesh); key = (x, y, z), the block of cubes 8 key .. 8 key + 7 of "
            "the voxel lattice.")
        .def_property_readonly(
            "removed",
            [](const MeshDelta& d) {
                py::list out;
                for (const VoxelKey& k : d.removed) out.append(py::make_tuple(k.x(), k.y(), k.z()));
                return out;
            },
            "[key]: the blocks left without a triangle.")
        .def_readonly("meshed_blocks", &MeshDelta::meshed_blocks, "Blocks meshed by the update (their mesh changed or not).")
        .def_readonly("pending", &MeshDelta::pending, "Blocks due and left for later updates.")
        .def_readonly("seconds", &MeshDelta::seconds, "The update's wall time.")
        .def_property_readonly("triangles", &MeshDelta::triangles, "Triangles in `changed`.")
        .def("__repr__", [](const MeshDelta& d) {
            return "MeshDelta(" + std::to_string(d.changed.size()) + " blocks changed, " + std::to_string(d.removed.size()) + " removed, " +
                   std::to_string(d.triangles()) + " triangles, " + std::to_string(d.pending) + " pending)";
        });

    py::class_<SharedReconstructor>(m, "Reconstructor",
                              "A reconstruction that accepts more points: integrate() scans or parts of scans seen from the same "
                              "origin, extract_mesh() whenever a mesh is needed. Each extraction re-evaluates only the vertices the "
                              "points integrated since the previous one can reach, and gives the mesh one extraction of all the "
                              "points would give. One object may be shared between threads: its calls run one at a time.")
        .def(py::init([](std::optional<ReconstructionConfig> config, const std::vector<double>& origin) {
                 return std::make_unique<SharedReconstructor>(config.value_or(ReconstructionConfig{}), as_vec3(origin, "origin"));
             }),
             py::arg("config") = py::none(), py::arg("origin") = std::vector<double>{0, 0, 0},
             "config: a Config (paper defaults when None); origin: the sensor position that orients the normals (Eq. 2). "
             "Raises ValueError on a bad parameter.")
        .def(
            "integrate",
            [](SharedReconstructor& self, const py::handle& points) {
                const PointArray view = points_view(points, "points");
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                self.rec.integrate(as_span(view));
            },
            py::arg("points"),
            "Add an (N, 3) float32/float64 array of points to the voxel statistics; non-finite points are counted as dropped. "
            "Raises MemoryError past the memory budget.")
        .def(
            "integrate_from",
            [](SharedReconstructor& self, const py::handle& points, const std::vector<double>& viewpoint) {
                const PointArray view = points_view(points, "points");
                const Eigen::Vector3d seen_from = as_vec3(viewpoint, "viewpoint");
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                self.rec.integrate(as_span(view), seen_from);
            },
            py::arg("points"), py::arg("viewpoint"),
            "Add points seen from `viewpoint` (same frame, e.g. world points and the pose's translation): for sequences. "
            "The first call turns on per-voxel viewpoints, so each part of the surface is oriented toward where it was "
            "seen from; points added by integrate() count as seen from the origin.")
        .def(
            "extract_mesh",
            [](SharedReconstructor& self) {
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                return self.rec.extract_mesh();
            },
            "The mesh of every point integrated so far. Raises ValueError if no finite point was integrated.")
        .def(
            "update_mesh",
            [](SharedReconstructor& self, double budget_ms) {
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                return self.rec.update_mesh(budget_ms);
            },
            py::arg("budget_ms") = 0.0,
            "Bring the live mesh up to date with the scans integrated since the last call, the blocks nearest the last "
            "viewpoint first, within budget_ms milliseconds (0: everything due), and return a MeshDelta. Applying the "
            "deltas in order gives live_mesh(). extract_mesh() stays the exact mesh. Raises ValueError for the paper's "
            "method as written (seeded_surface False).")
        .def(
            "live_mesh",
            [](SharedReconstructor& self) {
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                return self.rec.live_mesh();
            },
            "The live mesh as the update_mesh() calls so far made it: each block's mesh one after the other (vertices "
            "repeated on block faces).")
        .def_property_readonly(
            "summary",
            [](SharedReconstructor& self) {
                ReconstructionSummary s;
                {
                    py::gil_scoped_release release;
                    const std::lock_guard lock(self.mutex);
                    s = self.rec.summary();
                }
                py::dict d;
                d["points_read"] = s.points_read;
                d["points_dropped"] = s.points_dropped;
                d["voxels"] = s.voxels;
                d["vertices_evaluated"] = s.candidate_vertices;
                d["vertices_reused"] = s.reused_vertices;
                d["vertices_defined"] = s.defined_vertices;
                d["mesh_vertices"] = s.mesh_vertices;
                d["mesh_triangles"] = s.mesh_triangles;
                d["seconds_insert"] = s.seconds_insert;
                d["seconds_tsdf"] = s.seconds_tsdf;
                d["seconds_mesh"] = s.seconds_mesh;
                py::dict phases;
                for (const auto& [name, seconds] : s.tsdf_phases.named()) phases[name] = seconds;
                d["seconds_tsdf_phases"] = phases;
                return d;
            },
            "Counts and times as a dict: points_read, points_dropped, voxels, and of the last extraction vertices_evaluated, "
            "vertices_reused (taken from the extraction before), vertices_defined, mesh_vertices, mesh_triangles, "
            "seconds_tsdf, seconds_mesh, and seconds_tsdf_phases (the fast path's TSDF stage by phase: setup, seed_wave, "
            "later_waves, serial, field; zeros for the reference path); seconds_insert sums every integrate().")
        .def("__repr__", [](SharedReconstructor& self) {
            std::size_t points = 0, voxels = 0;
            {
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                points = self.rec.summary().points_read;
                voxels = self.rec.grid().size();
            }
            return "Reconstructor(" + std::to_string(points) + " points, " + std::to_string(voxels) + " voxels)";
        });

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

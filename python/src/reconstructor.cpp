// Bindings of the incremental pipeline (pipeline.hpp's Reconstructor) as lidarsurf.Reconstructor:
// scans integrated one at a time, the exact mesh and the live mesh's updates. The GIL is released
// while C++ runs.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/map/empty_rays.hpp"
#include "lidarsurf/pipeline.hpp"
#include "numpy_views.hpp"

namespace lidarsurf::python {

namespace {

// A Reconstructor shared between Python threads: one call at a time (the C++ object is not
// thread-safe). The GIL is released before the lock is taken, so a long extraction in one thread
// neither blocks other Python code nor deadlocks a thread waiting for the lock.
struct SharedReconstructor {
    SharedReconstructor(const ReconstructionConfig& config, const Eigen::Vector3d& origin) : rec(config, origin) {}
    Reconstructor rec;
    std::mutex mutex;
};

// An optional (N,) array of intensities as floats (empty for None); ValueError for another length.
std::vector<float> intensity_values(const py::handle& intensity, std::size_t n) {
    if (intensity.is_none()) return {};
    const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(intensity);
    if (!a || a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n)
        throw py::value_error("intensity must be a 1-D array of " + std::to_string(n) + " values (one per point)");
    return {a.data(), a.data() + n};
}

}  // namespace

void bind_reconstructor(py::module_& m) {
    m.def(
        "empty_rays",
        [](const py::handle& points, const std::vector<double>& elevations_deg, double azimuth_step_deg) {
            const PointArray view = points_view(points, "points");
            std::vector<Eigen::Vector3f> rays;
            {
                py::gil_scoped_release release;
                rays = empty_rays(BeamPattern{elevations_deg, azimuth_step_deg}, as_span(view));
            }
            py::array_t<float> out({static_cast<py::ssize_t>(rays.size()), py::ssize_t{3}});
            auto a = out.mutable_unchecked<2>();
            for (std::size_t i = 0; i < rays.size(); ++i)
                for (py::ssize_t c = 0; c < 3; ++c) a(static_cast<py::ssize_t>(i), c) = rays[i][c];
            return out;
        },
        py::arg("points"), py::arg("elevations_deg"), py::arg("azimuth_step_deg"),
        "The unit directions (an (M, 3) float32 array, sensor frame) of the rays of a spinning lidar's pattern (beams at "
        "`elevations_deg`, fired every `azimuth_step_deg` from azimuth 0) that none of `points` (an (N, 3) array of returns "
        "in the sensor frame) fell in: what Reconstructor.integrate_from takes as `no_return`, once turned into the world "
        "frame. A drive `lidarsurf simulate` wrote has its sensor's pattern in sensor.json. Raises ValueError for no beam or "
        "a step outside (0, 360].");
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
            [](SharedReconstructor& self, const py::handle& points, const py::handle& intensity) {
                const PointArray view = points_view(points, "points");
                const std::vector<float> values = intensity_values(intensity, static_cast<std::size_t>(view.shape(0)));
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                self.rec.integrate(as_span(view), values);
            },
            py::arg("points"), py::arg("intensity") = py::none(),
            "Add an (N, 3) float32/float64 array of points to the voxel statistics; non-finite points are counted as dropped. "
            "`intensity`: an (N,) array of the returns' intensities, which the mesh's vertices then carry (Mesh.intensity). "
            "Raises MemoryError past the memory budget, ValueError for an intensity array of another length.")
        .def(
            "integrate_from",
            [](SharedReconstructor& self, const py::handle& points, const std::vector<double>& viewpoint, const py::handle& no_return,
               const py::handle& intensity) {
                const PointArray view = points_view(points, "points");
                const std::vector<float> values = intensity_values(intensity, static_cast<std::size_t>(view.shape(0)));
                const Eigen::Vector3d seen_from = as_vec3(viewpoint, "viewpoint");
                std::vector<Eigen::Vector3f> empty;
                if (!no_return.is_none()) {
                    const PointArray rays = points_view(no_return, "no_return");
                    empty.reserve(static_cast<std::size_t>(rays.shape(0)));
                    for (const Eigen::Vector3d& u : as_span(rays)) empty.push_back(u.cast<float>());
                }
                py::gil_scoped_release release;
                const std::lock_guard lock(self.mutex);
                self.rec.integrate(as_span(view), seen_from, empty, values);
            },
            py::arg("points"), py::arg("viewpoint"), py::arg("no_return") = py::none(), py::arg("intensity") = py::none(),
            "Add points seen from `viewpoint` (same frame, e.g. world points and the pose's translation): for sequences. "
            "The first call turns on per-voxel viewpoints, so each part of the surface is oriented toward where it was "
            "seen from; points added by integrate() count as seen from the origin. `no_return`: an (M, 3) array of the "
            "directions (same frame) of the scan's rays that returned nothing, which carving takes as free space up to "
            "Config.carve_empty_range. `intensity`: as for integrate().")
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

}

}  // namespace lidarsurf::python

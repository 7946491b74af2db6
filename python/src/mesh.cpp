// Bindings of the mesh (mesh/mesh.hpp) as lidarsurf.Mesh, its arrays read-only numpy views, and of
// the live mesh's updates (map/live_mesh.hpp) as lidarsurf.MeshDelta.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/map/live_mesh.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "numpy_views.hpp"

namespace lidarsurf::python {

void bind_mesh(py::module_& m) {
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
        .def_property_readonly(
            "intensity", [](py::object self) { return vector_view<float, 1>(self.cast<const Mesh&>().intensity, self); },
            "(V,) float32 mean intensity of the returns in each vertex's neighbourhood, in the sensor's unit (empty when "
            "the points had none; NaN where no return near a vertex had one).")
        .def(
            "save",
            [](const Mesh& mesh, const std::string& path, const std::string& format) {
                const MeshFormat f = parse_mesh_format(format);
                py::gil_scoped_release release;
                write_mesh(mesh, path, f);
            },
            py::arg("path"), py::arg("format") = "auto",
            "Write the mesh atomically, in the format of the path's extension (.ply binary, .obj, .glb binary glTF) or `format`: 'ply', 'ply-ascii', 'obj', 'glb' or 'glb-draco' (Draco-compressed glTF).")
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

}

}  // namespace lidarsurf::python

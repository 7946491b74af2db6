#pragma once
// numpy in and out for the bindings: the (N, 3) float64 view the C++ code reads, read-only views
// into C++ vectors, arrays handed over to Python. Shared by the binding files of python/src/.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::python {

namespace py = pybind11;

using PointArray = py::array_t<double, py::array::c_style>;

// The (N, 3) float64 C-contiguous view the C++ code reads. A float64 C-contiguous input is used
// as it is (no copy); float32 or non-contiguous inputs are converted once.
inline PointArray points_view(const py::handle& obj, const char* what) {
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

inline std::span<const Eigen::Vector3d> as_span(const PointArray& a) {
    return {reinterpret_cast<const Eigen::Vector3d*>(a.data()), static_cast<std::size_t>(a.shape(0))};
}

inline Eigen::Vector3d as_vec3(const std::vector<double>& v, const char* what) {
    if (v.size() != 3) throw InvalidArgument(std::string(what) + " must have 3 values");
    return {v[0], v[1], v[2]};
}

// An array that refuses writes: a view into a Mesh, whose arrays Python must not change under it.
inline py::array read_only(py::array a) {
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

inline py::array_t<double> points_to_numpy(std::vector<Eigen::Vector3d>&& pts) {
    auto* owned = new std::vector<Eigen::Vector3d>(std::move(pts));
    py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<Eigen::Vector3d>*>(p); });
    return py::array_t<double>({static_cast<py::ssize_t>(owned->size()), py::ssize_t{3}},
                               {static_cast<py::ssize_t>(sizeof(Eigen::Vector3d)), static_cast<py::ssize_t>(sizeof(double))},
                               reinterpret_cast<const double*>(owned->data()), free_when_done);
}

}  // namespace lidarsurf::python

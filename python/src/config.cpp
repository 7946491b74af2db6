// Bindings of ReconstructionConfig as lidarsurf.Config: one property per setting of its tables
// (core/setting.hpp), named as the C++ field and documented by the table's help, plus the mode;
// __repr__ lists them all, in the tables' order.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <sstream>
#include <type_traits>

#include "lidarsurf/core/setting.hpp"
#include "lidarsurf/reconstruction_config.hpp"

namespace py = pybind11;

namespace lidarsurf {
namespace {

// A value as Python writes it: True/False for a bool.
template <typename T>
void write_python(std::ostream& o, const T& value) {
    if constexpr (std::is_same_v<T, bool>) o << (value ? "True" : "False");
    else o << value;
}

std::string config_repr(const ReconstructionConfig& c) {
    std::ostringstream o;
    o << "Config(mode='" << to_string(c.mode) << "'";
    ReconstructionConfig::for_each_setting([&](const Setting& s, auto member) {
        o << ", " << s.name << "=";
        write_python(o, c.*member);
    });
    o << ")";
    return o.str();
}

}  // namespace

void bind_config(py::module_& m) {
    py::class_<ReconstructionConfig> config(m, "Config",
                                            "Reconstruction parameters: the C++ ReconstructionConfig, with the paper's defaults "
                                            "(alpha 0.2 m, tau 0.2, N_min 10, k_max 5) and lidarsurf's guards on; Config.paper() "
                                            "is the paper as written. validate() raises ValueError on a bad value. Each property is "
                                            "the CLI option of the same name (voxel_size: --voxel-size).");
    config.def(py::init<>(), "The default configuration: the paper's parameters with lidarsurf's guards on.")
        .def_static(
            "paper", [](const std::string& mode) { return ReconstructionConfig::paper(parse_mode(mode)); }, py::arg("mode") = "an+gc",
            "The paper's method as written in `mode`: no planarity or thickness guard, no slab fallback, no bridges, no "
            "truncation, every defined cube meshed, interpolated vertices, no carving.")
        .def("make_paper_literal", &ReconstructionConfig::make_paper_literal,
             "Turn every guard off as Config.paper() does, keeping the other fields.")
        .def_property(
            "mode", [](const ReconstructionConfig& c) { return std::string(to_string(c.mode)); },
            [](ReconstructionConfig& c, const std::string& s) { c.mode = parse_mode(s); },
            "Neighbourhood strategy: 'an+gc' (default), 'an', 'cn+gc' or 'cn'.");
    ReconstructionConfig::for_each_setting([&](const Setting& s, auto member) {
        std::string doc = std::string(s.help) + ".";
        if (*s.unit) doc += std::string(" Unit: ") + s.unit + ".";
        config.def_readwrite(s.name, member, doc.c_str());
    });
    config.def("validate", &ReconstructionConfig::validate, "Raise ValueError naming the first bad field.")
        .def("__repr__", &config_repr, "Every setting, as Config(name=value, ...).");
}

}  // namespace lidarsurf

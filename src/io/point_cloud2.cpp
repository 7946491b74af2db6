// sensor_msgs/PointCloud2 (see point_cloud2.hpp).
#include "lidarsurf/io/point_cloud2.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "byte_reader.hpp"
#include "message_reader.hpp"
#include "organized_rays.hpp"
#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

constexpr double kMaxPointTime = 3600;  // s from the stamp: a sweep lasts well under a second

// sensor_msgs/PointCloud2 in the order of its .msg file, the same in ROS 1 and ROS 2 but for the
// header.
PointCloud2Message parse_point_cloud2(detail::MessageReader& r, const std::string& where) {
    PointCloud2Message m;
    auto header = r.header();
    m.stamp_ns = header.stamp_ns;
    m.frame_id = std::move(header.frame_id);
    m.height = r.scalar<std::uint32_t>();
    m.width = r.scalar<std::uint32_t>();
    const auto n_fields = r.scalar<std::uint32_t>();
    if (n_fields > 1024) throw FormatError(where + ": PointCloud2 with " + std::to_string(n_fields) + " fields");
    for (std::uint32_t i = 0; i < n_fields; ++i) {
        PointField2 f;
        f.name = r.string();
        f.offset = r.scalar<std::uint32_t>();
        f.datatype = r.scalar<std::uint8_t>();
        f.count = r.scalar<std::uint32_t>();
        m.fields.push_back(std::move(f));
    }
    m.big_endian = r.scalar<std::uint8_t>() != 0;
    m.point_step = r.scalar<std::uint32_t>();
    m.row_step = r.scalar<std::uint32_t>();
    m.data = r.bytes(r.scalar<std::uint32_t>());
    r.scalar<std::uint8_t>();  // is_dense: not trusted, every point is checked
    return m;
}

detail::ScalarType scalar_type(std::uint8_t datatype) {
    using detail::ScalarType;
    constexpr ScalarType types[] = {ScalarType::Int8,  ScalarType::UInt8,  ScalarType::Int16,   ScalarType::UInt16,
                                    ScalarType::Int32, ScalarType::UInt32, ScalarType::Float32, ScalarType::Float64};
    return types[datatype - 1];
}

const PointField2* field_named(const PointCloud2Message& m, std::initializer_list<const char*> names) {
    for (const char* n : names)
        for (const auto& f : m.fields)
            if (f.name == n) return &f;
    return nullptr;
}

}  // namespace

PointCloud2Message parse_ros1_point_cloud2(std::span<const std::uint8_t> bytes, const std::string& where) {
    detail::MessageReader r(bytes, where, detail::MessageReader::Encoding::Ros1);
    return parse_point_cloud2(r, where);
}

PointCloud2Message parse_cdr_point_cloud2(std::span<const std::uint8_t> bytes, const std::string& where) {
    detail::MessageReader r(bytes, where, detail::MessageReader::Encoding::Cdr);
    return parse_point_cloud2(r, where);
}

RecordedScan decode_point_cloud2(const PointCloud2Message& m, const std::string& where, std::size_t* no_returns) {
    const auto fail = [&](const std::string& what) { return FormatError(where + ": PointCloud2 " + what); };
    const std::uint64_t row_bytes = std::uint64_t{m.width} * m.point_step;
    if (m.point_step == 0 && m.width * std::uint64_t{m.height} > 0) throw fail("with point_step 0");
    if (m.row_step < row_bytes) throw fail("row_step " + std::to_string(m.row_step) + " is less than width x point_step = " + std::to_string(row_bytes));
    if (std::uint64_t{m.row_step} * m.height != m.data.size())
        throw fail("of " + std::to_string(m.height) + " rows of row_step " + std::to_string(m.row_step) + " bytes holds " +
                   std::to_string(m.data.size()) + " bytes of data");
    for (const auto& f : m.fields) {
        if (f.datatype < 1 || f.datatype > 8) throw fail("field '" + f.name + "' has datatype " + std::to_string(f.datatype));
        const std::uint64_t end = f.offset + std::uint64_t{f.count == 0 ? 1 : f.count} * detail::scalar_size(scalar_type(f.datatype));
        if (end > m.point_step) throw fail("field '" + f.name + "' ends at byte " + std::to_string(end) + " of a point_step of " + std::to_string(m.point_step));
    }
    const PointField2* xyz[3] = {field_named(m, {"x"}), field_named(m, {"y"}), field_named(m, {"z"})};
    for (const auto* f : xyz)
        if (!f || (f->datatype != 7 && f->datatype != 8)) throw fail("without float32 or float64 fields x, y and z");
    // Per-point time: its field and how to turn a value into seconds after the stamp.
    const PointField2* time = field_named(m, {"t", "offset_time", "time", "timestamp", "time_stamp"});
    double time_scale = 1;
    bool absolute = false;
    if (time) {
        const bool integer = time->datatype <= 6;
        if (integer) time_scale = 1e-9;  // Ouster t, Livox offset_time: ns after the stamp
        if (!integer && (time->name == "timestamp" || time->name == "time_stamp")) absolute = true;  // Hesai: absolute s
    }
    // Per-point intensity: the calibrated reflectivity where the driver gives it (Ouster, Livox),
    // else the intensity (Velodyne, Hesai, Ouster's signal) or SemanticKITTI's remission.
    const PointField2* intensity = field_named(m, {"reflectivity"});
    if (!intensity) intensity = field_named(m, {"intensity", "remission"});
    RecordedScan scan;
    scan.stamp_ns = m.stamp_ns;
    scan.frame_id = m.frame_id;
    if (no_returns) *no_returns = 0;
    const std::size_t n = std::size_t{m.width} * m.height;
    if (n == 0) return scan;  // (and no walk over 2^32 empty rows)
    scan.cloud.points.reserve(n);
    if (time) scan.times.reserve(n);
    if (intensity) scan.cloud.intensities.reserve(n);
    std::size_t empty = 0;
    const double stamp_s = 1e-9 * static_cast<double>(m.stamp_ns);
    // The usual layout (float32 x, y, z in the host's byte order) is read without the general
    // loader's per-value dispatch.
    const bool float32_xyz = !m.big_endian && xyz[0]->datatype == 7 && xyz[1]->datatype == 7 && xyz[2]->datatype == 7;
    // An organized cloud (beams by azimuths): where its empty rays point is found from its grid.
    const bool organized = m.height > 1 && m.width > 1 && n <= std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> cells, empty_cells;
    for (std::uint32_t row = 0; row < m.height; ++row) {
        const auto* base = reinterpret_cast<const char*>(m.data.data()) + std::size_t{row} * m.row_step;
        for (std::uint32_t col = 0; col < m.width; ++col) {
            const char* p = base + std::size_t{col} * m.point_step;
            Eigen::Vector3d v;
            if (float32_xyz) {
                for (int a = 0; a < 3; ++a) {
                    float f;
                    std::memcpy(&f, p + xyz[a]->offset, sizeof f);
                    v[a] = f;
                }
            } else {
                for (int a = 0; a < 3; ++a) v[a] = detail::load_scalar(p + xyz[a]->offset, scalar_type(xyz[a]->datatype), m.big_endian);
            }
            const bool finite = std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
            if (!finite || (v.x() == 0 && v.y() == 0 && v.z() == 0)) {  // organized clouds mark a ray without return so
                ++empty;
                if (organized) empty_cells.push_back(row * m.width + col);
                continue;
            }
            if (organized) cells.push_back(row * m.width + col);
            scan.cloud.points.push_back(v);
            if (intensity)  // a NaN stays NaN: the voxels' means leave it out
                scan.cloud.intensities.push_back(detail::to_float_or_nan(detail::load_scalar(p + intensity->offset, scalar_type(intensity->datatype), m.big_endian)));
            if (time) {
                double t = detail::load_scalar(p + time->offset, scalar_type(time->datatype), m.big_endian) * time_scale;
                if (absolute) t -= stamp_s;
                if (!(std::abs(t) <= kMaxPointTime))
                    throw fail("point " + std::to_string(std::size_t{row} * m.width + col) + " has a time of " + std::to_string(t) +
                               " s from the stamp (not finite, or over an hour away)");
                scan.times.push_back(static_cast<float>(t));
            }
        }
    }
    if (no_returns) *no_returns = empty;
    if (organized) scan.no_return = detail::organized_no_return_directions(m.height, m.width, scan.cloud.points, cells, empty_cells);
    return scan;
}

}  // namespace lidarsurf

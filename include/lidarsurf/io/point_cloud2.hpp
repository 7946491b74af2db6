#pragma once
// sensor_msgs/PointCloud2 as a ROS 1 bag stores it (ROS serialization: little endian, strings
// and arrays prefixed by a uint32 length) and as ROS 2 does (CDR), decoded into a RecordedScan: x, y, z of any float
// type, the per-point time under the drivers' usual names, organized clouds with NaN or zero
// for rays that returned nothing, padding inside point_step, and the big-endian flag.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "lidarsurf/io/recorded_scan.hpp"

namespace lidarsurf {

struct PointField2 {
    std::string name;
    std::uint32_t offset = 0;
    std::uint8_t datatype = 0;  ///< 1 int8, 2 uint8, 3 int16, 4 uint16, 5 int32, 6 uint32, 7 float32, 8 float64
    std::uint32_t count = 1;
};

struct PointCloud2Message {
    std::int64_t stamp_ns = 0;
    std::string frame_id;
    std::uint32_t height = 0, width = 0;
    std::vector<PointField2> fields;
    bool big_endian = false;
    std::uint32_t point_step = 0, row_step = 0;
    std::span<const std::uint8_t> data;  ///< points into the buffer the message was parsed from
};

/// Parses a ROS 1 serialized sensor_msgs/PointCloud2. Throws FormatError naming `where` when a
/// length runs past the buffer.
PointCloud2Message parse_ros1_point_cloud2(std::span<const std::uint8_t> bytes, const std::string& where);

/// Parses a ROS 2 sensor_msgs/msg/PointCloud2 in CDR (the encapsulation header, either byte
/// order, members aligned to their size). Throws FormatError naming `where` when a length runs
/// past the buffer, a string lacks its NUL, or the encapsulation is not plain CDR.
PointCloud2Message parse_cdr_point_cloud2(std::span<const std::uint8_t> bytes, const std::string& where);

/// The points of a PointCloud2 (rays that returned nothing left out and counted in
/// `no_returns`; in an organized cloud of beams by azimuths, their directions are estimated from
/// its rows and columns into RecordedScan::no_return). Per-point times: Ouster `t` (uint32 ns), Velodyne `time` (float32 s after the
/// stamp), Livox `offset_time` (uint32 ns), Hesai `timestamp` (float64 absolute s); `times` holds
/// them as seconds after the message's stamp. Per-point intensity (PointCloud::intensities, in the
/// field's own unit): `reflectivity` where there is one (Ouster, Livox), else `intensity` or
/// `remission`. Throws FormatError when the sizes disagree with the
/// data (width x height x point_step, row_step), a field lies outside point_step, x/y/z are
/// missing or not float32/float64, or a time is not finite.
RecordedScan decode_point_cloud2(const PointCloud2Message& message, const std::string& where, std::size_t* no_returns = nullptr);

}  // namespace lidarsurf

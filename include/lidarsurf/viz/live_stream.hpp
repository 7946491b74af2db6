#pragma once
// The live mesh's stream format: what `lidarsurf fuse --serve` sends to the viewer's page over a
// WebSocket, one binary message per update (docs/live_view.md has the layout). Little-endian,
// every array 4-byte aligned so that a browser reads it through typed arrays without a copy:
//   header (112 bytes): "LSLV", version, flags, scans fused, origin (3 float64: the world point
//     the positions are relative to, fixed for a stream), the sensor's pose (3x4 float32, row
//     major, translation relative to the origin), and the counts of the three parts below;
//   trajectory: sensor positions (3 float32 each) the client has not had yet, in order;
//   removed: block keys (3 int32 each) left without a triangle;
//   changed: blocks, each its key (3 int32), vertex and triangle counts (uint32), the block's
//     lowest corner (3 float32, relative to the origin), its position step, confidence step,
//     intensity base and intensity step (float32; a step of -1: the block has no intensity), and
//     the byte lengths (uint32) of its vertices and triangles, both compressed by meshoptimizer's
//     codecs (each zero-padded to 4 bytes): vertex records of 12 bytes (x, y, z and confidence as
//     uint16 steps from the corner and from 0, the level as uint8, a zero byte, the intensity as
//     uint16 steps from its base, 65535 for none), and 3 uint32 indices a triangle. The position
//     step is 0.5 mm (the block's extent / 65535 for a block past 32 m), so positions keep a
//     quarter of a millimetre; intensity keeps 1/65534 of the block's range; the vertices are in
//     meshoptimizer's order, not the block mesh's (a vertex no triangle uses is left out).
// Applying a message: drop every block if kReset, then the removed blocks, then put each changed
// block in place of the one with its key.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "lidarsurf/map/live_mesh.hpp"

namespace lidarsurf::live_stream {

inline constexpr std::uint32_t kVersion = 3;
inline constexpr std::size_t kHeaderBytes = 112;

enum Flags : std::uint32_t {
    kReset = 1,  ///< the client drops every block before applying this message
    kFinal = 2,  ///< the drive has ended: with this message the client holds the final mesh
    kMore = 4,   ///< the update goes on in the next message (a catch-up cut into pieces)
};

/// What a message says besides its blocks.
struct Header {
    std::uint32_t flags = 0;
    std::uint32_t scans = 0;                            ///< scans fused so far
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();   ///< world point the positions are relative to
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< the sensor's latest pose (world)
};

/// A changed block's part of a message (key, counts, arrays), to be encoded once and sent to
/// every client. Vertices without levels or confidence get 0; a mesh without intensity sends none. Throws InvalidArgument for a block
/// of more than 65,535 vertices or 131,072 triangles (a block of 8^3 cubes has at most ~2,200
/// vertices).
std::string encode_block(const MeshBlock& block, const Eigen::Vector3d& origin);

/// One message: the header, the trajectory positions (world), the removed keys and the blocks
/// encoded by encode_block, copied as they are.
std::string encode_message(const Header& header, std::span<const Eigen::Vector3d> trajectory, std::span<const VoxelKey> removed,
                           std::span<const std::string* const> blocks);

/// A message read back (world coordinates, within the quantization of what was sent).
struct Message {
    Header header;
    std::vector<Eigen::Vector3d> trajectory;
    std::vector<VoxelKey> removed;
    std::vector<MeshBlock> changed;
};

/// Reads a message. Throws FormatError when it is not one: wrong magic or version, counts that
/// disagree with its size or exceed a block's, data that does not decode, a triangle index out of
/// its block.
Message decode(std::span<const std::uint8_t> bytes);

/// Applies a message to a client's blocks (kept in (z, y, x) key order, as apply(MeshDelta)).
void apply(const Message& message, std::vector<MeshBlock>& blocks);

}  // namespace lidarsurf::live_stream

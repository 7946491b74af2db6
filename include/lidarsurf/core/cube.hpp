#pragma once
// The unit cube of the vertex lattice, shared by marching cubes and the surface search: corner c of
// the cube with minimum corner `base` is base + corner_offset(c) (bit a of c: the offset along axis
// a); its six faces; and which faces a surface crosses, from the signs of the corners.
#include <array>
#include <cstdint>

#include "lidarsurf/core/voxel_key.hpp"

namespace lidarsurf {

inline VoxelKey corner_offset(int c) { return {c & 1, (c >> 1) & 1, (c >> 2) & 1}; }

/// The corners of each face, counter-clockwise seen from outside the cube. Face f is normal to
/// axis f / 2, on the cube's lower side for even f and its upper side for odd f: -x, +x, -y, +y,
/// -z, +z.
inline constexpr std::array<std::array<int, 4>, 6> kCubeFaces{{
    {0, 4, 6, 2},  // -x
    {1, 3, 7, 5},  // +x
    {0, 1, 5, 4},  // -y
    {2, 6, 7, 3},  // +y
    {0, 2, 3, 1},  // -z
    {4, 5, 7, 6},  // +z
}};

/// Bit f set when the surface crosses face f of a cube whose corners' signs are `config` (bit c set
/// when corner c is negative): the face's four corners are not all of one sign.
inline constexpr std::array<std::uint8_t, 256> kCrossedFaces = [] {
    std::array<std::uint8_t, 256> t{};
    for (int config = 0; config < 256; ++config)
        for (int f = 0; f < 6; ++f) {
            int negatives = 0;
            for (int c : kCubeFaces[static_cast<std::size_t>(f)]) negatives += (config >> c) & 1;
            if (negatives != 0 && negatives != 4) t[static_cast<std::size_t>(config)] |= static_cast<std::uint8_t>(1 << f);
        }
    return t;
}();

}  // namespace lidarsurf

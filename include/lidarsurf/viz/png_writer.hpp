#pragma once
// Writes 8-bit RGB images as PNG (libpng), atomically.
#include <cstdint>
#include <filesystem>
#include <vector>

namespace lidarsurf {

struct Image {
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgb;  ///< row-major, top row first, 3 bytes per pixel
};

/// Throws InvalidArgument for an inconsistent image and IoError when the file cannot be written.
void write_png(const Image& image, const std::filesystem::path& path);

}  // namespace lidarsurf

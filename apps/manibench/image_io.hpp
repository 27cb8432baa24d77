// Files of the render command: PNG images (libpng) and PLY point clouds.
#pragma once

#include <manibench/pointcloud.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace manibench::cli {

// Writes an 8-bit PNG: `channels` 1 (gray), 3 (rgb) or 4 (rgba), rows top
// first. Throws std::runtime_error naming the file when it cannot.
void writePng8(const std::string& path, int width, int height, int channels,
               const std::vector<std::uint8_t>& pixels);
// A 16-bit grayscale PNG (e.g. depth in millimetres), rows top first.
void writePng16(const std::string& path, int width, int height,
                const std::vector<std::uint16_t>& pixels);

// Binary little-endian PLY: float x y z, uchar red green blue, then one
// uchar property per mask named mask_<name> (0 or 1).
void writePly(const std::string& path, const PointCloud& cloud,
              const std::vector<std::string>& mask_names);

}  // namespace manibench::cli

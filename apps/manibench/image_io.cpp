#include "image_io.hpp"

#include <manibench/error.hpp>

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <stdexcept>

namespace manibench::cli {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// libpng reports errors by longjmp; this keeps its message for the throw.
void onPngError(png_structp png, png_const_charp message) {
  auto* text = static_cast<std::string*>(png_get_error_ptr(png));
  *text = message;
  png_longjmp(png, 1);
}
void onPngWarning(png_structp, png_const_charp) {}

void writePng(const std::string& path, int width, int height, int color_type, int bit_depth,
              const std::uint8_t* data, std::size_t row_bytes) {
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
  if (!file) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  std::string error;
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, &onPngError, &onPngWarning);
  if (png == nullptr) throw std::runtime_error("cannot write " + path + ": libpng failed to start");
  png_infop info = png_create_info_struct(png);
  std::vector<png_const_bytep> rows(static_cast<std::size_t>(height));
  for (int r = 0; r < height; ++r) rows[std::size_t(r)] = data + std::size_t(r) * row_bytes;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("cannot write " + path + ": " + error);
  }
  png_init_io(png, file.get());
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), bit_depth, color_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (bit_depth == 16) png_set_swap(png);  // our 16-bit samples are little-endian
  png_write_rows(png, const_cast<png_bytepp>(rows.data()), png_uint_32(height));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(file.get()) != 0)
    throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
}

}  // namespace

void writePng8(const std::string& path, int width, int height, int channels,
               const std::vector<std::uint8_t>& pixels) {
  const int type = channels == 1   ? PNG_COLOR_TYPE_GRAY
                   : channels == 3 ? PNG_COLOR_TYPE_RGB
                   : channels == 4 ? PNG_COLOR_TYPE_RGBA
                                   : -1;
  if (type < 0) throw InvalidArgument("writePng8: channels must be 1, 3 or 4");
  if (pixels.size() != std::size_t(width) * height * channels)
    throw InvalidArgument("writePng8: " + path + ": pixel count does not match the size");
  writePng(path, width, height, type, 8, pixels.data(), std::size_t(width) * channels);
}

void writePng16(const std::string& path, int width, int height,
                const std::vector<std::uint16_t>& pixels) {
  if (pixels.size() != std::size_t(width) * height)
    throw InvalidArgument("writePng16: " + path + ": pixel count does not match the size");
  writePng(path, width, height, PNG_COLOR_TYPE_GRAY, 16,
           reinterpret_cast<const std::uint8_t*>(pixels.data()), std::size_t(width) * 2);
}

void writePly(const std::string& path, const PointCloud& cloud,
              const std::vector<std::string>& mask_names) {
  if (mask_names.size() != cloud.mask_count)
    throw InvalidArgument("writePly: " + path + ": mask names do not match the cloud");
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  out << "ply\nformat binary_little_endian 1.0\ncomment manibench point cloud, world frame, m\n"
      << "element vertex " << cloud.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  for (const std::string& name : mask_names) {
    std::string property = "mask_" + name;
    std::replace_if(property.begin(), property.end(), [](char c) { return c == ' '; }, '_');
    out << "property uchar " << property << "\n";
  }
  out << "end_header\n";
  const std::size_t k = cloud.mask_count;
  std::vector<char> record(12 + 3 + k);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    // x86 and ARM Linux are little-endian, as the header says.
    std::memcpy(record.data(), cloud.xyz.data() + 3 * i, 12);
    for (int c = 0; c < 3; ++c)
      record[12 + c] = char(std::lround(std::clamp(cloud.rgb[3 * i + c], 0.0f, 1.0f) * 255.0f));
    for (std::size_t m = 0; m < k; ++m) record[15 + m] = char(cloud.masks[i * k + m] ? 1 : 0);
    out.write(record.data(), std::streamsize(record.size()));
  }
  out.flush();
  if (!out) throw std::runtime_error("cannot write " + path + ": write failed");
}

}  // namespace manibench::cli

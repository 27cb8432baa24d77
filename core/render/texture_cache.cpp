#include "texture_cache.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <set>

// The render layer's one stb_image implementation. Static functions: the
// viewer's Dear ImGui links Debian's libstb, whose stbi_ symbols must not
// meet a second definition. User messages: the warning names the reason.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_FAILURE_USERMSG
#include <stb/stb_image.h>

namespace manibench {
namespace {

struct Image {
  int width = 0, height = 0;
  std::unique_ptr<stbi_uc, void (*)(void*)> pixels{nullptr, stbi_image_free};
};

// Decodes `path` into RGBA8 rows, top first, of a size GL takes; "" on
// success, else why not.
std::string decodeImage(const std::string& path, Image& image) {
  // Assimp names a texture embedded in the mesh file "*<index>"; the
  // renderer sees only the path, not the file's aiScene.
  if (!path.empty() && path[0] == '*') return "a texture embedded in the mesh file";
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return std::strerror(errno);
  int channels = 0;
  image.pixels.reset(stbi_load_from_file(file, &image.width, &image.height, &channels, 4));
  std::fclose(file);
  if (!image.pixels) {
    const char* reason = stbi_failure_reason();
    return std::string("cannot decode it: ") + (reason != nullptr ? reason : "unknown error");
  }
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (image.width > max_size || image.height > max_size) {
    return std::to_string(image.width) + "x" + std::to_string(image.height) +
           " exceeds GL_MAX_TEXTURE_SIZE " + std::to_string(max_size);
  }
  return "";
}

void warnOnce(const std::string& path, const std::string& reason) {
  static std::mutex mutex;
  static std::set<std::string> warned;
  const std::lock_guard<std::mutex> lock(mutex);
  if (!warned.insert(path).second) return;
  std::fprintf(stderr, "manibench: texture %s: %s; drawn in the material's plain color\n",
               path.c_str(), reason.c_str());
}

GLuint uploadTexture(const Image& image) {
  GLuint texture = 0;
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.width, image.height, 0, GL_RGBA,
               GL_UNSIGNED_BYTE, image.pixels.get());
  // Mipmaps: a 1024x1024 wood texture on a cabinet front a few hundred
  // pixels wide would otherwise alias into noise.
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  glBindTexture(GL_TEXTURE_2D, 0);
  return texture;
}

}  // namespace

GLuint TextureCache::findOrLoad(const std::string& path) {
  const auto found = textures_.find(path);
  if (found != textures_.end()) return found->second;
  Image image;
  const std::string error = decodeImage(path, image);
  GLuint texture = 0;
  if (error.empty()) {
    texture = uploadTexture(image);
  } else {
    warnOnce(path, error);
  }
  textures_.emplace(path, texture);
  return texture;
}

void TextureCache::release() {
  for (auto& [path, texture] : textures_) {
    if (texture != 0) glDeleteTextures(1, &texture);
  }
  textures_.clear();
}

std::size_t TextureCache::getCount() const {
  std::size_t count = 0;
  for (const auto& [path, texture] : textures_) count += texture != 0 ? 1 : 0;
  return count;
}

}  // namespace manibench

// Internal to core/render: the diffuse textures of mesh materials (an OBJ's
// map_Kd) as GL textures, one per image file and SceneRenderer.
#pragma once

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <map>
#include <string>

namespace manibench {

// Owned by one SceneRenderer and used under the context's lock. A file is
// decoded (stb_image) and uploaded at its first request only: the sub-meshes
// of an object share a few images.
class TextureCache {
 public:
  // The texture of image file `path`: RGBA8 with mipmaps, repeating (OBJ
  // texture coordinates often leave [0, 1]), its rows as the file stores
  // them (top first, so GL's t = 0 is the image's top: the vertex buffer
  // holds 1 - v). 0 when the file is missing or cannot be decoded: the
  // caller draws the plain color, and a line on stderr names the file and
  // the reason, once per file per process (a scene rebuilt per episode
  // would repeat it).
  GLuint findOrLoad(const std::string& path);
  // Deletes every texture (the renderer's releaseGl).
  void release();
  // Files uploaded (the ones that could be read).
  std::size_t getCount() const;

 private:
  std::map<std::string, GLuint> textures_;  // 0 for files that failed
};

}  // namespace manibench

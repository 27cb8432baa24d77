// Internal to core/render: the scene renderer's one shader program (Phong
// lighting with directional and point lights, an optional diffuse texture,
// a segmentation output), its
// GLSL sources and how it is built for a light count.
#pragma once

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

namespace manibench {

// The program for `directional_count` directional and `point_count` point
// lights, compiled and linked in the current context; RenderError with the
// linker's and compilers' logs when it does not link.
GLuint linkSceneProgram(int directional_count, int point_count);

}  // namespace manibench

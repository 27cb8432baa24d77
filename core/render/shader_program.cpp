#include "shader_program.hpp"

#include <manibench/renderer.hpp>

#include <algorithm>
#include <string>

namespace manibench {
namespace {

const char* const kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_texture_coord;
uniform mat4 u_model_view;
uniform mat4 u_projection;
uniform mat3 u_normal_matrix;
out vec3 v_position;
out vec3 v_normal;
out vec2 v_texture_coord;
void main() {
  vec4 p = u_model_view * vec4(a_position, 1.0);
  v_position = p.xyz;
  v_normal = u_normal_matrix * a_normal;
  v_texture_coord = a_texture_coord;
  gl_Position = u_projection * p;
}
)";

// Lights arrive in the camera (view) frame. The light counts are compile-
// time constants (one program per count pair): llvmpipe runs loops with
// uniform bounds about five times slower than unrolled ones. Specular
// exponent 32 by repeated squaring (pow() is slow there too). A textured
// mesh's diffuse color is its material color times the texture's rgb (as
// an OBJ's Kd and map_Kd); u_textured is uniform, so untextured draws skip
// the sampling and derivatives stay defined.
const char* const kFragmentShaderBody = R"(
in vec3 v_position;
in vec3 v_normal;
in vec2 v_texture_coord;
uniform vec4 u_color;
uniform bool u_textured;
uniform sampler2D u_texture;
uniform uint u_segment;
uniform vec3 u_ambient;
uniform vec3 u_directional_to_light[DIRECTIONAL_SIZE];
uniform vec3 u_directional_color[DIRECTIONAL_SIZE];
uniform vec3 u_point_position[POINT_SIZE];
uniform vec3 u_point_color[POINT_SIZE];
layout(location = 0) out vec4 o_color;
layout(location = 1) out uint o_segment;
float specular(vec3 n, vec3 l, vec3 v) {
  float s = max(dot(n, normalize(l + v)), 0.0);
  s *= s; s *= s; s *= s; s *= s; s *= s;
  return s;
}
void main() {
  vec3 albedo = u_color.rgb;
  if (u_textured) albedo *= texture(u_texture, v_texture_coord).rgb;
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 v = normalize(-v_position);
  vec3 diffuse = u_ambient;
  vec3 shine = vec3(0.0);
  for (int i = 0; i < DIRECTIONAL_COUNT; ++i) {
    vec3 l = u_directional_to_light[i];
    float lambert = max(dot(n, l), 0.0);
    diffuse += u_directional_color[i] * lambert;
    if (lambert > 0.0) shine += u_directional_color[i] * specular(n, l, v);
  }
  for (int i = 0; i < POINT_COUNT; ++i) {
    vec3 d = u_point_position[i] - v_position;
    float r2 = max(dot(d, d), 1e-6);
    vec3 l = d * inversesqrt(r2);
    float lambert = max(dot(n, l), 0.0);
    diffuse += u_point_color[i] * (lambert / r2);
    if (lambert > 0.0) shine += u_point_color[i] * (specular(n, l, v) / r2);
  }
  o_color = vec4(clamp(albedo * diffuse + 0.1 * shine, 0.0, 1.0), 1.0);
  o_segment = u_segment;
}
)";

std::string getFragmentShader(int directional_count, int point_count) {
  return "#version 330 core\n#define DIRECTIONAL_COUNT " + std::to_string(directional_count) +
         "\n#define DIRECTIONAL_SIZE " + std::to_string(std::max(directional_count, 1)) +
         "\n#define POINT_COUNT " + std::to_string(point_count) + "\n#define POINT_SIZE " +
         std::to_string(std::max(point_count, 1)) + "\n" + kFragmentShaderBody;
}

GLuint compileShader(GLenum type, const char* source) {
  GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  return shader;  // checked at link: Mesa's shader cache may skip the compile
}

std::string getShaderLog(GLuint shader) {
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
  glGetShaderInfoLog(shader, length, nullptr, log.data());
  return log.c_str();
}

}  // namespace

GLuint linkSceneProgram(int directional_count, int point_count) {
  const std::string fragment_source = getFragmentShader(directional_count, point_count);
  GLuint vertex = compileShader(GL_VERTEX_SHADER, kVertexShader);
  GLuint fragment = compileShader(GL_FRAGMENT_SHADER, fragment_source.c_str());
  GLuint program = glCreateProgram();
  glAttachShader(program, vertex);
  glAttachShader(program, fragment);
  glLinkProgram(program);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  std::string error;
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    error = "renderer shader program does not link: " + std::string(log.c_str()) +
            " vertex shader: " + getShaderLog(vertex) +
            " fragment shader: " + getShaderLog(fragment);
  }
  glDeleteShader(vertex);
  glDeleteShader(fragment);
  if (!error.empty()) {
    glDeleteProgram(program);
    throw RenderError(error);
  }
  return program;
}

}  // namespace manibench

// Diffuse textures of mesh materials (an OBJ's map_Kd): texture coordinates
// read with the mesh, the image's orientation on the surface, repetition
// beyond [0, 1], one upload per file, identical bytes on every render, and
// the plain color (with one warning) where the image is missing or broken.
// The files are written by the test: a quad facing the camera and an 8x8
// image of four colored quadrants.
#include <manibench/renderer.hpp>
#include <manibench/scene.hpp>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "render_scenes.hpp"
#include "test_support.hpp"

namespace manibench {
namespace {

using namespace render_test;
using Rgb = std::array<int, 3>;

// The texture's quadrants as the image file stores them (rows top first).
constexpr Rgb kTopLeft{220, 30, 30}, kTopRight{30, 200, 40}, kBottomLeft{40, 50, 210},
    kBottomRight{230, 210, 20};

// A fresh folder under /tmp, removed with the object.
class TempFolder {
 public:
  TempFolder() {
    char name[] = "/tmp/manibench_texture_test_XXXXXX";
    const char* made = mkdtemp(name);
    EXPECT_NE(made, nullptr);
    path_ = made != nullptr ? made : "/tmp";
  }
  ~TempFolder() {
    std::error_code ignored;
    if (path_ != "/tmp") std::filesystem::remove_all(path_, ignored);
  }
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

// A binary PPM (P6), 8x8: four 4x4 quadrants of the colors above (stb_image
// reads it; 4 texels per quadrant leave each a region of its pure color
// under linear filtering).
std::string makeQuadrantImage() {
  std::string bytes = "P6\n8 8\n255\n";
  for (int row = 0; row < 8; ++row) {
    for (int col = 0; col < 8; ++col) {
      const Rgb& c =
          row < 4 ? (col < 4 ? kTopLeft : kTopRight) : (col < 4 ? kBottomLeft : kBottomRight);
      for (int k = 0; k < 3; ++k) bytes += static_cast<char>(c[static_cast<std::size_t>(k)]);
    }
  }
  return bytes;
}

// A 1 m square in the plane x = 0 facing -x (a camera at x < 0 looking
// along +x sees +y on its left, +z up), texture coordinates from (0, 0) at
// its bottom left as seen to (`repeat`, `repeat`) at its top right (OBJ: v
// up), material `diffuse` from `quad.mtl`.
void writeQuad(const TempFolder& folder, double repeat, const std::string& kd,
               const std::string& map_kd) {
  const std::string r = std::to_string(repeat);
  writeFile(folder.file("quad.mtl"),
            "newmtl surface\nKd " + kd + "\n" + (map_kd.empty() ? "" : "map_Kd " + map_kd + "\n"));
  writeFile(folder.file("quad.obj"),
            "mtllib quad.mtl\n"
            "v 0 0.5 -0.5\nv 0 -0.5 -0.5\nv 0 -0.5 0.5\nv 0 0.5 0.5\n"
            "vt 0 0\nvt " + r + " 0\nvt " + r + " " + r + "\nvt 0 " + r + "\n"
            "usemtl surface\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
}

// A scene of `visuals` copies of quad.obj, 1 m in front of the origin.
std::string quadUrdf(int visuals) {
  std::string urdf = "<robot name='quad'><link name='quad'>" + inertial();
  for (int k = 0; k < visuals; ++k) {
    urdf += "<visual><geometry><mesh filename='quad.obj'/></geometry></visual>";
  }
  return urdf + "</link></robot>";
}

// Ambient light 1 alone: a pixel's color is the surface's albedo.
LightingSpec getAlbedoLighting() {
  LightingSpec lighting;
  lighting.directional.clear();
  lighting.ambient = Eigen::Vector3f::Ones();
  return lighting;
}

CameraSpec getCamera() {
  CameraSpec camera;
  camera.name = "front";
  camera.width = 96;
  camera.height = 96;
  return camera;
}

// The color of the pixel that sees point (1, y, z) of the quad's plane from
// the camera at the origin looking along +x.
Rgb getColorAt(const CameraImages& images, double y, double z) {
  const double f = images.intrinsic(0, 0);
  const int col = static_cast<int>(std::floor(images.intrinsic(0, 2) - f * y));
  const int row = static_cast<int>(std::floor(images.intrinsic(1, 2) - f * z));
  const std::size_t i = 4 * (static_cast<std::size_t>(row) * images.width + col);
  return {images.rgba[i], images.rgba[i + 1], images.rgba[i + 2]};
}

void expectColor(const Rgb& actual, const Rgb& expected, const std::string& where) {
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(actual[k], expected[k], 2) << where << ", channel " << k;
  }
}

struct QuadScene {
  Scene scene;
  explicit QuadScene(const TempFolder& folder, int visuals = 1) {
    scene.addUrdfString(quadUrdf(visuals), folder.path(), "quad", at(1, 0, 0), true);
    scene.finalize();
  }
};

TEST(RendererTexture, MeshesCarryTheirTextureCoordinates) {
  TempFolder folder;
  writeQuad(folder, 1, "1 1 1", "quad.ppm");
  writeFile(folder.file("plain.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  Scene scene;
  scene.addUrdfString(
      "<robot name='two'><link name='two'>" + inertial() +
          "<visual><geometry><mesh filename='quad.obj'/></geometry></visual>"
          "<visual><geometry><mesh filename='plain.obj'/></geometry></visual></link></robot>",
      folder.path(), "two", Pose(), true);
  const std::vector<VisualShape>& visuals = scene.getVisualShapes();
  ASSERT_EQ(visuals.size(), 2u);
  const VisualMesh& quad = visuals[0].meshes->front();
  EXPECT_EQ(quad.texture, folder.file("quad.ppm"));
  ASSERT_EQ(quad.texture_coords.size(), quad.positions.size());
  for (std::size_t k = 0; k < quad.positions.size(); ++k) {
    // As the file has them (v up): u grows towards -y, v towards +z.
    const Eigen::Vector3f& p = quad.positions[k];
    EXPECT_NEAR(quad.texture_coords[k].x(), 0.5f - p.y(), 1e-6f) << k;
    EXPECT_NEAR(quad.texture_coords[k].y(), p.z() + 0.5f, 1e-6f) << k;
  }
  EXPECT_TRUE(visuals[1].meshes->front().texture_coords.empty());
}

TEST(RendererTexture, TextureAppearsUprightAndUnmirrored) {
  TempFolder folder;
  writeFile(folder.file("quad.ppm"), makeQuadrantImage());
  writeQuad(folder, 1, "1 1 1", "quad.ppm");
  QuadScene quad(folder);
  SceneRenderer renderer(quad.scene, getAlbedoLighting());
  EXPECT_EQ(renderer.getTextureCount(), 1u);
  CameraImages images;
  renderer.render(getCamera(), Pose(), images);
  // The image's top left on the quad's top left as the camera sees it
  // (+y is the camera's left): the quadrants' centres.
  expectColor(getColorAt(images, 0.25, 0.25), kTopLeft, "top left");
  expectColor(getColorAt(images, -0.25, 0.25), kTopRight, "top right");
  expectColor(getColorAt(images, 0.25, -0.25), kBottomLeft, "bottom left");
  expectColor(getColorAt(images, -0.25, -0.25), kBottomRight, "bottom right");
  // Segmentation as for any visual: the quad covers most of the image.
  EXPECT_GT(countHits(images), images.width * images.height / 2);
}

TEST(RendererTexture, MaterialColorMultipliesTheTexture) {
  TempFolder folder;
  writeFile(folder.file("quad.ppm"), makeQuadrantImage());
  writeQuad(folder, 1, "0.5 1 0.25", "quad.ppm");
  QuadScene quad(folder);
  SceneRenderer renderer(quad.scene, getAlbedoLighting());
  CameraImages images;
  renderer.render(getCamera(), Pose(), images);
  const Rgb expected{static_cast<int>(std::lround(kTopLeft[0] * 0.5)), kTopLeft[1],
                     static_cast<int>(std::lround(kTopLeft[2] * 0.25))};
  expectColor(getColorAt(images, 0.25, 0.25), expected, "top left");
  // A color set on the visual replaces the material, texture included.
  renderer.setVisualColor(0, Eigen::Vector4f(0.2f, 0.4f, 0.6f, 1));
  renderer.render(getCamera(), Pose(), images);
  expectColor(getColorAt(images, 0.25, 0.25), {51, 102, 153}, "set color");
}

TEST(RendererTexture, CoordinatesBeyondOneRepeatTheTexture) {
  TempFolder folder;
  writeFile(folder.file("quad.ppm"), makeQuadrantImage());
  writeQuad(folder, 2, "1 1 1", "quad.ppm");  // the image twice along each side
  QuadScene quad(folder);
  SceneRenderer renderer(quad.scene, getAlbedoLighting());
  CameraImages images;
  renderer.render(getCamera(), Pose(), images);
  // Texture coordinates (0.25, 1.75) and (1.75, 1.75): the top left and
  // top right quadrants of the first and second copy; (1.25, 0.25) is the
  // second copy's bottom left (clamping would give the bottom right).
  expectColor(getColorAt(images, 0.375, 0.375), kTopLeft, "(0.25, 1.75)");
  expectColor(getColorAt(images, -0.375, 0.375), kTopRight, "(1.75, 1.75)");
  expectColor(getColorAt(images, -0.125, -0.375), kBottomLeft, "(1.25, 0.25)");
}

TEST(RendererTexture, OneUploadPerFileAndTheSameBytesEveryRender) {
  TempFolder folder;
  writeFile(folder.file("quad.ppm"), makeQuadrantImage());
  writeQuad(folder, 1, "1 1 1", "quad.ppm");
  QuadScene quad(folder, /*visuals=*/3);
  CameraImages first, second, third;
  {
    SceneRenderer renderer(quad.scene);  // default lights: specular, Lambert
    EXPECT_EQ(renderer.getTextureCount(), 1u);
    renderer.render(getCamera(), Pose(), first);
    renderer.render(getCamera(), Pose(), second);
  }
  SceneRenderer again(quad.scene);
  again.render(getCamera(), Pose(), third);
  EXPECT_TRUE(first.rgba == second.rgba);
  EXPECT_TRUE(first.rgba == third.rgba);
  EXPECT_NE(getColorAt(first, 0.25, 0.25), getColorAt(first, -0.25, -0.25));
}

// A missing or undecodable image: the material's plain color, no throw, and
// one warning per file for the whole process, however many renderers.
void expectPlainColorWithOneWarning(const std::string& image_bytes, const std::string& reason) {
  TempFolder folder;
  if (!image_bytes.empty()) writeFile(folder.file("broken.ppm"), image_bytes);
  writeQuad(folder, 1, "0.2 0.6 0.4", "broken.ppm");
  QuadScene quad(folder);
  CameraImages images;
  RenderContext::get();  // whatever the driver says at its start is not captured
  ::testing::internal::CaptureStderr();
  for (int k = 0; k < 2; ++k) {
    SceneRenderer renderer(quad.scene, getAlbedoLighting());
    EXPECT_EQ(renderer.getTextureCount(), 0u);
    EXPECT_NO_THROW(renderer.render(getCamera(), Pose(), images));
    expectColor(getColorAt(images, 0.25, 0.25), {51, 153, 102}, "plain color");
    expectColor(getColorAt(images, -0.25, -0.25), {51, 153, 102}, "plain color");
  }
  const std::string err = ::testing::internal::GetCapturedStderr();
  testing::expectMentions(err, {folder.file("broken.ppm"), reason, "plain color"});
  EXPECT_EQ(err.find('\n'), err.size() - 1) << "one line: " << err;
}

TEST(RendererTexture, MissingTextureFileGivesThePlainColor) {
  expectPlainColorWithOneWarning("", "No such file or directory");
}

TEST(RendererTexture, UndecodableTextureFileGivesThePlainColor) {
  expectPlainColorWithOneWarning("not an image\n", "cannot decode");
}

}  // namespace
}  // namespace manibench

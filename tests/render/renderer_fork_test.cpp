// The headless renderer's EGL across fork(): a worker forked before any EGL
// call renders with its own context, a child of a process that has one gets
// a clear error instead of a hang, and EGL failures say what was tried.
// One concern of its own (processes, not images), apart from renderer_test.
#include <manibench/renderer.hpp>
#include <manibench/scene.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "render_scenes.hpp"

namespace manibench {
namespace {

using namespace render_test;

// Waits for a child up to `seconds`, killing it on timeout; returns the
// exit code, 128 + signal if signalled, or -1 on timeout.
int waitChild(pid_t pid, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + WTERMSIG(status);
}

// Runs `body` in a forked child and returns its exit code: body's result,
// 99 when it threw (the message goes to stderr), -1 when it hung, -2 when
// fork failed. The child leaves with _exit: no destructors, so whatever it
// shares with the parent (a renderer, a scene) stays the parent's.
template <typename Body>
int runInChild(Body body) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return -2;
  if (pid == 0) {
    alarm(60);
    int code = 99;
    try {
      code = body();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "child: %s\n", e.what());
    }
    _exit(code);
  }
  return waitChild(pid, 90);
}

// Runs first (declaration order) so that, when this program runs all its
// tests in one process, no context exists yet; ctest runs each test alone.
TEST(RendererFork, WorkerForkedBeforeEglRendersWithItsOwnContext) {
  if (RenderContext::exists()) {
    GTEST_SKIP() << "this process already created its EGL context; run this test alone";
  }
  const int code = runInChild([] {
    PlateScene plate;
    SceneRenderer renderer(plate.scene);
    CameraImages images;
    CameraSpec camera;
    camera.name = "front";
    renderer.render(camera, Pose(), images);
    return countHits(images) == camera.width * camera.height ? 0 : 2;
  });
  EXPECT_EQ(code, 0) << "the forked worker could not render (or hung)";
  EXPECT_FALSE(RenderContext::exists()) << "the child's context must not appear in the parent";
}

TEST(RendererFork, RefusingSoftwareRenderingSaysWhatWasFound) {
  if (RenderContext::exists()) GTEST_SKIP() << "needs a process without EGL; run alone";
  const int code = runInChild([] {
    RenderOptions options;
    options.allow_software = false;
    try {
      const RenderContext& context = RenderContext::get(options);
      return context.getInfo().software ? 1 : 0;  // a GPU machine: fine
    } catch (const RenderError& e) {
      const std::string message = e.what();
      std::fprintf(stderr, "child: %s\n", e.what());
      return message.find("software rendering refused") != std::string::npos &&
                     message.find("EGL_MESA_device_software") != std::string::npos &&
                     message.find("NVIDIA") != std::string::npos
                 ? 0
                 : 2;
    }
  });
  EXPECT_EQ(code, 0);
}

TEST(RendererFork, EglFailureNamesWhatWasTriedAndTheFix) {
  if (RenderContext::exists()) GTEST_SKIP() << "needs a process without EGL; run alone";
  const int code = runInChild([] {
    // GLVND reads this on the process's first EGL call: no vendor at all.
    setenv("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/none.json", 1);
    try {
      RenderContext::get();
      return 1;
    } catch (const RenderError& e) {
      const std::string message = e.what();
      for (const char* expected : {"EGL_EXT_platform_device", "EGL_MESA_platform_surfaceless",
                                   "/nonexistent/none.json", "50_mesa.json", "libegl-mesa0",
                                   "libgl1-mesa-dri", "NVIDIA"}) {
        if (message.find(expected) == std::string::npos) {
          std::fprintf(stderr, "child: '%s' missing from: %s\n", expected, e.what());
          return 2;
        }
      }
      return 0;
    }
  });
  EXPECT_EQ(code, 0);
}

TEST(RendererFork, ChildUsingTheParentsContextGetsAClearError) {
  PlateScene plate;
  SceneRenderer renderer(plate.scene);
  CameraSpec camera;
  camera.name = "front";
  CameraImages images;
  renderer.render(camera, Pose(), images);
  ASSERT_GT(countHits(images), 0);

  const int code = runInChild([&] {
    try {
      renderer.render(camera, Pose(), images);
      return 11;  // must not render
    } catch (const RenderError& e) {
      const std::string message = e.what();
      if (message.find("fork") == std::string::npos ||
          message.find(std::to_string(getppid())) == std::string::npos) {
        std::fprintf(stderr, "child: unclear message: %s\n", e.what());
        return 12;
      }
    }
    try {
      RenderContext::get();
      return 13;
    } catch (const RenderError&) {
    }
    try {
      SceneRenderer other(plate.scene);
      return 14;
    } catch (const RenderError&) {
    }
    return 0;
  });
  EXPECT_EQ(code, 0) << "exit 11: rendered in the child; -1: hung";
  // The parent is unaffected.
  renderer.render(camera, Pose(), images);
  EXPECT_EQ(countHits(images), camera.width * camera.height);
}

}  // namespace
}  // namespace manibench

#include "render/bench.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "dem/insertion.h"
#include "render/frames.h"

namespace render {
dem::TriangleMesh BoxMesh(const dem::Vec3& lo, const dem::Vec3& hi) {
  dem::TriangleMesh mesh;
  mesh.name = "box";
  for (int k = 0; k < 8; ++k) {
    mesh.vertices.push_back({(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z});
  }
  mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return mesh;
}

int BenchRender(const BenchRenderOptions& options) {
  namespace fs = std::filesystem;
  if (options.threads > 0) setenv("LP_NUM_THREADS", std::to_string(options.threads).c_str(), 1);

  // The bed: lattice layers of pitch 3.6 mm (spheres of 3.5 mm diameter), every other layer
  // shifted by half a pitch, each centre jittered by up to 0.04 mm (keeps the 0.1 mm gap open).
  constexpr double kRadius = 1.75e-3, kPitch = 3.6e-3;
  const dem::Vec3 box_min{0, 0, 0};
  const double box_x = 0.4, box_y = 0.3;
  const int nx = static_cast<int>(box_x / kPitch) - 1;
  const int ny = static_cast<int>(box_y / kPitch) - 1;
  const int64_t per_layer = static_cast<int64_t>(nx) * ny;
  const int64_t layers = (options.particles + per_layer - 1) / per_layer;
  const double top = kRadius + (layers - 1) * kPitch;
  const dem::Vec3 box_max{box_x, box_y, top + 0.05};  // 5 cm of headroom above the bed
  dem::Rng rng(7);
  dem::Particles p;
  p.x.reserve(options.particles);
  for (int64_t k = 0; k < options.particles; ++k) {
    const int64_t layer = k / per_layer, in_layer = k % per_layer;
    const double shift = (layer % 2) * 0.5 * kPitch;
    const dem::Vec3 x{
        box_min.x + kPitch + (in_layer % nx) * kPitch + shift + rng.Uniform(-4e-5, 4e-5),
        box_min.y + kPitch + (in_layer / nx) * kPitch + rng.Uniform(-4e-5, 4e-5),
        box_min.z + kRadius + layer * kPitch + rng.Uniform(0, 4e-5)};
    const double depth = top - x.z;
    const double speed = 0.05 * std::exp(-depth / 0.01) * rng.Uniform(0.5, 1.0);
    p.id.push_back(k);
    p.x.push_back(x);
    p.v.push_back({speed, 0, 0});
    p.radius.push_back(kRadius);
    p.material.push_back(0);
  }
  const dem::TriangleMesh scoop = BoxMesh({-0.04, -0.03, -0.02}, {0.04, 0.03, 0.02});

  const fs::path dir =
      !options.keep_dir.empty()
          ? fs::path(options.keep_dir)
          : fs::temp_directory_path() / ("scoopsim_bench_render_" + std::to_string(getpid()));
  FrameOptions frame_options;
  frame_options.dir = dir.string();
  frame_options.settings.camera.width = options.width;
  frame_options.settings.camera.height = options.height;
  frame_options.camera_preset = "trench_oblique";
  frame_options.png_level = options.png_level;
  frame_options.settings.cull_hidden = options.cull_hidden;
  frame_options.threads = options.threads;
  double png_bytes = 0;
  double wall = 0;
  std::string description;
  int frames_done = 0;
  double draw_s = 0, png_s = 0;
  size_t drawn = 0;
  {
    FrameSequence frames(frame_options);
    description = frames.renderer().Description();
    sim::WorldView view;
    view.particles = &p;
    view.box_min = box_min;
    view.box_max = box_max;
    view.gravity = {0, 0, -1.3};
    view.meshes.push_back({&scoop, {}});
    frames.Add(view);  // warm-up: shader compilation, first allocation (not timed)
    const double draw0 = frames.draw_seconds(), png0 = frames.png_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    for (int f = 0; f < options.frames; ++f) {
      view.time = 1e-2 * f;
      view.pass = 1;
      view.rho = 0.3 * f / std::max(options.frames, 1);
      view.force = 10 + f;
      view.meshes[0].pose.position = {0.05 + view.rho, 0.15, top};
      frames.Add(view);
    }
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    frames_done = options.frames;
    drawn = frames.renderer().drawn_particles();
    draw_s = frames.draw_seconds() - draw0;
    png_s = frames.png_seconds() - png0;
    for (int f = 1; f <= frames_done; ++f)
      png_bytes += static_cast<double>(fs::file_size(frames.FramePath(f)));
  }
  std::error_code ignored;
  if (options.keep_dir.empty()) fs::remove_all(dir, ignored);
  const char* lp = std::getenv("LP_NUM_THREADS");
  const int threads = lp != nullptr && std::atoi(lp) > 0
                          ? std::atoi(lp)
                          : static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  const int n = std::max(frames_done, 1);
  std::printf(
      "{\"bench\":\"render\",\"particles\":%lld,\"frames\":%d,\"width\":%d,\"height\":%d,"
      "\"threads\":%d,\"png_level\":%d,\"cull\":%s,\"fps\":%.3f,\"draw_ms\":%.2f,\"png_ms\":%.2f,"
      "\"png_kb\":%.1f,\"drawn\":%zu,\"renderer\":\"%s\"}\n",
      static_cast<long long>(options.particles), frames_done, options.width, options.height,
      threads, options.png_level, options.cull_hidden ? "true" : "false", frames_done / wall,
      1e3 * draw_s / n, 1e3 * png_s / n, png_bytes / n / 1024.0, drawn, description.c_str());
  return 0;
}

}  // namespace render

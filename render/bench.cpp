#include "render/bench.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "render/frames.h"
#include "sim/files/saved_run.h"
#include "sim/input/input_error.h"

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

  // The bed: the file's last snapshot, copied side by side (shifted by the box's floor size) on
  // a near-square grid until there are options.particles spheres. Copies do not interact: this
  // is a picture to draw, not a state to step.
  const sim::SavedRun run(options.bed);
  dem::Particles tile;
  run.ReadSnapshot(run.Snapshots().back(), &tile);
  const sim::StoredScene stored = run.Scene();
  dem::Vec3 box_min = stored.box_min, box_max = stored.box_max;
  if (!stored.has_box) {  // a scene without a box: the particles' extent
    box_min = {1e300, 1e300, 1e300};
    box_max = {-1e300, -1e300, -1e300};
    for (size_t i = 0; i < tile.x.size(); ++i) {
      const dem::Vec3& x = tile.x[i];
      const double r = tile.radius[i];
      box_min = {std::min(box_min.x, x.x - r), std::min(box_min.y, x.y - r),
                 std::min(box_min.z, x.z - r)};
      box_max = {std::max(box_max.x, x.x + r), std::max(box_max.y, x.y + r),
                 std::max(box_max.z, x.z + r)};
    }
  }
  const int64_t per_tile = static_cast<int64_t>(tile.x.size());
  if (per_tile == 0) throw sim::InputError(options.bed + ": its last snapshot has no particles");
  const int64_t wanted = options.particles > 0 ? options.particles : per_tile;
  const int64_t tiles = (wanted + per_tile - 1) / per_tile;
  const int64_t across = static_cast<int64_t>(std::ceil(std::sqrt(static_cast<double>(tiles))));
  const dem::Vec3 size = box_max - box_min;
  double top = box_min.z;
  dem::Particles p;
  p.x.reserve(wanted);
  for (int64_t k = 0; k < wanted; ++k) {
    const int64_t t = k / per_tile, i = k % per_tile;
    const dem::Vec3 shift{(t % across) * size.x, (t / across) * size.y, 0};
    p.id.push_back(k);
    p.x.push_back(tile.x[i] + shift);
    p.v.push_back(tile.v[i]);
    p.radius.push_back(tile.radius[i]);
    p.material.push_back(tile.material[i]);
    top = std::max(top, tile.x[i].z + tile.radius[i]);
  }
  const int64_t rows = (tiles + across - 1) / across;
  box_max = {box_min.x + std::min(tiles, across) * size.x, box_min.y + rows * size.y, box_max.z};
  const double length = box_max.x - box_min.x;
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
    view.gravity = stored.gravity;
    view.meshes.push_back({&scoop, {}});
    frames.Add(view);  // warm-up: shader compilation, first allocation (not timed)
    const double draw0 = frames.draw_seconds(), png0 = frames.png_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    for (int f = 0; f < options.frames; ++f) {
      view.time = 1e-2 * f;
      view.pass = 1;
      view.rho = 0.75 * length * f / std::max(options.frames, 1);
      view.force = 10 + f;
      view.meshes[0].pose.position = {box_min.x + 0.1 * length + view.rho,
                                      0.5 * (box_min.y + box_max.y), top};
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
      static_cast<long long>(wanted), frames_done, options.width, options.height, threads,
      options.png_level, options.cull_hidden ? "true" : "false", frames_done / wall,
      1e3 * draw_s / n, 1e3 * png_s / n, png_bytes / n / 1024.0, drawn, description.c_str());
  return 0;
}

}  // namespace render

// `scoopsim bench render`: frames per second of the renderer, PNG writing included, on a bed the
// project made (a bed file of `scoopsim bed` or a run's output). Public header of the render
// module.
#pragma once

#include <cstdint>
#include <string>

#include "sim/files/world_view.h"

namespace render {

// A closed box [lo, hi] as a triangle mesh in its body frame (12 triangles, counter-clockwise
// seen from outside): the benchmark's and the tests' stand-in for the scoop.
dem::TriangleMesh BoxMesh(const dem::Vec3& lo, const dem::Vec3& hi);

struct BenchRenderOptions {
  std::string bed;  // a bed file (`scoopsim bed`) or a run's output: its last particle snapshot
  int64_t particles = 200000;
  int frames = 20;
  int threads = 0;  // LP_NUM_THREADS (0: keep the environment's, else llvmpipe's default)
  int width = 1280, height = 720;
  int png_level = 1;
  bool cull_hidden = true;  // false: hand every particle to GL (to measure the culling)
  std::string keep_dir;     // when set, frames go here and stay (to look at them)
};

// Reads the last particle snapshot of `bed` (sim::SavedRun) and its box and gravity from the
// scene stored with it, and lays copies of it side by side on a near-square grid of the box's
// floor until there are `particles` spheres (the last copy cut short; 0: the file's own count).
// Renders `frames` frames of that bed with the trench_oblique camera and a box-shaped scoop moving
// over it, writes each as PNG to a temporary folder (removed afterwards), and prints one JSON
// line: bench, particles, frames, width, height, threads (LP_NUM_THREADS in effect; llvmpipe's
// default is the core count), png_level, cull, fps, draw_ms, png_ms (means per frame), png_kb
// (mean size), drawn (particles handed to GL in the last frame), renderer. Throws
// sim::InputError for a file that cannot be read as a bed or run.
int BenchRender(const BenchRenderOptions& options);

}  // namespace render

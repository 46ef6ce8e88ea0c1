// `scoopsim bench render`: frames per second of the renderer, PNG writing included, on a synthetic
// bed. Public header of the render module.
#pragma once

#include <cstdint>
#include <string>

#include "dem/mesh.h"

namespace render {

// A closed box [lo, hi] as a triangle mesh in its body frame (12 triangles, counter-clockwise
// seen from outside): the benchmark's and the tests' stand-in for the scoop.
dem::TriangleMesh BoxMesh(const dem::Vec3& lo, const dem::Vec3& hi);

struct BenchRenderOptions {
  int64_t particles = 200000;
  int frames = 20;
  int threads = 0;  // LP_NUM_THREADS (0: keep the environment's, else llvmpipe's default)
  int width = 1280, height = 720;
  int png_level = 1;
  bool cull_hidden = true;  // false: hand every particle to GL (to measure the culling)
  std::string keep_dir;     // when set, frames go here and stay (to look at them)
};

// Builds a bed of `particles` spheres of radius 1.75 mm (jittered, non-overlapping lattice layers
// in a 0.4 x 0.3 m box with 5 cm of headroom, speeds falling off with depth), renders `frames`
// frames of it with the trench_oblique camera and a box-shaped scoop moving through it, writes each
// as PNG to a temporary folder (removed afterwards), and prints one JSON line: bench, particles,
// frames, width, height, threads (LP_NUM_THREADS in effect; llvmpipe's default is the core count),
// png_level, cull, fps, draw_ms, png_ms (means per frame), png_kb (mean size), drawn (particles
// handed to GL in the last frame), renderer.
int BenchRender(const BenchRenderOptions& options);

}  // namespace render

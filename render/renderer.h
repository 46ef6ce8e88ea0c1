// Offscreen frames of a sim::WorldView through OSMesa (Mesa's software GL on llvmpipe, GL 4.5
// core; no display, no GPU). Public header of the render module.
//
// What a frame shows: particles as ray-cast sphere impostors drawn from point sprites, coloured by
// a field through a colour map and lit; the meshes of the view lit with flat normals (the scoop
// and obstacles light grey, the arm's links orange); the ground under the bed box and the box's
// edges; a caption (t, pass, rho, |F|), a colour bar, and with an arm its torque bars and fault
// flags. Threads: llvmpipe rasterises on LP_NUM_THREADS threads. Never call Render() while the
// DEM's OpenMP threads run (the run loop calls its frame callback between steps).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/color_map.h"
#include "render/image.h"
#include "sim/files/world_view.h"

namespace render {

// Lighting, in view space (camera looks down -z): a directional light towards kLightDirection
// (unnormalised here) and an ambient term. A surface of base colour c with unit normal n shows
//   c * (kAmbient + (1 - kAmbient) * max(0, n . L)),  L = kLightDirection / |kLightDirection|.
constexpr float kAmbient = 0.35f;
constexpr float kLightDirection[3] = {0.3f, 0.5f, 1.0f};

struct RenderSettings {
  Camera camera;
  ColorField color_by = ColorField::kSpeed;
  double range_min = 0;  // field value mapped to the bottom of the colour map
  double range_max = 1;  // ... and to the top (material: the palette is used instead)
  bool shading = true;   // false: flat colours (tests)
  bool scenery = true;   // ground under the bed box and the box edges
  bool overlays = true;  // caption and colour bar
  // Skip, before GL sees them, particles that other particles hide (see Renderer::Render). The
  // image is the same either way (tested); off only to check that.
  bool cull_hidden = true;
  Rgba8 background{235, 238, 242, 255};
};

class Renderer {
 public:
  // Creates the OSMesa context (GL 3.3 core or later). Sets LP_NUM_THREADS to `threads` when the
  // variable is unset and threads > 0 (llvmpipe reads it once, when the first context is made).
  // Throws std::runtime_error when OSMesa cannot make a context.
  explicit Renderer(int threads = 0);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders one frame at settings.camera's size. The image stays valid until the next call.
  //
  // Occlusion culling (settings.cull_hidden): llvmpipe shades every sprite fragment because the
  // impostors write their own depth (no early depth test), and its vertex stage runs on one
  // thread, so a deep bed would cost in proportion to all its particles though only the top
  // layers show. Before drawing, the particles are projected on the CPU. Pass 1: every pixel
  // centre surely inside a sphere's silhouette records the nearest "back" (centre depth + r) of
  // such spheres. Pass 2: a sphere with something nearer than its own front (centre depth - r)
  // at every pixel centre its silhouette could cover (a disk of the silhouette's semi-major axis
  // plus 1 px) cannot show, and is not handed to GL. 4 x 4 blocks of pixels keep their farthest
  // value, so pass 2 mostly reads one value per block.
  const Image& Render(const sim::WorldView& view, const RenderSettings& settings);

  // The last rendered image (empty before the first Render()).
  const Image& image() const;
  // Particles handed to GL by the last Render() (after culling).
  size_t drawn_particles() const;

  // "GL_RENDERER (GL_VERSION)", for logs.
  std::string Description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Caption text for a view: "t = 0.01234 s" on the run's one clock (README "One clock"), plus
// pass and rho when the view has a dig (pass > 0) and |F| when
// it has a dig or a force.
std::string Caption(const sim::WorldView& view);

// The arm's torque bars (bottom left, one per joint of view.joints, base to tip). The margin of a
// joint is m = 1 - |torque| / limit (the demanded torque's distance from the effort limit, as a
// fraction of it). The bar's filled length is min(|torque| / limit, 1) of its track, i.e.
// 1 - max(m, 0); its colour is kMarginOk (green) for m > kMarginLow, kMarginWarn (amber) for
// 0 < m <= kMarginLow, kMarginOver (red) for m <= 0 (at or over the limit: the joint saturates).
// Latched fault flags (view.faults) are written in red under the caption.
constexpr double kMarginLow = 0.25;
// The light plate behind the caption, the fault line and the torque bars (85% opaque).
constexpr Rgba8 kPlate{250, 250, 248, 217};
constexpr Rgba8 kMarginOk{46, 160, 67, 255};
constexpr Rgba8 kMarginWarn{235, 160, 20, 255};
constexpr Rgba8 kMarginOver{214, 39, 40, 255};
double TorqueMargin(const sim::JointView& joint);
double TorqueBarFraction(const sim::JointView& joint);
Rgba8 MarginColor(double margin);
// Draws the bars of `joints` into `image` at font scale `s`, labels and track outline in `ink`.
void DrawTorqueBars(Image* image, const std::vector<sim::JointView>& joints, int s, Rgba8 ink);

}  // namespace render

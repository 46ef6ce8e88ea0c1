// Numbered PNG frames of a run: DIR/frame_000000.png, frame_000001.png, ..., rendered from the
// views a run hands its frame callback (`scoopsim run --frames`) or read back from a saved run
// (`scoopsim render`), and optionally an MP4 made from them by ffmpeg. Public header.
#pragma once

#include <memory>
#include <string>

#include "render/renderer.h"
#include "sim/input/scene.h"
#include "sim/files/world_view.h"

namespace render {

struct FrameOptions {
  std::string dir;  // output folder (created)
  // Camera size, colouring, ... and the colour range (range_min, range_max) of every frame:
  // fixed for the whole sequence, so a colour means the same value in every frame.
  RenderSettings settings;
  std::string camera_preset;  // when not empty, frames the view's box with this preset
  bool range_given = false;   // settings' range was chosen by the user (--color-range); else
                              // the caller sets it: SceneColorRange (running), the whole run's
                              // AutoRange (saved, RenderSavedRun)
  int png_level = 1;          // zlib level
  int threads = 0;            // LP_NUM_THREADS when unset (0 = llvmpipe's default)
};

// The box a camera preset frames in `view` (render/camera.h): the bed container (trench_side,
// trench_oblique, top); it and every mesh of the view, the arm's links and scoop included (arm;
// FrameSequence keeps the union over the frames);
// a cube of side kScoopFrame centred on the scoop's mesh (scoop; the container without a scoop).
constexpr double kScoopFrame = 0.3;  // [m]
void PresetBounds(const std::string& preset, const sim::WorldView& view, dem::Vec3* lo,
                  dem::Vec3* hi);

// Frame options from a scene's `render:` block (camera, colour field, size). Throws
// sim::InputError for a colour field or preset this build does not know.
FrameOptions FrameOptionsFromSpec(const sim::RenderSpec& spec);

class FrameSequence {
 public:
  // Creates the folder (removing frame_NNNNNN.png files an earlier sequence left there) and the
  // renderer.
  explicit FrameSequence(FrameOptions options);
  ~FrameSequence();

  // Renders `view` and writes the next numbered frame, in the sequence's colour range. Call
  // between DEM steps only.
  void Add(const sim::WorldView& view);
  // Sets the colour range of the sequence; std::logic_error once a frame was written.
  void SetRange(double min, double max);
  // The arm preset frames at least this box in every frame (a saved run's union over all its
  // snapshots, so the camera never moves); without it, the box of the frames so far.
  void FrameAtLeast(const dem::Vec3& lo, const dem::Vec3& hi);

  int count() const { return count_; }
  const std::string& dir() const { return options_.dir; }
  std::string FramePath(int index) const;                // DIR/frame_NNNNNN.png
  double draw_seconds() const { return draw_seconds_; }  // summed over the frames so far
  double png_seconds() const { return png_seconds_; }
  const Renderer& renderer() const { return *renderer_; }
  const FrameOptions& options() const { return options_; }

 private:
  FrameOptions options_;
  bool framed_ = false;  // the arm preset's box so far: the camera moves only to grow it
  dem::Vec3 framed_lo_, framed_hi_;
  Camera framed_camera_;
  std::unique_ptr<Renderer> renderer_;
  int count_ = 0;
  double draw_seconds_ = 0, png_seconds_ = 0;
};

// Assembles DIR/frame_%06d.png into `mp4` with ffmpeg (H.264, yuv420p) at `fps`. Returns false
// with *message saying why (ffmpeg not installed, or it failed); true with the output path.
bool AssembleVideo(const std::string& dir, const std::string& mp4, double fps,
                   std::string* message);

}  // namespace render

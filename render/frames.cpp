#include "render/frames.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace render {

FrameOptions FrameOptionsFromSpec(const sim::RenderSpec& spec) {
  FrameOptions options;
  if (!ParseColorField(spec.color_by, &options.settings.color_by)) {
    throw sim::InputError("render.color_by: unknown field '" + spec.color_by + "'");
  }
  Camera& camera = options.settings.camera;
  camera.width = spec.width;
  camera.height = spec.height;
  camera.fov_y_deg = spec.fov_deg;
  if (spec.camera_preset.empty()) {
    camera.position = spec.camera_position;
    camera.target = spec.camera_target;
  } else {
    Camera probe = camera;
    if (!ApplyCameraPreset(spec.camera_preset, {0, 0, 0}, {1, 1, 1}, &probe)) {
      throw sim::InputError("render.camera: unknown preset '" + spec.camera_preset + "'");
    }
    options.camera_preset = spec.camera_preset;
  }
  return options;
}

FrameSequence::FrameSequence(FrameOptions options) : options_(std::move(options)) {
  namespace fs = std::filesystem;
  fs::create_directories(options_.dir);
  // Frames of an earlier, longer sequence would otherwise trail this one (and its video).
  for (const fs::directory_entry& entry : fs::directory_iterator(options_.dir)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && name.size() == 16 && name.compare(0, 6, "frame_") == 0 &&
        name.compare(12, 4, ".png") == 0 && name.find_first_not_of("0123456789", 6) == 12) {
      fs::remove(entry.path());
    }
  }
  renderer_ = std::make_unique<Renderer>(options_.threads);
}

FrameSequence::~FrameSequence() = default;

std::string FrameSequence::FramePath(int index) const {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%06d.png", index);
  return (std::filesystem::path(options_.dir) / name).string();
}

void FrameSequence::Add(const sim::WorldView& view) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  RenderSettings settings = options_.settings;
  if (!options_.camera_preset.empty()) {
    ApplyCameraPreset(options_.camera_preset, view.box_min, view.box_max, &settings.camera);
  }
  const Image& image = renderer_->Render(view, settings);
  const auto t1 = Clock::now();
  WritePng(FramePath(count_), image, options_.png_level);
  const auto t2 = Clock::now();
  draw_seconds_ += std::chrono::duration<double>(t1 - t0).count();
  png_seconds_ += std::chrono::duration<double>(t2 - t1).count();
  ++count_;
}

void FrameSequence::SetRange(double min, double max) {
  if (count_ > 0) throw std::logic_error("FrameSequence::SetRange: frames already written");
  options_.settings.range_min = min;
  options_.settings.range_max = max;
}

bool AssembleVideo(const std::string& dir, const std::string& mp4, double fps,
                   std::string* message) {
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0) {
    *message = "ffmpeg is not installed: no video made (the PNG frames are in " + dir +
               "; apt-get install ffmpeg to get --video)";
    return false;
  }
  // Even sizes for yuv420p; quiet unless something goes wrong. Paths are quoted for the shell.
  auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  char rate[32];
  std::snprintf(rate, sizeof(rate), "%g", fps);
  const std::string command =
      "ffmpeg -y -loglevel error -framerate " + std::string(rate) + " -i " +
      quote((std::filesystem::path(dir) / "frame_%06d.png").string()) +
      " -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -pix_fmt yuv420p " + quote(mp4);
  if (std::system(command.c_str()) != 0) {
    *message = "ffmpeg failed to make " + mp4;
    return false;
  }
  *message = "video " + mp4;
  return true;
}

}  // namespace render

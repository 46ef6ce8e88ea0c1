#include "render/frames.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace render {

void PresetBounds(const std::string& preset, const sim::WorldView& view, dem::Vec3* lo,
                  dem::Vec3* hi) {
  *lo = view.box_min;
  *hi = view.box_max;
  auto grow = [&](const dem::Vec3& p) {
    *lo = {std::min(lo->x, p.x), std::min(lo->y, p.y), std::min(lo->z, p.z)};
    *hi = {std::max(hi->x, p.x), std::max(hi->y, p.y), std::max(hi->z, p.z)};
  };
  if (preset == "arm") {
    for (const sim::MeshView& m : view.meshes)
      for (const dem::Vec3& v : m.mesh->vertices) grow(dem::Apply(m.pose, v));
  } else if (preset == "scoop") {
    dem::Vec3 scoop_lo{1e300, 1e300, 1e300}, scoop_hi{-1e300, -1e300, -1e300};
    for (const sim::MeshView& m : view.meshes) {
      if (m.role != sim::MeshRole::kScoop) continue;
      for (const dem::Vec3& v : m.mesh->vertices) {
        const dem::Vec3 p = dem::Apply(m.pose, v);
        scoop_lo = {std::min(scoop_lo.x, p.x), std::min(scoop_lo.y, p.y),
                    std::min(scoop_lo.z, p.z)};
        scoop_hi = {std::max(scoop_hi.x, p.x), std::max(scoop_hi.y, p.y),
                    std::max(scoop_hi.z, p.z)};
      }
    }
    if (scoop_lo.x <= scoop_hi.x) {
      const dem::Vec3 centre = 0.5 * (scoop_lo + scoop_hi);
      const dem::Vec3 half{0.5 * kScoopFrame, 0.5 * kScoopFrame, 0.5 * kScoopFrame};
      *lo = centre - half;
      *hi = centre + half;
    }
  }
}

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
    dem::Vec3 lo, hi;
    PresetBounds(options_.camera_preset, view, &lo, &hi);
    if (options_.camera_preset == "arm") {
      // A camera that followed the links' extent would jitter: it frames the box of every frame
      // so far (or the whole run's, FrameAtLeast) and moves only when a link leaves that box.
      const bool inside = framed_ && lo.x >= framed_lo_.x && lo.y >= framed_lo_.y &&
                          lo.z >= framed_lo_.z && hi.x <= framed_hi_.x && hi.y <= framed_hi_.y &&
                          hi.z <= framed_hi_.z;
      if (!inside) FrameAtLeast(lo, hi);
      settings.camera = framed_camera_;
    } else {
      ApplyCameraPreset(options_.camera_preset, lo, hi, &settings.camera);
    }
  }
  const Image& image = renderer_->Render(view, settings);
  const auto t1 = Clock::now();
  WritePng(FramePath(count_), image, options_.png_level);
  const auto t2 = Clock::now();
  draw_seconds_ += std::chrono::duration<double>(t1 - t0).count();
  png_seconds_ += std::chrono::duration<double>(t2 - t1).count();
  ++count_;
}

void FrameSequence::FrameAtLeast(const dem::Vec3& lo, const dem::Vec3& hi) {
  if (!framed_) {
    framed_lo_ = lo;
    framed_hi_ = hi;
    framed_ = true;
  }
  framed_lo_ = {std::min(framed_lo_.x, lo.x), std::min(framed_lo_.y, lo.y),
                std::min(framed_lo_.z, lo.z)};
  framed_hi_ = {std::max(framed_hi_.x, hi.x), std::max(framed_hi_.y, hi.y),
                std::max(framed_hi_.z, hi.z)};
  framed_camera_ = options_.settings.camera;
  ApplyCameraPreset("arm", framed_lo_, framed_hi_, &framed_camera_);
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

#include "render/camera.h"

#include <algorithm>
#include <cmath>

namespace render {
namespace {

constexpr double kPi = 3.14159265358979323846;

dem::Vec3 Normalized(const dem::Vec3& v) { return (1.0 / dem::Norm(v)) * v; }

// Right, true-up and forward unit vectors of a camera looking along `forward`.
void Basis(const dem::Vec3& forward_in, const dem::Vec3& up_in, dem::Vec3* right, dem::Vec3* up,
           dem::Vec3* forward) {
  *forward = Normalized(forward_in);
  dem::Vec3 r = dem::Cross(*forward, up_in);
  if (dem::Norm(r) < 1e-12) r = dem::Cross(*forward, dem::Vec3{0, 1, 0});  // up parallel to view
  *right = Normalized(r);
  *up = dem::Cross(*right, *forward);
}

struct Preset {
  const char* name;
  dem::Vec3 direction;  // from the box centre towards the eye
  dem::Vec3 up;
};

const Preset kPresets[] = {
    {"trench_side", {0, -1, 0.12}, {0, 0, 1}},
    {"trench_oblique", {-0.55, -1, 0.75}, {0, 0, 1}},
    {"top", {0, 0, 1}, {0, 1, 0}},
    // Over the arm's whole length and the trench: from the side (-y), a little ahead and above.
    {"arm", {0.3, -1, 0.35}, {0, 0, 1}},
    // Close on the scoop, as trench_oblique looks at the box.
    {"scoop", {-0.55, -1, 0.75}, {0, 0, 1}},
};

}  // namespace

Mat4 Multiply(const Mat4& a, const Mat4& b) {
  Mat4 c{};
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 4; ++row) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + row] * b[col * 4 + k];
      c[col * 4 + row] = s;
    }
  }
  return c;
}

Mat4 ViewMatrix(const Camera& camera) {
  dem::Vec3 r, u, f;
  Basis(camera.target - camera.position, camera.up, &r, &u, &f);
  const dem::Vec3& e = camera.position;
  // Rows: right, up, -forward; translation moves the eye to the origin.
  return {r.x,
          u.x,
          -f.x,
          0,  //
          r.y,
          u.y,
          -f.y,
          0,  //
          r.z,
          u.z,
          -f.z,
          0,  //
          -dem::Dot(r, e),
          -dem::Dot(u, e),
          dem::Dot(f, e),
          1};
}

void ClipPlanes(const Camera& camera, double* near_plane, double* far_plane) {
  const double distance = dem::Norm(camera.target - camera.position);
  *near_plane = camera.near_plane > 0 ? camera.near_plane : 1e-3 * distance;
  *far_plane = camera.far_plane > 0 ? camera.far_plane : 100 * distance;
}

Mat4 ProjectionMatrix(const Camera& camera) {
  double n = 0, f = 0;
  ClipPlanes(camera, &n, &f);
  const double t = 1.0 / std::tan(0.5 * camera.fov_y_deg * kPi / 180.0);
  const double aspect = static_cast<double>(camera.width) / camera.height;
  Mat4 p{};
  p[0] = t / aspect;
  p[5] = t;
  p[10] = (f + n) / (n - f);
  p[11] = -1;
  p[14] = 2 * f * n / (n - f);
  return p;
}

const std::vector<std::string>& CameraPresetNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> all;
    for (const Preset& p : kPresets) all.emplace_back(p.name);
    return all;
  }();
  return names;
}

bool ApplyCameraPreset(const std::string& name, const dem::Vec3& box_min, const dem::Vec3& box_max,
                       Camera* camera) {
  const Preset* preset = nullptr;
  for (const Preset& p : kPresets) {
    if (name == p.name) preset = &p;
  }
  if (preset == nullptr) return false;
  // Fit: the smallest eye distance d from the centre along the preset's direction at which every
  // box corner lies inside the frustum, i.e. |x_right| <= (d + z_forward) tan(fov_x / 2) and the
  // same for y, plus a 6% margin.
  const dem::Vec3 centre = 0.5 * (box_min + box_max);
  dem::Vec3 r, u, f;
  Basis(-preset->direction, preset->up, &r, &u, &f);
  const double tan_y = std::tan(0.5 * camera->fov_y_deg * kPi / 180.0);
  const double tan_x = tan_y * camera->width / camera->height;
  double d = 0;
  for (int k = 0; k < 8; ++k) {
    const dem::Vec3 corner{(k & 1) ? box_max.x : box_min.x, (k & 2) ? box_max.y : box_min.y,
                           (k & 4) ? box_max.z : box_min.z};
    const dem::Vec3 o = corner - centre;
    const double zf = dem::Dot(o, f);
    d = std::max({d, std::abs(dem::Dot(o, r)) / tan_x - zf, std::abs(dem::Dot(o, u)) / tan_y - zf});
  }
  d *= 1.06;
  camera->target = centre;
  camera->position = centre - d * f;
  camera->up = preset->up;
  return true;
}

}  // namespace render

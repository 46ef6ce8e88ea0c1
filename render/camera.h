// The camera of a frame: a pinhole looking from `position` at `target`, and the matrices that the
// renderer uploads. Public header of the render module.
#pragma once

#include <array>
#include <string>
#include <vector>

// dem::Vec3 comes with the view of the world (render/ reads sim/files and sim/input, never dem/).
#include "sim/files/world_view.h"

namespace render {

// Column-major 4x4 matrix, as OpenGL takes it: m[col * 4 + row].
using Mat4 = std::array<double, 16>;

struct Camera {
  dem::Vec3 position{0.5, -0.5, 0.5};  // eye [m], world frame
  dem::Vec3 target{0, 0, 0};           // point looked at [m]
  dem::Vec3 up{0, 0, 1};               // world direction that appears upwards in the image
  double fov_y_deg = 35;               // vertical field of view [deg]
  int width = 1280;                    // image size [px]
  int height = 720;
  double near_plane = 0;  // clip distances [m]; 0 = chosen from the distance to the target
  double far_plane = 0;
};

// World -> view (camera at the origin looking down -z, y up), the usual gluLookAt matrix.
Mat4 ViewMatrix(const Camera& camera);
// View -> clip: the usual gluPerspective matrix with the near/far planes resolved.
Mat4 ProjectionMatrix(const Camera& camera);
// Near/far planes actually used: the camera's, or 1e-3 and 100 times the distance to the target.
void ClipPlanes(const Camera& camera, double* near_plane, double* far_plane);
// Matrix product a * b.
Mat4 Multiply(const Mat4& a, const Mat4& b);

// Framing presets over a box: each looks at the box from a set direction at the distance where
// the whole box fits the field of view. The box is the bed container for the first three; the
// caller gives the others theirs (render/frames.h, PresetBounds):
//   trench_side     from -y, level with the top of the box: the trench in section
//   trench_oblique  from -x -y above: the default, scoop and trench in perspective
//   top             from straight above (+z), x to the right
//   arm             from -y, a little ahead (+x) and above, over the container and the whole arm
//                   (its links and scoop in every frame so far, a saved run's in all its
//                   snapshots: the camera moves only when a link leaves what it frames)
//   scoop           as trench_oblique, over a cube of 0.3 m around the scoop: follows it
const std::vector<std::string>& CameraPresetNames();
// False when `name` is not a preset (camera unchanged). Keeps width, height and fov_y_deg.
bool ApplyCameraPreset(const std::string& name, const dem::Vec3& box_min, const dem::Vec3& box_max,
                       Camera* camera);

}  // namespace render

// Triangle-mesh walls (the scoop): geometry in the mesh's own body frame, moved kinematically by
// the caller every step (pose + twist). Public header of the dem module.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "dem/transform.h"
#include "dem/vec3.h"

namespace dem {

struct TriangleMesh {
  std::string name;
  std::vector<Vec3> vertices;                     // [m] in the body frame (V)
  std::vector<std::array<int32_t, 3>> triangles;  // vertex indices, counter-clockwise seen from
                                                  // outside (T)
  int material = 0;                               // index into the MaterialTable
};

// Kinematic state of a mesh: pose of its body frame and the velocity of that frame's origin.
struct MeshMotion {
  Pose pose;
  Vec3 velocity;          // of the body origin [m/s], world frame
  Vec3 angular_velocity;  // [rad/s], world frame
};

}  // namespace dem

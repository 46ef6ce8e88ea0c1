// A read-only view of the world at one instant, handed to observers such as the renderer
// (render/ reads sim/, never the other way) and to the snapshots' meshes (H5Output). Valid only
// during the callback that receives it.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "dem/mesh.h"
#include "dem/system.h"

namespace sim {

// What a mesh of the view is: the tool, a fixed obstacle, or a link of the arm that holds the tool.
enum class MeshRole { kScoop, kObstacle, kArmLink };

// The name of a role's meshes in the snapshots (/snapshots/NNNNNN/meshes/<name>) and the XDMF.
inline const char* MeshRoleName(MeshRole role) {
  switch (role) {
    case MeshRole::kScoop:
      return "scoop";
    case MeshRole::kObstacle:
      return "obstacles";
    case MeshRole::kArmLink:
      return "arm";
  }
  return "?";
}

struct MeshView {
  const dem::TriangleMesh* mesh = nullptr;  // body-frame geometry
  dem::Pose pose;                           // body -> world
  MeshRole role = MeshRole::kScoop;
};

// A joint of the arm: its demanded torque against its effort limit (the torque bars of a frame).
struct JointView {
  std::string name;
  double torque = 0;  // demanded [N m] (the PID's output before the clamp)
  double limit = 0;   // effort limit, derated [N m], > 0
};

struct WorldView {
  double time = 0;    // simulated time, on the run's one clock (README "One clock") [s]
  int pass = 0;       // dig pass (1-based); 0 when the scene has no dig
  double rho = 0;     // distance along the trench since first contact [m]
  double force = 0;   // |F| on the scoop [N]
  double torque = 0;  // |T| on the scoop about its CoM [N m]
  const dem::Particles* particles = nullptr;
  std::vector<MeshView> meshes;
  std::vector<JointView> joints;  // the arm's joints, base to tip; empty without an arm
  std::string faults;             // the arm's latched fault flags by name ("" when none)
  dem::Vec3 box_min, box_max;     // bed container [m]
  dem::Vec3 gravity;              // [m/s^2]
  // Broken bonds of each particle of *particles, in its order (a bonded bed, issue 44; render's
  // colour field broken_bonds); empty without bonds.
  std::vector<float> broken_bonds;
};

// Called by the run loop between steps (never while the DEM's OpenMP threads run).
using FrameCallback = std::function<void(const WorldView&)>;

}  // namespace sim

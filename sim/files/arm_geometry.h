// The arm's links as triangle meshes, for the frames (render/) and the snapshots' meshes (the
// XDMF): one mesh per moving body of the chain but the last, in its body frame (the URDF link
// frame), made of the shapes of its links: their <visual> shapes, or their <collision> shapes
// for a link that has no visual one. Boxes are 12 triangles; cylinders and spheres are faceted
// (kSegments around); mesh shapes are read with sim::LoadMesh and scaled. The last body
// (l_scoop) is left out: the scoop is drawn from the DEM's own mesh at its DEM pose.
// Public header of sim; the arm's types stay in arm_geometry.cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dem/mesh.h"
#include "dem/transform.h"
#include "sim/files/world_view.h"

namespace arm {
struct ArmModel;
}

namespace sim {

// Where the arm's base_link stands in the world (the /arm/ attributes arm_base_x, _y, _z, _yaw).
struct ArmBase {
  dem::Vec3 position;  // [m]
  double yaw = 0;      // about world z [rad]
};

class ArmGeometry {
 public:
  static constexpr int kSegments = 16;  // facets around a cylinder or a sphere

  // The links of `model`. Throws sim::InputError (one line) for a mesh shape that cannot be read.
  explicit ArmGeometry(std::shared_ptr<const arm::ArmModel> model);
  // The links of the URDF at `urdf_path` (a saved run's arm_urdf); InputError for a bad URDF.
  static ArmGeometry FromUrdf(const std::string& urdf_path);

  int dof() const;
  int parts() const { return static_cast<int>(meshes_.size()); }
  const dem::TriangleMesh& mesh(int part) const { return meshes_[part]; }
  int body(int part) const { return bodies_[part]; }  // index in ArmModel::bodies (1..dof-1)

  // The parts' poses (body frame -> world) at joint positions q (dof values) [rad].
  std::vector<dem::Pose> Poses(const double* q, const ArmBase& base) const;
  // Appends the parts at q to view->meshes (role kArmLink). The view points into this object.
  void AddToView(const double* q, const ArmBase& base, WorldView* view) const;

 private:
  std::shared_ptr<const arm::ArmModel> model_;
  std::vector<dem::TriangleMesh> meshes_;
  std::vector<int> bodies_;
};

// The names of the fault flags set in `bits` (arm/fault_monitor.h), joined by spaces:
// "JOINT_TORQUE_LIMIT"; "" for none.
std::string FaultNames(uint64_t bits);

}  // namespace sim

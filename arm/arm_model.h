// The arm as a plain description of our own: a serial chain of bodies and revolute joints from a
// URDF's root link to a named tip link (l_scoop), with inertials, limits, damping, friction and
// joint origins. Loaded from a URDF with urdfdom; no urdfdom type leaves arm_model.cpp.
//
// Bodies and links. A body is what one chain joint moves rigidly: the URDF link that is the
// joint's child, plus every link hung on it through `fixed` joints (the grinder on l_hand, the
// massless l_scoop_tip frame on l_scoop), merged into one inertial. bodies[0] is the fixed base
// (the URDF root link); bodies[i] (i = 1..n) is moved by joints[i - 1]. A body's frame is the URDF
// frame of its own link; a merged link keeps its place as a Frame of the body.
//
// Frames (the merge rule, as Gazebo and KDL treat such links): a link hung on its body through
// fixed (or held) joints whose <inertial> is missing or has a mass of at most kFrameMass (1 g) is
// a frame: it keeps its place (a Frame of the body) but adds no mass and no inertia, and its
// inertial is not checked (the lander's l_scoop_tip: 0.001 kg with a 1 kg m^2 placeholder inertia
// that would otherwise swamp the 0.31 kg scoop's; tool frames such as l_grinder_tip with none or a
// zero mass). Heavier links are merged with their mass and inertia (the grinder). A link that a
// chain joint moves itself must have an <inertial> with a mass above kFrameMass, else the load is
// refused naming it. Every link merged into another's body is listed in ArmModel::merges.
//
// Off-chain joints: a `revolute`, `continuous` or `prismatic` joint that is not on the path from
// the root to the tip is held at zero and its child merged like a fixed one (it is listed in
// ArmModel::held_joints). On the chain only `revolute` and `continuous` are supported.
//
// The joints must make the links a tree: a link that is the child of two joints, or a loop of
// joints, is refused naming the joint (the second parent, the loop's first joint in the file).
//
// Bad input throws ArmModelError, one line: "FILE:LINE: ELEMENT: expected ..., got ..." (LINE is
// left out where the element has none, e.g. a missing file).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace arm {

// Bad URDF input (the CLI exits 2 on it).
class ArmModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class JointType { kRevolute, kContinuous };

const char* JointTypeName(JointType type);

// Mass properties of a body.
struct Inertial {
  double mass = 0;                                    // [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      // centre of mass in the body frame [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // about the CoM, body-frame axes [kg m^2]
};

// A visual or collision shape of a link (for drawing and for the DEM's moving mesh).
struct Shape {
  enum class Kind { kMesh, kBox, kCylinder, kSphere };
  Kind kind = Kind::kBox;
  std::string link;                                          // URDF link it belongs to
  bool collision = false;                                    // <collision> (else <visual>)
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // shape frame in the body frame
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // box: x y z; cylinder: radius, length, 0;
                                                   // sphere: radius, 0, 0; mesh: scale x y z [m]
  std::string mesh_path;  // mesh: the file name, resolved against the URDF's folder
};

// A URDF link merged into a body, and where it sits in the body frame.
struct Frame {
  std::string link;
  Eigen::Isometry3d in_body = Eigen::Isometry3d::Identity();
};

struct Body {
  std::string link;           // the URDF link whose frame is the body frame
  Inertial inertial;          // the link and its merged links together
  std::vector<Frame> frames;  // every link of the body, itself first (identity)
  std::vector<Shape> shapes;  // shapes of all its links, in the body frame
};

// The heaviest link that is still a frame (see the merge rule above) [kg].
constexpr double kFrameMass = 1e-3;

// A link merged into the body of another (through fixed or held joints).
struct MergedLink {
  std::string link;           // the merged link
  std::string body_link;      // the link of the body it went to
  std::string joint;          // the joint that hangs it on its parent
  std::string joint_type;     // "fixed", or "held" (an off-chain movable joint held at zero)
  bool frame = false;         // a frame: mass and inertia dropped (see the merge rule)
  bool has_inertial = false;  // it had an <inertial>
  double mass = 0;            // its mass as written [kg] (0 without an <inertial>)
};

struct Joint {
  std::string name;
  JointType type = JointType::kRevolute;
  // Joint frame in the parent body's frame; at q = 0 it is the child body's frame, and at q the
  // child frame is origin * AngleAxis(q, axis).
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, in the joint (child) frame
  bool has_position_limits = false;  // revolute: true; continuous: false (lower/upper ignored)
  double lower = 0, upper = 0;       // [rad] when has_position_limits
  double effort = 0;                 // torque limit, the motor's saturation [N m], > 0
  double velocity = 0;               // velocity limit [rad/s], > 0
  double damping = 0;                // viscous damping [N m s/rad], >= 0
  double friction = 0;               // Coulomb friction [N m], >= 0
  int line = 0;                      // line of <joint> in the URDF (0 if unknown)
};

struct ArmModel {
  std::string source;         // the URDF's path (or the name given to ParseArmModel)
  std::string robot_name;     // <robot name>
  std::string tip_link;       // the chain's last link (l_scoop)
  std::vector<Body> bodies;   // bodies[0] the fixed base; bodies[i] moved by joints[i - 1]
  std::vector<Joint> joints;  // the chain from the base to the tip, n = dof()
  std::vector<std::string> held_joints;  // off-chain movable joints held at zero
  std::vector<MergedLink> merges;        // every link merged into another's body, by name

  int dof() const { return static_cast<int>(joints.size()); }
  // Mass of the moving bodies (the base excluded) [kg].
  double MovingMass() const;
  // Index of a chain joint by name, or -1.
  int JointIndex(const std::string& name) const;
  // Which body a URDF link belongs to and where it sits in the body frame; false if the URDF has
  // no such link.
  bool FindLink(const std::string& link, int* body, Eigen::Isometry3d* in_body) const;
};

// Loads a URDF file; the chain ends at `tip_link`. A URDF of more than 64 MiB is refused (a URDF
// names its meshes, it does not hold them); the text is read in time linear in its size.
ArmModel LoadArmModel(const std::string& path, const std::string& tip_link = "l_scoop");
// Parses URDF text. `source` names it in messages; mesh file names are resolved against
// `base_dir` (empty: left as written).
ArmModel ParseArmModel(const std::string& urdf_text, const std::string& source,
                       const std::string& tip_link = "l_scoop", const std::string& base_dir = "");

// `model` with each joint's effort limit multiplied by its factor (a worn motor's derate, in
// (0, 1]; one per joint, missing ones 1): effort_i x factors_i, the limit the controller clamps at
// and the fault monitor compares with. The URDF's own values stay in the model it was read into.
ArmModel Derated(const ArmModel& model, const std::vector<double>& factors);

// Named poses of the lander's arm (joint order 1..6, shared/FACTS.md section 2), for the gravity
// torques of `scoopsim arm info` and for tests:
//   zero      all joints at 0: the arm stretched out (the reach-out pose)
//   stowed    folded against the lander for flight
//   unstowed  the lander's ready pose after unstowing
//   digging   the lander's dig-ready pose (scoop above the ground, pointing down)
struct NamedPose {
  const char* name;
  std::array<double, 6> q;  // [rad]
};
constexpr std::array<NamedPose, 4> kLanderPoses = {{
    {"zero", {0, 0, 0, 0, 0, 0}},
    {"stowed", {-1.5, 1.5708, -2.65, 2.9, 0, 0}},
    {"unstowed", {0, 1.5707, -1.5707, 0, 1.5707, 0}},
    {"digging", {0, 0.8537, -1.5707, 0.7171, 1.5, 0}},
}};

}  // namespace arm

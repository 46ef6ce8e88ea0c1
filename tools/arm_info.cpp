#include "tools/arm_info.h"

#include <cmath>
#include <vector>

#include "arm/arm_model.h"
#include "arm/kinematics.h"

namespace tools {

void PrintArmInfo(const std::string& urdf, double g, std::FILE* out) {
  const arm::ArmModel model = arm::LoadArmModel(urdf);
  const int n = model.dof();
  std::fprintf(out, "arm: %s (robot '%s'), chain %s -> %s, %d joints\n", model.source.c_str(),
               model.robot_name.c_str(), model.bodies[0].link.c_str(), model.tip_link.c_str(), n);
  std::fprintf(out, "%-3s %-14s %-10s %8s %8s %8s %8s %8s %8s  %s\n", "#", "joint", "type", "lower",
               "upper", "effort", "velocity", "damping", "friction", "moves (mass kg)");
  for (int i = 0; i < n; ++i) {
    const arm::Joint& j = model.joints[i];
    const arm::Body& b = model.bodies[i + 1];
    std::string moves = b.link;
    for (size_t f = 1; f < b.frames.size(); ++f) moves += " + " + b.frames[f].link;
    char lower[16] = "-", upper[16] = "-";
    if (j.has_position_limits) {
      std::snprintf(lower, sizeof lower, "%.3f", j.lower);
      std::snprintf(upper, sizeof upper, "%.3f", j.upper);
    }
    std::fprintf(out, "%-3d %-14s %-10s %8s %8s %8.2f %8.3f %8.2f %8.2f  %s (%.4f)\n", i + 1,
                 j.name.c_str(), arm::JointTypeName(j.type), lower, upper, j.effort, j.velocity,
                 j.damping, j.friction, moves.c_str(), b.inertial.mass);
  }
  std::fprintf(out, "units: rad, N m, rad/s, N m s/rad; '-': continuous, no position limits\n");
  if (!model.held_joints.empty()) {
    std::fprintf(out, "held at zero (off the chain):");
    for (const std::string& h : model.held_joints) std::fprintf(out, " %s", h.c_str());
    std::fprintf(out, "\n");
  }
  // Every link merged into another's body, one line each (the merge rule: arm/arm_model.h).
  for (const arm::MergedLink& m : model.merges) {
    char mass[64] = "no <inertial>";
    if (m.has_inertial) std::snprintf(mass, sizeof mass, "%.6g kg", m.mass);
    std::fprintf(out, "merged: %s (%s, %s joint %s) into %s: %s\n", m.link.c_str(), mass,
                 m.joint_type.c_str(), m.joint.c_str(), m.body_link.c_str(),
                 m.frame ? "a frame (mass and inertia dropped)" : "mass and inertia added");
  }
  const double base = model.bodies[0].inertial.mass;
  std::fprintf(out, "mass: moving %.4f kg, base %.4f kg, total %.4f kg\n", model.MovingMass(), base,
               model.MovingMass() + base);

  // Gravity torques at the named poses: the torques that hold the arm still there.
  std::vector<arm::NamedPose> poses;
  for (const arm::NamedPose& p : arm::kLanderPoses) {
    if (n == 6 || std::string(p.name) == "zero") poses.push_back(p);
  }
  std::fprintf(out,
               "gravity torques [N m, 6 significant digits] at g = %g m/s^2 (-z of %s); '!' marks "
               "|tau| > effort\n",
               g, model.bodies[0].link.c_str());
  std::fprintf(out, "%-10s", "pose");
  for (int i = 0; i < n; ++i) std::fprintf(out, " %13s", model.joints[i].name.c_str());
  std::fprintf(out, "\n");
  for (const arm::NamedPose& p : poses) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n && i < 6; ++i) q[i] = p.q[i];
    const Eigen::VectorXd tau = arm::GravityTorques(model, q, Eigen::Vector3d(0, 0, -g));
    std::fprintf(out, "%-10s", p.name);
    for (int i = 0; i < n; ++i) {
      const bool over = std::abs(tau[i]) > model.joints[i].effort;
      std::fprintf(out, " %12.6g%c", tau[i], over ? '!' : ' ');
    }
    std::fprintf(out, "\n");
  }
}

}  // namespace tools

// Links scoopsim::arm alone (find_package(scoopsim COMPONENTS arm)) and loads the installed
// URDF (scoopsim_DATA_DIR/assets/lander_arm.urdf): its dof (6). Then two independent models of the
// same arm: the joint torques of arm::GravityTorques (our Newton-Euler in Eigen, from the URDF's
// inertials), applied to the Bullet arm (btMultiBody) at rest at q = (0.3, -0.5, 0.8, -0.4, 0.2,
// 0.1) rad under Mars's 3.71 m/s^2, must hold it: the joint accelerations of one step are below
// 1e-9 of those of the arm let fall (no torques) from the same state (4e-15 on GCC 12, x86-64).
// Exit 0 when dof = 6 and the arm is held, 1 otherwise.
#include <cstdio>

#include "arm/arm_model.h"
#include "arm/bullet_arm.h"
#include "arm/kinematics.h"

int main() {
  const arm::ArmModel model = arm::LoadArmModel(SCOOPSIM_URDF);
  std::printf("arm_hold: %s: robot %s, dof %d, moving mass %.4f kg\n", SCOOPSIM_URDF,
              model.robot_name.c_str(), model.dof(), model.MovingMass());
  if (model.dof() != 6) return 1;

  arm::BulletArmOptions options;
  options.gravity = Eigen::Vector3d(0, 0, -3.71);
  options.joint_damping = false;
  options.joint_friction = false;
  Eigen::VectorXd q(6);
  q << 0.3, -0.5, 0.8, -0.4, 0.2, 0.1;
  double qdd_max[2] = {0, 0};  // [0] let fall, [1] held by GravityTorques
  for (int held = 0; held < 2; ++held) {
    arm::BulletArm bullet(model, options);
    bullet.SetJointState(q);
    if (held) bullet.SetJointTorques(arm::GravityTorques(model, q, options.gravity));
    bullet.Step(1e-4);
    qdd_max[held] = bullet.qdd().cwiseAbs().maxCoeff();
  }
  std::printf(
      "arm_hold: max |qdd| let fall %.4g rad/s^2, held by GravityTorques %.3g rad/s^2 "
      "(ratio %.2g, tolerance 1e-9)\n",
      qdd_max[0], qdd_max[1], qdd_max[1] / qdd_max[0]);
  return qdd_max[1] <= 1e-9 * qdd_max[0] ? 0 : 1;
}

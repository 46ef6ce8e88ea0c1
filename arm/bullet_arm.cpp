#include "arm/bullet_arm.h"

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

static_assert(sizeof(btScalar) == sizeof(double),
              "scoopsim needs Bullet's double-precision build (pkg-config bullet-float64, "
              "BT_USE_DOUBLE_PRECISION)");

namespace arm {

namespace {

btVector3 BtVec(const Eigen::Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }
Eigen::Vector3d Eig(const btVector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); }
btQuaternion BtQuat(const Eigen::Matrix3d& r) {
  const Eigen::Quaterniond q(r);
  return btQuaternion(q.x(), q.y(), q.z(), q.w());
}
Eigen::Isometry3d Eig(const btTransform& t) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const btMatrix3x3& b = t.getBasis();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.linear()(r, c) = b[r][c];
  }
  out.translation() = Eig(t.getOrigin());
  return out;
}

// A collision filter no broadphase pair passes: the colliders never touch anything.
constexpr int kNoCollisionGroup = 0;
constexpr int kNoCollisionMask = 0;

}  // namespace

struct BulletArm::Impl {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btMultiBodyConstraintSolver solver;
  btMultiBodyDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::unique_ptr<btMultiBody> body;
  std::vector<std::unique_ptr<btBoxShape>> shapes;
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders;
  // Scratch for Bullet's dynamics routines (sized once).
  btAlignedObjectArray<btScalar> scratch_r;
  btAlignedObjectArray<btVector3> scratch_v;
  btAlignedObjectArray<btMatrix3x3> scratch_m;
  btAlignedObjectArray<btQuaternion> world_to_local;
  btAlignedObjectArray<btVector3> local_origin;
  // Per link (joint i moves link i), for the mass matrix: the joint axis and the pivot-to-CoM
  // offset in Bullet's link frame (principal axes at the CoM), the mass and principal moments.
  std::vector<Eigen::Vector3d> axis_local, pivot_to_com;
  // The composite rigid body algorithm's scratch, world axes: per link the axis, pivot, and the
  // composite body of the links from it outward (mass, CoM, inertia about that CoM).
  std::vector<Eigen::Vector3d> axis, pivot, composite_com;
  std::vector<Eigen::Matrix3d> composite_inertia;
  std::vector<double> composite_mass;
  // The rate solve (bullet_arm.h): mass matrix, the system of the current guess (padded with
  // identity to n x n), the solve's vectors and the guess (sized once: the step allocates
  // nothing).
  Eigen::MatrixXd mass, system, identity;
  Eigen::LLT<Eigen::MatrixXd> llt_system;
  Eigen::VectorXd v_free, m_v_free, v, v_saved, residual, rhs, x, qd_old, damping, friction;
  std::vector<int> slide;   // per joint: +1 / -1 sliding that way, 0 stuck (friction > 0 only)
  std::vector<int> motor;   // per joint: 0 servo linear, +1 at its upper bound, -1 at its lower
  std::vector<int> moving;  // the joints the current guess lets move
  mutable std::vector<btVector3> omega, vel;  // link velocities for BodyTwist
  // Wrenches for the next step (world axes, force at the CoM, torque about the CoM).
  std::vector<Eigen::Vector3d> force, torque;

  ~Impl() {
    for (auto& c : colliders) world.removeCollisionObject(c.get());
    if (body) world.removeMultiBody(body.get());
  }
};

BulletArm::BulletArm(const ArmModel& model, const BulletArmOptions& options)
    : model_(model), gravity_(options.gravity), options_(options), impl_(new Impl) {
  const int n = model_.dof();
  const int nb = n + 1;
  principal_.assign(nb, Eigen::Isometry3d::Identity());
  moments_.assign(nb, Eigen::Vector3d::Ones());
  // Principal frames: the base keeps its link frame (a fixed base's inertia is never used).
  for (int b = 1; b < nb; ++b) {
    const Inertial& in = model_.bodies[b].inertial;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(in.inertia);
    Eigen::Matrix3d axes = eig.eigenvectors();
    if (axes.determinant() < 0) axes.col(2) = -axes.col(2);  // a rotation, not a reflection
    principal_[b].linear() = axes;
    principal_[b].translation() = in.com;
    moments_[b] = eig.eigenvalues();
  }

  const double base_mass = model_.bodies[0].inertial.mass > 0 ? model_.bodies[0].inertial.mass : 1;
  impl_->body = std::make_unique<btMultiBody>(n, base_mass, btVector3(1, 1, 1),
                                              /*fixedBase=*/true, /*canSleep=*/false);
  btMultiBody& mb = *impl_->body;
  for (int i = 0; i < n; ++i) {
    const Joint& j = model_.joints[i];
    const Eigen::Isometry3d& pp = principal_[i];      // parent's principal frame, parent body
    const Eigen::Isometry3d& pc = principal_[i + 1];  // own principal frame, own body
    const Eigen::Isometry3d offset_in_parent = pp.inverse() * j.origin;
    const Eigen::Matrix3d rot_parent_to_this =
        pc.linear().transpose() * j.origin.linear().transpose() * pp.linear();
    mb.setupRevolute(i, model_.bodies[i + 1].inertial.mass, BtVec(moments_[i + 1]), i - 1,
                     BtQuat(rot_parent_to_this), BtVec(pc.linear().transpose() * j.axis),
                     BtVec(offset_in_parent.translation()),
                     BtVec(pc.linear().transpose() * pc.translation()),
                     /*disableParentCollision=*/true);
  }
  mb.finalizeMultiDof();
  // Bullet's defaults that are not physics: body damping 0.04, sleeping, 100 rad/s clamp.
  mb.setLinearDamping(0);
  mb.setAngularDamping(0);
  mb.setCanSleep(false);
  mb.setMaxCoordinateVelocity(std::numeric_limits<btScalar>::max());
  mb.setHasSelfCollision(false);
  btTransform base;
  base.setOrigin(BtVec(Eigen::Vector3d(options.base_pose.translation())));
  base.setBasis(btMatrix3x3(BtQuat(Eigen::Matrix3d(options.base_pose.linear()))));
  mb.setBaseWorldTransform(base);

  impl_->world.setGravity(btVector3(0, 0, 0));  // gravity is added per link in Step()
  impl_->world.addMultiBody(&mb);

  // Colliders: a box with the body's principal moments (I1 = m (b^2 + c^2) / 12, ...), in the
  // principal frame; in no collision group.
  for (int b = 0; b < nb; ++b) {
    Eigen::Vector3d half(0.05, 0.05, 0.05);
    const double m = model_.bodies[b].inertial.mass;
    if (b > 0 && m > 0) {
      const Eigen::Vector3d& i = moments_[b];
      const Eigen::Vector3d sq(i[1] + i[2] - i[0], i[0] + i[2] - i[1], i[0] + i[1] - i[2]);
      for (int k = 0; k < 3; ++k) half[k] = 0.5 * std::sqrt(std::max(6 * sq[k] / m, 1e-6));
    }
    impl_->shapes.push_back(std::make_unique<btBoxShape>(BtVec(half)));
    auto collider = std::make_unique<btMultiBodyLinkCollider>(&mb, b - 1);
    collider->setCollisionShape(impl_->shapes.back().get());
    collider->setActivationState(DISABLE_DEACTIVATION);
    impl_->world.addCollisionObject(collider.get(), kNoCollisionGroup, kNoCollisionMask);
    if (b == 0) {
      mb.setBaseCollider(collider.get());
    } else {
      mb.getLink(b - 1).m_collider = collider.get();
    }
    impl_->colliders.push_back(std::move(collider));
  }

  Impl& s = *impl_;
  s.mass = s.system = s.identity = Eigen::MatrixXd::Identity(n, n);
  // Sized by a first factorisation, not by assigning LLT(n) (for LDLT that copies the new
  // object's uninitialised m_info, undefined behaviour: UBSan "not a valid value for
  // ComputationInfo").
  s.llt_system.compute(s.identity);
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d& pc = principal_[i + 1];
    s.axis_local.push_back(pc.linear().transpose() * model_.joints[i].axis);
    s.pivot_to_com.push_back(pc.linear().transpose() * pc.translation());
  }
  s.axis.resize(n);
  s.pivot.resize(n);
  s.composite_com.resize(n);
  s.composite_inertia.resize(n);
  s.composite_mass.resize(n);
  s.v_free = s.m_v_free = s.v = s.v_saved = s.residual = s.rhs = s.x = s.qd_old =
      Eigen::VectorXd::Zero(n);
  s.slide.assign(n, 0);
  s.motor.assign(n, 0);
  s.moving.reserve(n);
  s.omega.resize(n + 1);
  s.vel.resize(n + 1);
  impl_->force.assign(nb, Eigen::Vector3d::Zero());
  impl_->torque.assign(nb, Eigen::Vector3d::Zero());
  impl_->damping = Eigen::VectorXd::Zero(n);
  impl_->friction = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    if (options.joint_damping) impl_->damping[i] = model_.joints[i].damping;
    if (options.joint_friction) impl_->friction[i] = model_.joints[i].friction;
  }
  q_ = qd_ = qdd_ = last_motor_ = last_dissipative_ = Eigen::VectorXd::Zero(n);
  servo_.Resize(n);
  SetJointState(Eigen::VectorXd::Zero(n));
}

BulletArm::~BulletArm() = default;

void BulletArm::SetGravity(const Eigen::Vector3d& gravity) { gravity_ = gravity; }

void BulletArm::SetJointState(const Eigen::VectorXd& q) {
  SetJointState(q, Eigen::VectorXd::Zero(dof()));
}

void BulletArm::SetJointState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  assert(q.size() == dof() && qd.size() == dof());
  btMultiBody& mb = *impl_->body;
  for (int i = 0; i < dof(); ++i) {
    mb.setJointPos(i, q[i]);
    mb.setJointVel(i, qd[i]);
  }
  Refresh();
}

void JointServo::Resize(int n) {
  bias = gain = Eigen::VectorXd::Zero(n);
  lower = Eigen::VectorXd::Constant(n, -std::numeric_limits<double>::infinity());
  upper = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
}

void BulletArm::SetJointTorques(const Eigen::VectorXd& tau) {
  assert(tau.size() == dof());
  servo_.bias = tau;
  servo_.gain.setZero();
  servo_.lower.setConstant(-std::numeric_limits<double>::infinity());
  servo_.upper.setConstant(std::numeric_limits<double>::infinity());
}

void BulletArm::SetJointServo(const JointServo& servo) {
  assert(servo.bias.size() == dof() && servo.gain.size() == dof());
  assert(servo.lower.size() == dof() && servo.upper.size() == dof());
  assert((servo.gain.array() >= 0).all() && (servo.lower.array() <= servo.upper.array()).all());
  servo_.bias = servo.bias;
  servo_.gain = servo.gain;
  servo_.lower = servo.lower;
  servo_.upper = servo.upper;
}

void BulletArm::ApplyWrench(int body, const Wrench& wrench) {
  assert(body >= 0 && body <= dof());
  const Eigen::Vector3d com = BulletLinkFrame(body).translation();
  impl_->force[body] += wrench.force;
  impl_->torque[body] += wrench.torque + (wrench.point - com).cross(wrench.force);
}

void BulletArm::Refresh() {
  btMultiBody& mb = *impl_->body;
  mb.forwardKinematics(impl_->world_to_local, impl_->local_origin);  // the links' frames
  for (int i = 0; i < dof(); ++i) {
    q_[i] = mb.getJointPos(i);
    qd_[i] = mb.getJointVel(i);
  }
}

namespace {

// The servo's torque at rate v, and its state there: 0 linear, +1 at upper, -1 at lower.
int ServoState(const JointServo& s, int i, double v) {
  const double u = s.bias[i] - s.gain[i] * v;
  return u > s.upper[i] ? 1 : (u < s.lower[i] ? -1 : 0);
}
double ServoTorque(const JointServo& s, int i, double v) {
  return std::clamp(s.bias[i] - s.gain[i] * v, s.lower[i], s.upper[i]);
}

}  // namespace

// M(q) by the composite rigid body algorithm (Featherstone 2008, section 6.2) on Bullet's link
// frames at q (Refresh() keeps them): for the chain's joints i <= j, with C_j the composite body
// of links j..n-1 (mass m, CoM c, inertia I_c about c) and a unit rate of joint j (axis a_j
// through p_j: CoM velocity a_j x (c - p_j), angular velocity a_j),
//   M_ij = a_i . (I_c a_j + (c - p_i) x m (a_j x (c - p_j))),
// the moment about joint i's axis of C_j's momentum. The same inertias as Bullet's (principal
// moments in the link frame): the torques the solve adds, M (v - v_free) / dt, are those of our
// own Newton-Euler to 1e-9 (tests/arm/bullet_arm_test.cpp, RateSolveMeetsItsConditions).
void BulletArm::MassMatrix() {
  const int n = dof();
  Impl& s = *impl_;
  const btMultiBody& mb = *s.body;
  for (int j = n - 1; j >= 0; --j) {
    const btTransform& t = mb.getLink(j).m_cachedWorldTransform;
    Eigen::Matrix3d r;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) r(a, b) = t.getBasis()[a][b];
    }
    const Eigen::Vector3d com = Eig(t.getOrigin());
    s.axis[j] = r * s.axis_local[j];
    s.pivot[j] = com - r * s.pivot_to_com[j];
    const double m = model_.bodies[j + 1].inertial.mass;
    const Eigen::Matrix3d inertia = r * moments_[j + 1].asDiagonal() * r.transpose();
    if (j == n - 1) {
      s.composite_mass[j] = m;
      s.composite_com[j] = com;
      s.composite_inertia[j] = inertia;
      continue;
    }
    // Link j joined to C_{j+1}: parallel axes to the new CoM.
    const double mo = s.composite_mass[j + 1];
    const double mt = m + mo;
    const Eigen::Vector3d c = (m * com + mo * s.composite_com[j + 1]) / mt;
    const Eigen::Vector3d r1 = com - c, r2 = s.composite_com[j + 1] - c;
    const Eigen::Matrix3d one = Eigen::Matrix3d::Identity();
    s.composite_inertia[j] = inertia + m * (r1.squaredNorm() * one - r1 * r1.transpose()) +
                             s.composite_inertia[j + 1] +
                             mo * (r2.squaredNorm() * one - r2 * r2.transpose());
    s.composite_mass[j] = mt;
    s.composite_com[j] = c;
  }
  for (int j = 0; j < n; ++j) {
    const double m = s.composite_mass[j];
    const Eigen::Vector3d& c = s.composite_com[j];
    const Eigen::Vector3d momentum = m * s.axis[j].cross(c - s.pivot[j]);
    const Eigen::Vector3d spin = s.composite_inertia[j] * s.axis[j];
    for (int i = 0; i <= j; ++i) {
      s.mass(i, j) = s.mass(j, i) = s.axis[i].dot(spin + (c - s.pivot[i]).cross(momentum));
    }
  }
}

// v from v_free (bullet_arm.h): the joints whose servo has a gain, damping or friction solved
// together; then the motor torques of those servos and the dissipative torques.
void BulletArm::SolveRates(double dt) {
  const int n = dof();
  Impl& s = *impl_;
  const JointServo& servo = servo_;
  last_dissipative_.setZero();
  bool implicit = !s.damping.isZero() || !s.friction.isZero();
  for (int i = 0; i < n; ++i) implicit |= servo.gain[i] > 0;
  if (!implicit) {
    s.v = s.v_free;
    return;
  }

  MassMatrix();
  s.m_v_free.noalias() = s.mass * s.v_free;

  // The linear system of a guess: the moving joints' rows of
  //   (M + dt C + dt G_lin) v = M v_free + dt (servo constant - friction_i slide_i),
  // G_lin the gains of linear servos, the constant the bias (linear) or the bound (saturated);
  // stuck joints v_i = 0. In the top-left corner of the identity-padded system.
  auto solve_guess = [&]() {
    s.moving.clear();
    for (int i = 0; i < n; ++i) {
      if (!(s.friction[i] > 0 && s.slide[i] == 0)) s.moving.push_back(i);
    }
    const int m = static_cast<int>(s.moving.size());
    s.system.setIdentity();
    s.rhs.setZero();
    for (int a = 0; a < m; ++a) {
      const int i = s.moving[a];
      for (int b = 0; b < m; ++b) s.system(a, b) = s.mass(i, s.moving[b]);
      double constant = 0, gain = 0;
      if (servo.gain[i] > 0) {
        if (s.motor[i] == 0) {
          constant = servo.bias[i];
          gain = servo.gain[i];
        } else {
          constant = s.motor[i] > 0 ? servo.upper[i] : servo.lower[i];
        }
      }
      s.system(a, a) += dt * (s.damping[i] + gain);
      s.rhs[a] = s.m_v_free[i] + dt * (constant - s.friction[i] * s.slide[i]);
    }
    s.llt_system.compute(s.system);
    s.x = s.llt_system.solve(s.rhs);
    s.v.setZero();
    for (int a = 0; a < m; ++a) s.v[s.moving[a]] = s.x[a];
  };
  // Corrects the guess where v contradicts it; true when nothing needed correcting.
  auto consistent = [&]() {
    bool ok = true;
    s.residual.noalias() = s.mass * (s.v - s.v_free);  // dt x the torques the solve added
    for (int i = 0; i < n; ++i) {
      const bool servoed = servo.gain[i] > 0;
      if (servoed) {
        const int state = ServoState(servo, i, s.v[i]);
        ok &= state == s.motor[i];
        s.motor[i] = state;
      }
      if (!(s.friction[i] > 0)) continue;
      if (s.slide[i] != 0) {
        if (s.v[i] * s.slide[i] <= 0) {  // slid back through zero: stuck
          s.slide[i] = 0;
          ok = false;
        }
      } else {
        // The friction torque that holds it: f = tau_servo(0) - residual / dt - C 0.
        const double tau = servoed ? ServoTorque(servo, i, 0.0) : 0.0;
        const double f = tau - s.residual[i] / dt;
        if (std::abs(f) > s.friction[i]) {
          s.slide[i] = f > 0 ? 1 : -1;
          ok = false;
        }
      }
    }
    return ok;
  };

  // The guess: servos linear, each joint sliding the way it moved, stuck if it was at rest.
  for (int i = 0; i < n; ++i) {
    s.motor[i] = 0;
    s.slide[i] = qd_[i] > 0 ? 1 : (qd_[i] < 0 ? -1 : 0);
  }
  bool solved = false;
  for (int round = 0; round < 4 * n + 4 && !solved; ++round) {
    solve_guess();
    solved = consistent();
  }
  if (!solved) {
    // The guesses cycled: coordinate descent on the convex objective, each joint's
    // one-dimensional problem solved exactly (its torque is monotone and piecewise linear in
    // v_i), then the linear solve on the states it found, kept if consistent.
    for (int sweep = 0; sweep < 200; ++sweep) {
      double change = 0;
      for (int i = 0; i < n; ++i) {
        const double k = s.mass(i, i) + dt * s.damping[i];
        const double r = s.m_v_free[i] - s.mass.row(i).dot(s.v) + s.mass(i, i) * s.v[i];
        const bool servoed = servo.gain[i] > 0;
        const double tau0 = servoed ? ServoTorque(servo, i, 0.0) : 0.0;
        const double h0 = -r - dt * tau0;  // k v - r - dt tau(v) at v = 0
        const double limit = dt * s.friction[i];
        double vi = 0;
        if (std::abs(h0) > limit) {
          const double rr = h0 < 0 ? r - limit : r + limit;  // k v - rr - dt tau(v) = 0
          if (!servoed) {
            vi = rr / k;
          } else {
            vi = (rr + dt * servo.bias[i]) / (k + dt * servo.gain[i]);
            const double u = servo.bias[i] - servo.gain[i] * vi;
            if (u > servo.upper[i]) vi = (rr + dt * servo.upper[i]) / k;
            if (u < servo.lower[i]) vi = (rr + dt * servo.lower[i]) / k;
          }
        }
        change = std::max(change, std::abs(vi - s.v[i]));
        s.v[i] = vi;
      }
      if (change <= 1e-14 * (1 + s.v.cwiseAbs().maxCoeff())) break;
    }
    s.v_saved = s.v;
    for (int i = 0; i < n; ++i) {
      s.slide[i] = s.v[i] > 0 ? 1 : (s.v[i] < 0 ? -1 : 0);
      s.motor[i] = servo.gain[i] > 0 ? ServoState(servo, i, s.v[i]) : 0;
    }
    solve_guess();
    if (!consistent()) s.v = s.v_saved;
  }

  // The torques: the servos' at v, and what else the solve added (damping and friction).
  s.residual.noalias() = s.mass * (s.v - s.v_free);
  for (int i = 0; i < n; ++i) {
    if (servo.gain[i] > 0) last_motor_[i] = ServoTorque(servo, i, s.v[i]);
    last_dissipative_[i] = s.residual[i] / dt - (servo.gain[i] > 0 ? last_motor_[i] : 0.0);
  }
}

void BulletArm::Step(double dt) {
  const int n = dof();
  Impl& s = *impl_;
  btMultiBody& mb = *s.body;
  // Gravity, wrenches and the servos without a gain (a constant torque), in Bullet's
  // accumulators for this step.
  for (int b = 1; b <= n; ++b) {
    const Eigen::Vector3d f = model_.bodies[b].inertial.mass * gravity_ + s.force[b];
    mb.addLinkForce(b - 1, BtVec(f));
    mb.addLinkTorque(b - 1, BtVec(s.torque[b]));
  }
  for (int i = 0; i < n; ++i) {
    if (servo_.gain[i] > 0) continue;
    last_motor_[i] = ServoTorque(servo_, i, 0.0);
    mb.addJointTorque(i, last_motor_[i]);
  }
  // qdd with those forces (dt = 0: Bullet leaves the rates alone; it also caches what
  // calcAccelerationDeltasMultiDof needs), then the rates at the step's end.
  mb.computeAccelerationsArticulatedBodyAlgorithmMultiDof(0, s.scratch_r, s.scratch_v, s.scratch_m,
                                                          false, false, false);
  const btScalar* qdd = &s.scratch_r[mb.getNumDofs() + 6];
  for (int i = 0; i < n; ++i) s.v_free[i] = qd_[i] + dt * qdd[i];
  SolveRates(dt);

  // Semi-implicit Euler: q += dt v (Bullet's own position step), forces cleared.
  for (int i = 0; i < n; ++i) mb.setJointVel(i, s.v[i]);
  mb.stepPositionsMultiDof(dt);
  mb.clearForcesAndTorques();
  s.qd_old = qd_;
  Refresh();
  qdd_ = (qd_ - s.qd_old) / dt;
  time_ += dt;
  servo_.bias.setZero();
  servo_.gain.setZero();
  servo_.lower.setConstant(-std::numeric_limits<double>::infinity());
  servo_.upper.setConstant(std::numeric_limits<double>::infinity());
  for (int b = 0; b <= n; ++b) {
    s.force[b].setZero();
    s.torque[b].setZero();
  }
}

Eigen::Isometry3d BulletArm::BulletLinkFrame(int body) const {
  const btMultiBody& mb = *impl_->body;
  if (body == 0) return Eig(mb.getBaseWorldTransform());
  return Eig(mb.getLink(body - 1).m_cachedWorldTransform);
}

Eigen::Isometry3d BulletArm::BodyPose(int body) const {
  return BulletLinkFrame(body) * principal_[body].inverse();
}

Eigen::Isometry3d BulletArm::LinkPose(const std::string& link) const {
  int body = 0;
  Eigen::Isometry3d in_body;
  if (!model_.FindLink(link, &body, &in_body)) {
    throw std::invalid_argument("arm: no link named '" + link + "'");
  }
  return BodyPose(body) * in_body;
}

Twist BulletArm::BodyTwist(int body) const {
  Twist out;
  if (body == 0) return out;
  const btMultiBody& mb = *impl_->body;
  // Bullet's link velocities, in each link's own (principal) frame, CoM velocity.
  mb.compTreeLinkVelocities(impl_->omega.data(), impl_->vel.data());
  const Eigen::Isometry3d frame = BulletLinkFrame(body);
  out.angular = frame.linear() * Eig(impl_->omega[body]);
  const Eigen::Vector3d v_com = frame.linear() * Eig(impl_->vel[body]);
  const Eigen::Vector3d origin = BodyPose(body).translation();
  out.linear = v_com + out.angular.cross(origin - frame.translation());
  return out;
}

Twist BulletArm::LinkTwist(const std::string& link) const {
  int body = 0;
  Eigen::Isometry3d in_body;
  if (!model_.FindLink(link, &body, &in_body)) {
    throw std::invalid_argument("arm: no link named '" + link + "'");
  }
  Twist t = BodyTwist(body);
  const Eigen::Vector3d offset = LinkPose(link).translation() - BodyPose(body).translation();
  t.linear += t.angular.cross(offset);
  return t;
}

}  // namespace arm

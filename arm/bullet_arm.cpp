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
  btAlignedObjectArray<btScalar> scratch_r, scratch_r2;
  btAlignedObjectArray<btVector3> scratch_v, scratch_v2;
  btAlignedObjectArray<btMatrix3x3> scratch_m;
  btAlignedObjectArray<btQuaternion> world_to_local;
  btAlignedObjectArray<btVector3> local_origin;
  std::vector<btScalar> unit, response;
  // Implicit damping/friction: mass matrix, its inverse, the solve's vectors (sized once: the
  // step allocates nothing).
  Eigen::MatrixXd inv_mass, mass, k, identity, k_sliding;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_mass, ldlt_k, ldlt_sliding;
  Eigen::VectorXd v_free, b, v, damping, friction, rhs, v_sliding, qd_old;
  std::vector<int> sliding;
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
  s.inv_mass = s.mass = s.k = s.identity = Eigen::MatrixXd::Identity(n, n);
  // Sized by a first factorisation, not by assigning LDLT(n): that copies the new object's
  // uninitialised m_info, undefined behaviour (UBSan: "not a valid value for ComputationInfo").
  s.ldlt_mass.compute(s.identity);
  s.ldlt_k.compute(s.identity);
  s.ldlt_sliding.compute(s.identity);
  s.v_free = s.b = s.v = s.rhs = s.v_sliding = s.qd_old = Eigen::VectorXd::Zero(n);
  s.k_sliding = Eigen::MatrixXd::Zero(n, n);
  s.sliding.reserve(n);
  s.omega.resize(n + 1);
  s.vel.resize(n + 1);
  impl_->unit.assign(6 + n, 0);
  impl_->response.assign(6 + n, 0);
  impl_->force.assign(nb, Eigen::Vector3d::Zero());
  impl_->torque.assign(nb, Eigen::Vector3d::Zero());
  impl_->damping = Eigen::VectorXd::Zero(n);
  impl_->friction = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    if (options.joint_damping) impl_->damping[i] = model_.joints[i].damping;
    if (options.joint_friction) impl_->friction[i] = model_.joints[i].friction;
  }
  q_ = qd_ = qdd_ = tau_ = last_motor_ = last_dissipative_ = Eigen::VectorXd::Zero(n);
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

void BulletArm::SetJointTorques(const Eigen::VectorXd& tau) {
  assert(tau.size() == dof());
  tau_ = tau;
}

void BulletArm::ApplyWrench(int body, const Wrench& wrench) {
  assert(body >= 0 && body <= dof());
  const Eigen::Vector3d com = BulletLinkFrame(body).translation();
  impl_->force[body] += wrench.force;
  impl_->torque[body] += wrench.torque + (wrench.point - com).cross(wrench.force);
}

void BulletArm::Refresh() {
  btMultiBody& mb = *impl_->body;
  mb.forwardKinematics(impl_->world_to_local, impl_->local_origin);
  mb.updateCollisionObjectWorldTransforms(impl_->world_to_local, impl_->local_origin);
  for (int i = 0; i < dof(); ++i) {
    q_[i] = mb.getJointPos(i);
    qd_[i] = mb.getJointVel(i);
  }
}

// Forward dynamics with every force of this step but damping and friction, then the implicit
// solve of bullet_arm.h, then the equivalent joint torque.
void BulletArm::SolveDissipation(double dt) {
  const int n = dof();
  Impl& s = *impl_;
  btMultiBody& mb = *s.body;
  last_dissipative_.setZero();
  if (s.damping.isZero() && s.friction.isZero()) return;

  // qdd without damping and friction (dt = 0: Bullet leaves the rates alone). Also caches what
  // calcAccelerationDeltasMultiDof needs.
  mb.computeAccelerationsArticulatedBodyAlgorithmMultiDof(0, s.scratch_r, s.scratch_v, s.scratch_m,
                                                          false, false, false);
  const btScalar* qdd = &s.scratch_r[mb.getNumDofs() + 6];
  for (int i = 0; i < n; ++i) s.v_free[i] = qd_[i] + dt * qdd[i];
  // M^-1 column by column: the joint accelerations of a unit joint torque.
  for (int j = 0; j < n; ++j) {
    std::fill(s.unit.begin(), s.unit.end(), 0);
    s.unit[6 + j] = 1;
    mb.calcAccelerationDeltasMultiDof(s.unit.data(), s.response.data(), s.scratch_r2, s.scratch_v2);
    for (int i = 0; i < n; ++i) s.inv_mass(i, j) = s.response[6 + i];
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j)
      s.inv_mass(i, j) = s.inv_mass(j, i) = 0.5 * (s.inv_mass(i, j) + s.inv_mass(j, i));
  }
  s.ldlt_mass.compute(s.inv_mass);
  s.mass = s.ldlt_mass.solve(s.identity);
  s.k = s.mass;
  s.k.diagonal() += dt * s.damping;
  s.b.noalias() = s.mass * s.v_free;

  // Damping alone: v = K^-1 b. With friction: coordinate descent on the convex objective
  // (soft thresholding per joint), then the linear solve on the active set it found.
  s.ldlt_k.compute(s.k);
  s.v = s.ldlt_k.solve(s.b);
  if (!s.friction.isZero()) {
    for (int sweep = 0; sweep < 100; ++sweep) {
      double change = 0;
      for (int i = 0; i < n; ++i) {
        const double r = s.b[i] - s.k.row(i).dot(s.v) + s.k(i, i) * s.v[i];
        const double limit = dt * s.friction[i];
        const double vi = std::abs(r) <= limit ? 0 : (r - std::copysign(limit, r)) / s.k(i, i);
        change = std::max(change, std::abs(vi - s.v[i]));
        s.v[i] = vi;
      }
      if (change <= 1e-14 * (1 + s.v.cwiseAbs().maxCoeff())) break;
    }
    // Polish: sliding joints (v != 0) obey K v = b - dt friction sign(v), stuck ones v = 0.
    std::vector<int>& sliding = s.sliding;
    sliding.clear();
    for (int i = 0; i < n; ++i) {
      if (s.v[i] != 0) sliding.push_back(i);
    }
    if (!sliding.empty() && static_cast<int>(sliding.size()) < n) {
      // The sliding joints' block, in the top-left corner of the preallocated matrices.
      const int m = static_cast<int>(sliding.size());
      s.k_sliding.setIdentity();
      s.rhs.setZero();
      for (int a = 0; a < m; ++a) {
        s.rhs[a] = s.b[sliding[a]] - dt * s.friction[sliding[a]] * (s.v[sliding[a]] > 0 ? 1 : -1);
        for (int c = 0; c < m; ++c) s.k_sliding(a, c) = s.k(sliding[a], sliding[c]);
      }
      s.ldlt_sliding.compute(s.k_sliding);
      s.v_sliding = s.ldlt_sliding.solve(s.rhs);
      bool consistent = true;
      for (int a = 0; a < m; ++a) consistent &= (s.v_sliding[a] > 0) == (s.v[sliding[a]] > 0);
      if (consistent) {
        for (int a = 0; a < m; ++a) s.v[sliding[a]] = s.v_sliding[a];
      }
    } else if (!sliding.empty()) {
      // All sliding: K v = b - dt friction sign(v).
      for (int i = 0; i < n; ++i) s.rhs[i] = s.b[i] - dt * s.friction[i] * (s.v[i] > 0 ? 1 : -1);
      s.v_sliding = s.ldlt_k.solve(s.rhs);
      bool consistent = true;
      for (int i = 0; i < n; ++i) consistent &= (s.v_sliding[i] > 0) == (s.v[i] > 0);
      if (consistent) s.v = s.v_sliding;
    }
  }
  s.v_free -= s.v;  // now v_free - v
  last_dissipative_.noalias() = s.mass * s.v_free;
  last_dissipative_ /= -dt;
  for (int i = 0; i < n; ++i) mb.addJointTorque(i, last_dissipative_[i]);
}

void BulletArm::Step(double dt) {
  const int n = dof();
  Impl& s = *impl_;
  btMultiBody& mb = *s.body;
  // Gravity, wrenches and motor torques, in Bullet's accumulators for this step.
  for (int b = 1; b <= n; ++b) {
    const Eigen::Vector3d f = model_.bodies[b].inertial.mass * gravity_ + s.force[b];
    mb.addLinkForce(b - 1, BtVec(f));
    mb.addLinkTorque(b - 1, BtVec(s.torque[b]));
  }
  for (int i = 0; i < n; ++i) mb.addJointTorque(i, tau_[i]);
  last_motor_ = tau_;
  SolveDissipation(dt);

  s.qd_old = qd_;
  s.world.stepSimulation(dt, 0, dt);  // one step of exactly dt
  Refresh();
  qdd_ = (qd_ - s.qd_old) / dt;
  time_ += dt;
  tau_.setZero();
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

#include "sim/files/arm_geometry.h"

#include <Eigen/Geometry>
#include <cmath>

#include "arm/arm_model.h"
#include "arm/fault_monitor.h"
#include "arm/kinematics.h"
#include "sim/input/mesh_io.h"
#include "sim/input/scene.h"

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

dem::Vec3 ToDem(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// Appends a shape's triangles, given in its own frame, placed by `origin` (shape -> body).
void Append(const std::vector<Eigen::Vector3d>& vertices,
            const std::vector<std::array<int32_t, 3>>& triangles, const Eigen::Isometry3d& origin,
            dem::TriangleMesh* mesh) {
  const int32_t base = static_cast<int32_t>(mesh->vertices.size());
  for (const Eigen::Vector3d& v : vertices) mesh->vertices.push_back(ToDem(origin * v));
  for (const auto& t : triangles)
    mesh->triangles.push_back({base + t[0], base + t[1], base + t[2]});
}

// A box of half sides h, centred on its frame; counter-clockwise seen from outside.
void AppendBox(const Eigen::Vector3d& h, const Eigen::Isometry3d& origin, dem::TriangleMesh* mesh) {
  std::vector<Eigen::Vector3d> v;
  for (int k = 0; k < 8; ++k)
    v.emplace_back((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(), (k & 4) ? h.z() : -h.z());
  Append(v,
         {{0, 2, 1},
          {1, 2, 3},
          {4, 5, 6},
          {5, 7, 6},
          {0, 1, 4},
          {1, 5, 4},
          {2, 6, 3},
          {3, 6, 7},
          {0, 4, 2},
          {2, 4, 6},
          {1, 3, 5},
          {3, 7, 5}},
         origin, mesh);
}

// A cylinder of radius r and length l along its frame's z, centred, kSegments facets round.
void AppendCylinder(double r, double l, const Eigen::Isometry3d& origin, dem::TriangleMesh* mesh) {
  const int n = ArmGeometry::kSegments;
  std::vector<Eigen::Vector3d> v = {{0, 0, -0.5 * l}, {0, 0, 0.5 * l}};
  for (int k = 0; k < n; ++k) {
    const double a = 2 * kPi * k / n;
    v.emplace_back(r * std::cos(a), r * std::sin(a), -0.5 * l);
    v.emplace_back(r * std::cos(a), r * std::sin(a), 0.5 * l);
  }
  std::vector<std::array<int32_t, 3>> t;
  for (int k = 0; k < n; ++k) {
    const int32_t b0 = 2 + 2 * k, t0 = b0 + 1, b1 = 2 + 2 * ((k + 1) % n), t1 = b1 + 1;
    t.push_back({b0, b1, t1});
    t.push_back({b0, t1, t0});
    t.push_back({0, b1, b0});
    t.push_back({1, t0, t1});
  }
  Append(v, t, origin, mesh);
}

// A sphere of radius r: kSegments meridians, kSegments / 2 bands.
void AppendSphere(double r, const Eigen::Isometry3d& origin, dem::TriangleMesh* mesh) {
  const int n = ArmGeometry::kSegments, m = n / 2;
  std::vector<Eigen::Vector3d> v = {{0, 0, -r}, {0, 0, r}};
  for (int i = 1; i < m; ++i) {
    const double polar = kPi * i / m;
    for (int k = 0; k < n; ++k) {
      const double a = 2 * kPi * k / n;
      v.emplace_back(r * std::sin(polar) * std::cos(a), r * std::sin(polar) * std::sin(a),
                     -r * std::cos(polar));
    }
  }
  auto ring = [n](int i, int k) { return static_cast<int32_t>(2 + (i - 1) * n + (k % n)); };
  std::vector<std::array<int32_t, 3>> t;
  for (int k = 0; k < n; ++k) {
    t.push_back({0, ring(1, k + 1), ring(1, k)});
    t.push_back({1, ring(m - 1, k), ring(m - 1, k + 1)});
    for (int i = 1; i + 1 < m; ++i) {
      t.push_back({ring(i, k), ring(i, k + 1), ring(i + 1, k + 1)});
      t.push_back({ring(i, k), ring(i + 1, k + 1), ring(i + 1, k)});
    }
  }
  Append(v, t, origin, mesh);
}

void AppendShape(const std::string& urdf, const arm::Shape& s, dem::TriangleMesh* mesh) {
  switch (s.kind) {
    case arm::Shape::Kind::kBox:
      AppendBox(0.5 * s.size, s.origin, mesh);
      break;
    case arm::Shape::Kind::kCylinder:
      AppendCylinder(s.size.x(), s.size.y(), s.origin, mesh);
      break;
    case arm::Shape::Kind::kSphere:
      AppendSphere(s.size.x(), s.origin, mesh);
      break;
    case arm::Shape::Kind::kMesh: {
      dem::TriangleMesh file;
      try {
        file = LoadMesh(s.mesh_path);
      } catch (const InputError& e) {
        // The mesh's own error names only the mesh file: name the URDF and the link as well.
        throw InputError(urdf, 0, "link '" + s.link + "' <mesh filename>", e.expected(),
                         s.mesh_path + ": " + e.got());
      }
      std::vector<Eigen::Vector3d> v;
      for (const dem::Vec3& p : file.vertices)
        v.emplace_back(s.size.x() * p.x, s.size.y() * p.y, s.size.z() * p.z);
      Append(v, file.triangles, s.origin, mesh);
      break;
    }
  }
}

}  // namespace

ArmGeometry::ArmGeometry(std::shared_ptr<const arm::ArmModel> model) : model_(std::move(model)) {
  const arm::ArmModel& m = *model_;
  // Bodies 1..dof-1: the moving links but the scoop's (the last).
  for (int b = 1; b < m.dof(); ++b) {
    const arm::Body& body = m.bodies[b];
    dem::TriangleMesh mesh;
    mesh.name = body.link;
    for (const arm::Frame& frame : body.frames) {
      bool has_visual = false;
      for (const arm::Shape& s : body.shapes) has_visual |= s.link == frame.link && !s.collision;
      for (const arm::Shape& s : body.shapes)
        if (s.link == frame.link && s.collision != has_visual) AppendShape(m.source, s, &mesh);
    }
    if (mesh.triangles.empty()) continue;
    meshes_.push_back(std::move(mesh));
    bodies_.push_back(b);
  }
}

ArmGeometry ArmGeometry::FromUrdf(const std::string& urdf_path) {
  try {
    return ArmGeometry(std::make_shared<const arm::ArmModel>(arm::LoadArmModel(urdf_path)));
  } catch (const arm::ArmModelError& e) {
    throw InputError(e.what());
  }
}

int ArmGeometry::dof() const { return model_->dof(); }

std::vector<dem::Pose> ArmGeometry::Poses(const double* q, const ArmBase& base) const {
  const int n = model_->dof();
  Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
  b.linear() = Eigen::AngleAxisd(base.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  b.translation() = Eigen::Vector3d(base.position.x, base.position.y, base.position.z);
  const std::vector<Eigen::Isometry3d> bodies =
      arm::BodyPoses(*model_, Eigen::Map<const Eigen::VectorXd>(q, n), b);
  std::vector<dem::Pose> poses;
  for (int body : bodies_) {
    const Eigen::Quaterniond r(bodies[body].linear());
    poses.push_back({ToDem(bodies[body].translation()), {r.w(), r.x(), r.y(), r.z()}});
  }
  return poses;
}

void ArmGeometry::AddToView(const double* q, const ArmBase& base, WorldView* view) const {
  const std::vector<dem::Pose> poses = Poses(q, base);
  for (int p = 0; p < parts(); ++p)
    view->meshes.push_back({&meshes_[p], poses[p], MeshRole::kArmLink});
}

std::string FaultNames(uint64_t bits) {
  std::string names;
  for (int b = 0; b < 64; ++b) {
    const uint64_t flag = uint64_t{1} << b;
    if (!(bits & flag)) continue;
    const char* name = arm::FaultName(flag);
    names += (names.empty() ? "" : " ") + std::string(*name ? name : "BIT" + std::to_string(b));
  }
  return names;
}

}  // namespace sim

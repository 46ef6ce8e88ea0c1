#include "sim/loop/table_arm.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "sim/files/h5_output.h"
#include "sim/loop/progress.h"

namespace sim {

TableWrench::TableWrench(const Scene& scene)
    : table_(scene.arm.table),
      material_(scene.bed.material),
      bite_depth_mm_(scene.dig.bite_depth * 1e3),
      surface_(scene.dig.surface),
      bite_depth_(scene.dig.bite_depth),
      com_scoop_(scene.dig.scoop.com),
      trench_{std::cos(scene.dig.heading), std::sin(scene.dig.heading), 0.0},
      mesh_(&scene.dig.scoop.geometry) {
  // Refuse before the run what the run would otherwise meet mid-dig: every pass at rho 0.
  for (int pass = 1; pass <= scene.dig.passes; ++pass) {
    try {
      table_.Query(material_, bite_depth_mm_, pass, 0.0);
    } catch (const OutOfTableDomain& e) {
      // The scene's key that asked for it.
      const auto& m = table_.materials();
      const auto& p = table_.passes();
      const char* key = "dig.bite_depth";
      if (std::find(m.begin(), m.end(), material_) == m.end()) {
        key = "bed.material";
      } else if (std::find(p.begin(), p.end(), pass) == p.end()) {
        key = "dig.passes";
      }
      throw InputError(scene.path + ": " + key + " (arm.wrench: table): " + e.what());
    }
  }
}

void TableWrench::BeginPass(int pass) {
  pass_ = pass;
  floor_ = surface_ - (pass - 1) * bite_depth_;
  touched_ = false;
  rho_ = along0_ = 0;
  scoop_wrench_.fill(0.0);
  // The end of the pass's data: that of the cell(s) Query blends (the shorter one).
  rho_end_ = std::numeric_limits<double>::infinity();
  const auto& materials = table_.materials();
  const int m = static_cast<int>(std::find(materials.begin(), materials.end(), material_) -
                                 materials.begin());
  const int p = static_cast<int>(std::find(table_.passes().begin(), table_.passes().end(), pass) -
                                 table_.passes().begin());
  const std::vector<double>& depths = table_.bite_depths();
  for (size_t b = 0; b < depths.size(); ++b) {
    const bool below_next =
        b + 1 < depths.size() && depths[b] < bite_depth_ && bite_depth_ < depths[b + 1];
    const bool at = std::abs(depths[b] - bite_depth_) <= 1e-12;
    const bool above_previous = b > 0 && depths[b - 1] < bite_depth_ && bite_depth_ < depths[b];
    if (at || below_next || above_previous)
      rho_end_ = std::min(rho_end_, table_.RhoEnd(m, static_cast<int>(b), p));
  }
}

dem::MeshWrench TableWrench::At(const dem::Pose& pose) {
  com_ = dem::Apply(pose, com_scoop_);
  dem::MeshWrench w;
  if (!touched_) {
    // First contact: the lowest vertex of the scoop at or below the floor of this pass.
    for (const dem::Vec3& v : mesh_->vertices) {
      if (dem::Apply(pose, v).z <= floor_) {
        touched_ = true;
        along0_ = dem::Dot(com_, trench_);
        com_last_ = com_;
        break;
      }
    }
    if (!touched_) return w;
  }
  if (table_.rho_definition() == RhoDefinition::kPath) {
    rho_ += dem::Norm(com_ - com_last_);
    com_last_ = com_;
  } else {
    rho_ = std::max(rho_, dem::Dot(com_, trench_) - along0_);
  }
  if (rho_ > rho_end_) ++held_steps_;
  // Material, bite depth and pass were checked at construction: with clamp, Query cannot throw.
  scoop_wrench_ = table_.Query(material_, bite_depth_mm_, pass_, rho_ * 1e3, /*clamp=*/true);
  // l_scoop axes about the CoM -> world axes about the l_scoop origin.
  const dem::Vec3 force =
      dem::Rotate(pose.orientation, {scoop_wrench_[0], scoop_wrench_[1], scoop_wrench_[2]});
  const dem::Vec3 torque_com =
      dem::Rotate(pose.orientation, {scoop_wrench_[3], scoop_wrench_[4], scoop_wrench_[5]});
  w.force = force;
  w.torque = torque_com + dem::Cross(com_ - pose.position, force);
  w.contacts = 1;
  return w;
}

Scene TableArmDriver::ArmScene(const Scene& scene) {
  // The arm steps once per loop step: the scene's arm step as the "DEM step", one substep.
  Scene arm_scene = scene;
  arm_scene.time_step = scene.arm.step > 0 ? scene.arm.step : scene.arm.substeps * scene.time_step;
  arm_scene.arm.substeps = 1;
  arm_scene.arm.timing = CouplingTiming::kBulletFirst;
  return arm_scene;
}

TableArmDriver::TableArmDriver(const Scene& scene, bool announce)
    : scene_(scene),
      step_(ArmScene(scene).time_step),
      source_(scene_),
      arm_(ArmScene(scene), announce) {}

TableArmDriver::~TableArmDriver() = default;

PassStart TableArmDriver::BeginPass(int pass, const BedContext& bed) {
  if (!started_) {
    started_ = true;
    wall0_ = std::chrono::steady_clock::now();
  }
  passes_time_ += last_tau_;
  last_tau_ = 0;
  const PassStart start = arm_.BeginPass(pass, bed);
  source_.BeginPass(pass);
  return start;
}

void TableArmDriver::Feedback(double tau, const dem::MeshWrench& wrench) {
  last_tau_ = tau;
  arm_.Feedback(tau, wrench);
}

void TableArmDriver::Record(H5Output* out, double time) {
  if (out && !attributes_written_) {
    out->SetAttribute("wrench_source", std::string("table"));
    out->SetAttribute("wrench_table", scene_.arm.table);
    out->SetAttribute("arm_step", step_);
    attributes_written_ = true;
  }
  arm_.Record(out, time);
}

void TableArmDriver::Finish(H5Output* out) {
  arm_.Finish(out);
  const double wall =
      started_ ? std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count()
               : 0.0;
  const int64_t steps = arm_.report().bullet_steps;
  const double simulated = passes_time_ + last_tau_;
  const double factor = wall > 0 ? simulated / wall : 0.0;
  Status(
      "scoopsim: table-driven arm: %.4g s simulated in %.3g s wall: %.3g x real time (%lld Bullet "
      "steps of %.3g s, %.3g us each); %lld steps past the table's rho held its last value\n",
      simulated, wall, factor, static_cast<long long>(steps), step_,
      1e6 * wall / std::max<int64_t>(1, steps), static_cast<long long>(source_.held_steps()));
  if (out) out->SetAttribute("real_time_factor", factor);
}

}  // namespace sim

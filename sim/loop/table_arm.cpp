#include "sim/loop/table_arm.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "sim/loop/arm_driver.h"
#include "sim/loop/world.h"
#include "sim/input/exit_status.h"
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

namespace {

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

void Row3(H5Output* out, const char* name, const double* v) { out->AppendRow(name, v, 3); }

}  // namespace

TableArmResult RunTableArm(const Scene& scene, const RunOptions& options) {
  InstallStopHandlers();
  TableWrench source(scene);
  // The arm steps once per loop step: the scene's arm step as the "DEM step", one substep.
  Scene arm_scene = scene;
  const double h = scene.arm.step > 0 ? scene.arm.step : scene.arm.substeps * scene.time_step;
  arm_scene.time_step = h;
  arm_scene.arm.substeps = 1;
  arm_scene.arm.timing = CouplingTiming::kBulletFirst;
  ArmDriver driver(arm_scene);

  std::unique_ptr<H5Output> out;
  if (!options.output.empty()) {
    out = std::make_unique<H5Output>(options.output, scene.yaml_text, SCOOPSIM_VERSION,
                                     scene.output.flush_seconds);
    out->SetAttribute("wrench_source", std::string("table"));
    out->SetAttribute("wrench_table", scene.arm.table);
    out->SetAttribute("surface", scene.dig.surface);
    out->SetAttribute("arm_step", h);
  }
  // No bed: the surface is the scene's, the scoop starts its descent a few radii above it.
  BedContext bed;
  bed.mesh = &scene.dig.scoop.geometry;
  bed.surface = scene.dig.surface;
  bed.clear_z = scene.dig.surface + 3 * scene.bed.radius_max;
  bed.time_step = h;
  bed.start_time = 0;

  TableArmResult result;
  const auto wall0 = std::chrono::steady_clock::now();
  double time = 0;  // simulated time at the start of the current pass [s]
  // Snapshots every output.snapshot_every arm steps and at the start: no particles, the scoop and
  // the arm's links (a replay by `scoopsim render`, the XDMF in ParaView).
  const int64_t snapshot_every = out ? scene.output.snapshot_every : 0;
  dem::Particles no_particles;
  int64_t arm_steps = 0;
  auto snapshot = [&](double t, const dem::Pose& scoop) {
    WorldView view;
    view.meshes.push_back({&scene.dig.scoop.geometry, scoop, MeshRole::kScoop});
    driver.AddToView(&view);
    out->WriteSnapshot(t, no_particles, view.meshes);
  };
  bool stopped_after = false;
  for (int pass = 1; pass <= scene.dig.passes && result.exit_status == kExitOk && !stopped_after;
       ++pass) {
    driver.BeginPass(pass, bed);
    source.BeginPass(pass);
    if (snapshot_every > 0 && pass == 1) snapshot(0.0, driver.MotionAt(0.0).pose);
    double next_row = 0;
    int64_t k = 0;
    double tau = 0;
    while (!driver.PassOver(tau)) {
      const double next = static_cast<double>(k + 1) * h;  // no drift from summing h
      const dem::MeshMotion m = driver.MotionAt(next);
      driver.Feedback(next, source.At(m.pose));
      tau = next;
      ++k;
      if (snapshot_every > 0 && ++arm_steps % snapshot_every == 0) snapshot(time + tau, m.pose);
      if (out && tau >= next_row) {
        next_row += scene.dig.interval;
        const double t = time + tau, p = pass, rho = source.rho();
        const dem::Vec3& c = source.com();
        const double com[3] = {c.x, c.y, c.z};
        out->AppendRow("/scoop/time", &t, 1);
        out->AppendRow("/scoop/pass", &p, 1);
        out->AppendRow("/scoop/rho", &rho, 1);
        Row3(out.get(), "/scoop/com", com);
        Row3(out.get(), "/scoop/force_scoop", source.scoop_wrench().data());
        Row3(out.get(), "/scoop/torque_scoop", source.scoop_wrench().data() + 3);
        driver.Record(out.get(), t);
        out->MaybeFlush();
      }
      if (options.stop_after > 0 && time + tau >= options.stop_after) {
        Status("scoopsim: stopped at t = %.6g s (--stop-after); output closed\n", time + tau);
        stopped_after = true;
        break;
      }
      if ((k & 1023) == 0 && StopRequested()) {
        Status("scoopsim: stopped by signal %d at t = %.6g s; output closed\n", StopSignal(),
               time + tau);
        result.exit_status = kExitStopped;
        break;
      }
    }
    result.steps += k;
    time += tau;
    Status("scoopsim: pass %d: rho %.1f mm (table-driven)\n", pass, 1e3 * source.rho());
  }
  result.simulated = time;
  result.wall = Seconds(std::chrono::steady_clock::now() - wall0);
  driver.Finish(out.get());
  Status(
      "scoopsim: table-driven arm: %.4g s simulated in %.3g s wall: %.3g x real time (%lld Bullet "
      "steps of %.3g s, %.3g us each); %lld steps past the table's rho held its last value\n",
      result.simulated, result.wall, result.RealTimeFactor(), static_cast<long long>(result.steps),
      h, 1e6 * result.wall / std::max<int64_t>(1, result.steps),
      static_cast<long long>(source.held_steps()));
  if (out) {
    out->SetAttribute("real_time_factor", result.RealTimeFactor());
    out->SetAttribute("time", result.simulated);
    out->Close();
    if (out->snapshot_count() > 0) {
      Status("scoopsim: wrote %s (ParaView: %s)\n", out->path().c_str(), out->xdmf_path().c_str());
    } else {
      Status("scoopsim: wrote %s\n", out->path().c_str());
    }
  }
  return result;
}

}  // namespace sim

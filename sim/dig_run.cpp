#include "sim/dig_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "sim/dig.h"
#include "sim/mesh_io.h"
#include "sim/progress.h"
#include "sim/trajectory.h"

namespace sim {
namespace {

constexpr int kExitUnstable = 3;
constexpr int kExitStopped = 130;

// Level orientation of the scoop (l_scoop +x forward, +z down): rpy (pi, 0, 0).
const dem::Quat kLevel{0.0, 1.0, 0.0, 0.0};

// Rotation about world z by the trench heading, applied to a kinematic state of the trajectory
// (which digs along +x).
dem::Quat Heading(double heading) { return dem::AxisAngle({0, 0, 1}, heading); }

// One pass: the trajectory, shifted in time by a vertical descent that brings the scoop from
// clear of the bed down to the trajectory's start pose at the approach speed.
struct PassPlan {
  Trajectory trajectory;
  double offset = 0;        // trajectory time at which the pass starts: its first segment [s]
  double descent_time = 0;  // [s]
  double descent_speed = 0;
  double lift = 0;  // height of the start pose above the trajectory's t = 0 pose [m]
  double Duration() const { return descent_time + trajectory.end_time() - offset; }
};

dem::MeshMotion MotionAt(const PassPlan& plan, double tau, const dem::Quat& heading,
                         const dem::Vec3& origin_shift) {
  ScoopKinematics k;
  dem::Vec3 extra;  // descent offset (world z)
  if (tau < plan.descent_time) {
    k = plan.trajectory.At(plan.offset);
    extra = {0, 0, plan.lift - plan.descent_speed * tau};
    k.velocity = {0, 0, -plan.descent_speed};
    k.angular_velocity = {};
  } else {
    k = plan.trajectory.At(tau - plan.descent_time + plan.offset);
  }
  // Heading: rotate the whole trajectory about the vertical through origin_shift.
  dem::MeshMotion m;
  m.pose.position = origin_shift + dem::Rotate(heading, k.pose.position - origin_shift) + extra;
  m.pose.orientation = heading * k.pose.orientation;
  m.velocity = dem::Rotate(heading, k.velocity);
  m.angular_velocity = dem::Rotate(heading, k.angular_velocity);
  return m;
}

double LowestZ(const dem::TriangleMesh& mesh, const dem::Pose& pose) {
  double z = 1e300;
  for (const dem::Vec3& v : mesh.vertices) z = std::min(z, dem::Apply(pose, v).z);
  return z;
}

}  // namespace

int RunDig(const Scene& scene, const RunOptions& options, dem::System* system, H5Output* out) {
  const DigSpec& dig = scene.dig;
  dem::TriangleMesh mesh = LoadMesh(dig.scoop.mesh, dig.scoop.scale);
  mesh.name = "scoop";
  mesh.material = dig.scoop.material_index;
  const dem::TriangleMesh* mesh_ptr = nullptr;
  const int k = system->AddMesh(mesh);
  mesh_ptr = &system->mesh(k);
  // Mass properties: from the scene, or from the mesh at the scene's density.
  double scoop_mass = dig.scoop.mass;
  dem::Vec3 com_scoop = dig.scoop.com;
  if (dig.scoop.density > 0) {
    try {
      const dem::MassProperties mp = dem::ComputeMassProperties(mesh, dig.scoop.density);
      scoop_mass = mp.mass;
      com_scoop = mp.center_of_mass;
    } catch (const std::invalid_argument& e) {
      throw InputError(dig.scoop.mesh + ": dig.scoop.density needs a closed mesh (" + e.what() +
                       ")");
    }
  }
  out->SetAttribute("scoop_mesh", dig.scoop.mesh);
  out->SetAttribute("scoop_mass", scoop_mass);
  out->SetAttribute("scoop_com_x", com_scoop.x);
  out->SetAttribute("scoop_com_y", com_scoop.y);
  out->SetAttribute("scoop_com_z", com_scoop.z);

  // Original surface: given, or the mean column top of the bed's central part (the columns
  // next to the walls are lower or higher by wall effects).
  const double r_max = scene.bed.radius_max;
  double surface = dig.surface;
  double bed_top = surface;
  if (!dig.surface_given) {
    const dem::Vec3 margin{4 * r_max, 4 * r_max, 0};
    surface =
        BedSurface(system->particles(), scene.box_min + margin, scene.box_max - margin, 4 * r_max);
  }
  for (size_t i = 0; i < system->particles().size(); ++i)
    bed_top = std::max(bed_top, system->particles().x[i].z + system->particles().radius[i]);
  out->SetAttribute("surface", surface);

  const BodyFrame body = StudyBodyFrame(dig.heading, scene.gravity);
  const dem::Vec3 trench{std::cos(dig.heading), std::sin(dig.heading), 0.0};
  const dem::Quat heading = Heading(dig.heading);
  const dem::Vec3 origin_shift{dig.trajectory.pivot_start.x, dig.trajectory.pivot_start.y, 0};
  const double dt = scene.time_step;
  const double lowest_level = LowestBelowPivot(*mesh_ptr, kLevel, dig.trajectory.pivot_offset);
  const Trajectory path(dig.trajectory);
  // The descent from clear of the bed goes at the approach's speed (the first move's, when it
  // translates), else at the study's 0.14 m/s.
  const double approach_speed =
      !path.spec().moves.empty() && path.spec().moves[0].kind == Move::Kind::kTranslate
          ? path.spec().moves[0].speed
          : 0.14;

  dem::SleepConfig sleep = scene.sleep;
  system->set_sleep(sleep);

  // Total simulated time for the progress line (descents are estimated).
  double total = 0;
  for (int p = 1; p <= dig.passes; ++p) total += Trajectory(dig.trajectory).end_time() + 0.3;
  Progress progress("dig", total, options.quiet);
  const auto wall0 = std::chrono::steady_clock::now();
  const dem::PhaseTimes phases0 = system->phase_times();
  const double t_start = system->time();
  const int64_t step0 = system->step_count();
  int64_t particle_steps = 0;
  int status = 0;
  double next_frame = system->time();
  DigSummary summary;
  summary.particles = static_cast<int64_t>(system->particles().size());
  double force_sum = 0;
  int64_t force_rows = 0;

  auto frame = [&](int pass, double rho, const ScoopWrench& w) {
    if (!options.on_frame) return;
    WorldView view;
    view.time = system->time();
    view.pass = pass;
    view.rho = rho;
    view.force = dem::Norm(w.force_world);
    view.torque = dem::Norm(w.torque_world);
    view.particles = &system->particles();
    view.meshes.push_back({mesh_ptr, system->mesh_motion(k).pose});
    view.box_min = scene.box_min;
    view.box_max = scene.box_max;
    view.gravity = scene.gravity;
    options.on_frame(view);
  };
  // Frames: every frame_every seconds, by default 20 a simulated second.
  const double frame_every = options.frame_every > 0 ? options.frame_every : 0.05;

  bool stopped_after = false;  // RunOptions::stop_after
  for (int pass = 1; pass <= dig.passes && status == 0; ++pass) {
    // Where the pass goes: the level scoop's lowest point at pass * bite below the surface.
    TrajectorySpec spec = dig.trajectory;
    spec.pivot_start.z = surface - pass * dig.bite_depth - lowest_level;
    spec.pivot_start.z -= path.LeadingDrop();
    PassPlan plan{Trajectory(spec)};
    // The pass starts with the first move (Table 1's 1.8 s before the approach are the study's
    // bed generation).
    plan.offset = plan.trajectory.start_time();
    const dem::MeshMotion first = MotionAt(plan, plan.descent_time, heading, origin_shift);
    if (dig.start_buried) {
      // The tool is placed in the bed at its start pose (as the testbed's scoop was inserted by
      // hand): the particles it would overlap are taken out first.
      const std::vector<int64_t> cut =
          ParticlesTouchingMesh(system->particles(), *mesh_ptr, first.pose);
      system->RemoveParticles(cut);
      std::fprintf(stderr, "scoopsim: pass %d starts buried: %zu particles removed from the tool\n",
                   pass, cut.size());
    } else {
      const double clear = bed_top + 2 * r_max;
      plan.lift = std::max(0.0, clear - LowestZ(*mesh_ptr, first.pose));
      plan.descent_speed = approach_speed;
      plan.descent_time = plan.lift / approach_speed;
    }

    const double t0 = system->time();
    const double duration = plan.Duration();
    double next_row = t0;
    double rho = 0;
    bool touched = false;
    dem::Vec3 com_contact;
    ScoopWrench w;
    system->SetMeshMotion(k, MotionAt(plan, 0.0, heading, origin_shift));
    while (system->time() - t0 < duration - 0.5 * dt) {
      // The mesh pose at the end of the coming step, where Step() evaluates forces.
      const double tau = system->time() + dt - t0;
      system->SetMeshMotion(k, MotionAt(plan, tau, heading, origin_shift));
      const dem::StepStatus st = system->Step();
      const dem::NeighborStats stats = system->neighbor_stats();
      particle_steps += stats.awake;
      summary.peak_overlap = std::max(summary.peak_overlap, stats.max_overlap);
      if (!st.ok()) {
        std::fprintf(stderr, "scoopsim: simulation unstable: %s\n", st.message.c_str());
        status = kExitUnstable;
        break;
      }
      const dem::MeshWrench mw = system->mesh_wrench(k);
      const dem::Pose& pose = system->mesh_motion(k).pose;
      w = ComputeScoopWrench(mw, pose, com_scoop, body);
      const dem::Vec3 com = dem::Apply(pose, com_scoop);
      // rho (paper Figs. 9-11): horizontal displacement of the CoM along the trench since the
      // scoop first touched a particle in this pass.
      if (!touched && mw.contacts > 0) {
        touched = true;
        com_contact = com;
      }
      if (touched) rho = dem::Dot(com - com_contact, trench);
      if (system->time() >= next_row) {
        next_row += dig.interval;
        const double t = system->time();
        const double passd = pass;
        const double contacts = static_cast<double>(mw.contacts);
        const double awake = static_cast<double>(system->neighbor_stats().awake);
        const double pose7[7] = {pose.position.x,    pose.position.y,    pose.position.z,
                                 pose.orientation.w, pose.orientation.x, pose.orientation.y,
                                 pose.orientation.z};
        auto row3 = [&](const char* name, const dem::Vec3& v) {
          const double a[3] = {v.x, v.y, v.z};
          out->AppendRow(name, a, 3);
        };
        const double fm = dem::Norm(w.force_world);
        summary.peak_force = std::max(summary.peak_force, fm);
        summary.peak_torque = std::max(summary.peak_torque, dem::Norm(w.torque_world));
        if (touched) {
          force_sum += fm;
          ++force_rows;
        }
        out->AppendRow("/scoop/time", &t, 1);
        out->AppendRow("/scoop/pass", &passd, 1);
        out->AppendRow("/scoop/rho", &rho, 1);
        row3("/scoop/force_body", w.force_body);
        row3("/scoop/torque_body", w.torque_body);
        row3("/scoop/force_scoop", w.force_scoop);
        row3("/scoop/torque_scoop", w.torque_scoop);
        row3("/scoop/force_world", w.force_world);
        row3("/scoop/torque_world", w.torque_world);
        out->AppendRow("/scoop/pose", pose7, 7);
        out->AppendRow("/scoop/contacts", &contacts, 1);
        out->AppendRow("/series/time", &t, 1);
        out->AppendRow("/series/awake", &awake, 1);
        const double ke = system->KineticEnergy();
        out->AppendRow("/series/kinetic_energy", &ke, 1);
      }
      const int64_t steps = system->step_count() - step0;
      if (scene.output.snapshot_every > 0 && steps % scene.output.snapshot_every == 0)
        out->WriteSnapshot(system->time(), system->particles());
      if (options.on_frame && system->time() >= next_frame) {
        next_frame += frame_every;
        frame(pass, rho, w);
      }
      if (steps % 64 == 0) {
        out->MaybeFlush();
        progress.Update(system->time() - t_start, particle_steps);
        if (StopRequested()) {
          std::fprintf(stderr, "scoopsim: stopped by signal %d at t = %.6g s; output closed\n",
                       StopSignal(), system->time());
          status = kExitStopped;
          break;
        }
      }
      if (options.stop_after > 0 && system->time() - t_start >= options.stop_after) {
        std::fprintf(stderr, "scoopsim: stopped at t = %.6g s (--stop-after); output closed\n",
                     system->time());
        stopped_after = true;
        break;
      }
    }
    if (status != 0 || stopped_after) break;
    // Empty the scoop: the particles in its cavity are the sample of this pass.
    double mass = 0;
    const std::vector<int64_t> held =
        ParticlesInCavity(system->particles(), system->mesh_motion(k).pose, dig.scoop.cavity_min,
                          dig.scoop.cavity_max, &mass, &system->clumps());
    system->RemoveParticles(held);
    out->AppendRow("/scoop/collected_mass", &mass, 1);
    summary.collected_mass.push_back(mass);
    const double count = static_cast<double>(held.size());
    out->AppendRow("/scoop/collected_count", &count, 1);
    std::fprintf(stderr, "scoopsim: pass %d: rho %.1f mm, collected %zu particles, %.4g kg\n", pass,
                 1e3 * rho, held.size(), mass);
  }
  progress.Finish(system->time() - t_start, particle_steps);
  summary.mean_force = force_rows > 0 ? force_sum / force_rows : 0.0;
  summary.steps = system->step_count() - step0;
  summary.simulated = system->time() - t_start;
  std::fprintf(stderr,
               "scoopsim: dig: %lld particles, %lld steps, %.4g s simulated; peak |F| %.4g N, "
               "mean |F| %.4g N (after first contact), peak |T| %.4g N m; %lld neighbour builds, "
               "%.3g awake particle-steps per step\n",
               static_cast<long long>(summary.particles), static_cast<long long>(summary.steps),
               summary.simulated, summary.peak_force, summary.mean_force, summary.peak_torque,
               static_cast<long long>(system->neighbor_stats().builds),
               static_cast<double>(particle_steps) / std::max<int64_t>(1, summary.steps));
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::fprintf(stderr, "scoopsim: dig: %.1f s wall: %s\n", wall,
               PhaseBreakdown(PhasesSince(system->phase_times(), phases0), wall).c_str());
  if (options.dig_summary) *options.dig_summary = summary;
  return status;
}

}  // namespace sim

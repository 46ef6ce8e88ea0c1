#include "render/saved_run.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "sim/files/arm_geometry.h"
#include "sim/files/saved_run.h"
#include "sim/input/mesh_io.h"

namespace render {

int RenderSavedRun(const std::string& h5_path, FrameSequence* frames, bool quiet) {
  if (frames->options().settings.color_by == ColorField::kForce) {
    throw sim::InputError(h5_path +
                          ": cannot colour by force: snapshots store no forces (use "
                          "speed, depth or material, or render while running with --frames)");
  }
  const sim::SavedRun run(h5_path);
  const std::vector<sim::SnapshotInfo> snapshots = run.Snapshots();
  const sim::StoredScene scene = run.Scene();
  // The scoop's series for the caption and its pose, when the run had a dig.
  const sim::ScoopSeries scoop = run.Scoop();
  // The scoop mesh the run used (root attribute scoop_mesh), drawn at /scoop/pose. A run moved
  // since, or a mesh no longer there, draws no scoop and says so once.
  dem::TriangleMesh scoop_mesh;
  const std::string scoop_path = run.RootAttribute("scoop_mesh");
  if (!scoop_path.empty() && !scoop.pose.empty()) {
    try {
      scoop_mesh = sim::LoadMesh(scoop_path);
    } catch (const sim::InputError& e) {
      std::fprintf(stderr, "scoopsim render: no scoop in the frames: %s\n", e.what());
    }
  }

  const sim::ArmSeries arm = run.Arm();
  // A bonded run's broken bonds (/bonds/broken/): each snapshot's per-particle count is that of
  // the records up to its time (the snapshots store no bonds).
  const bool broken_field = frames->options().settings.color_by == ColorField::kBrokenBonds;
  const sim::BondSeries bonds = broken_field ? run.Bonds() : sim::BondSeries();
  const auto broken_counts = [&](double t, const dem::Particles& p) {
    const int k = sim::SampleAt(bonds.broken_time, t) + 1;  // records at or before t
    const std::vector<int64_t> a(bonds.broken_a.begin(), bonds.broken_a.begin() + k);
    const std::vector<int64_t> b(bonds.broken_b.begin(), bonds.broken_b.begin() + k);
    return sim::BrokenBondCounts(p.id, a, b);
  };

  dem::Particles particles;
  // One colour range for the whole sequence: from every snapshot's field, unless given.
  if (!frames->options().range_given) {
    const ColorField field = frames->options().settings.color_by;
    AutoRange range;
    std::vector<float> values;
    for (const sim::SnapshotInfo& snapshot : snapshots) {
      run.ReadSnapshot(snapshot, &particles);
      sim::WorldView view;
      view.particles = &particles;
      if (broken_field) view.broken_bonds = broken_counts(snapshot.time, particles);
      ComputeField(view, field, &values);
      range.Update(field, values);
    }
    frames->SetRange(range.min(), range.max());
  }

  // The arm preset over the whole run: every snapshot's meshes and the box, so its camera stays.
  if (frames->options().camera_preset == "arm" && scene.has_box) {
    for (const sim::SnapshotInfo& snapshot : snapshots) {
      const std::vector<sim::SnapshotMesh> stored = run.ReadSnapshotMeshes(snapshot);
      sim::WorldView view;
      view.box_min = scene.has_box ? scene.box_min : dem::Vec3{};
      view.box_max = scene.has_box ? scene.box_max : dem::Vec3{};
      for (const sim::SnapshotMesh& m : stored)
        view.meshes.push_back({&m.mesh, dem::Pose{}, sim::MeshRole::kArmLink});
      dem::Vec3 lo, hi;
      PresetBounds("arm", view, &lo, &hi);
      frames->FrameAtLeast(lo, hi);
    }
  }

  int written = 0;
  const bool tty = isatty(fileno(stderr)) != 0;
  for (const sim::SnapshotInfo& snapshot : snapshots) {
    run.ReadSnapshot(snapshot, &particles);
    const size_t n = particles.size();

    sim::WorldView view;
    view.time = snapshot.time;
    view.particles = &particles;
    if (broken_field) view.broken_bonds = broken_counts(snapshot.time, particles);
    if (scene.has_gravity) view.gravity = scene.gravity;
    if (scene.has_box) {
      view.box_min = scene.box_min;
      view.box_max = scene.box_max;
    } else {
      // No box in the stored scene: the particles' extent.
      view.box_min = {1e300, 1e300, 1e300};
      view.box_max = {-1e300, -1e300, -1e300};
      for (size_t i = 0; i < n; ++i) {
        const double r = particles.radius[i];
        const dem::Vec3& p = particles.x[i];
        view.box_min = {std::min(view.box_min.x, p.x - r), std::min(view.box_min.y, p.y - r),
                        std::min(view.box_min.z, p.z - r)};
        view.box_max = {std::max(view.box_max.x, p.x + r), std::max(view.box_max.y, p.y + r),
                        std::max(view.box_max.z, p.z + r)};
      }
    }
    // The meshes stored with the snapshot (world coordinates); a file written before they were
    // stored: the scoop at the last /scoop/ sample at or before the snapshot.
    const std::vector<sim::SnapshotMesh> stored = run.ReadSnapshotMeshes(snapshot);
    for (const sim::SnapshotMesh& m : stored) {
      const sim::MeshRole role = m.name == "arm"         ? sim::MeshRole::kArmLink
                                 : m.name == "obstacles" ? sim::MeshRole::kObstacle
                                                         : sim::MeshRole::kScoop;
      view.meshes.push_back({&m.mesh, dem::Pose{}, role});
    }
    const int k = scoop.SampleAt(snapshot.time);
    if (k >= 0) {
      if (!scoop.pass.empty()) view.pass = scoop.pass[k];
      if (!scoop.rho.empty()) view.rho = scoop.rho[k];
      if (!scoop.force_world.empty()) view.force = dem::Norm(scoop.force_world[k]);
      if (stored.empty() && !scoop_mesh.triangles.empty())
        view.meshes.push_back({&scoop_mesh, scoop.pose[k]});
    }
    // The arm's torque bars and fault flags at the last /arm/ sample at or before it (the first
    // sample for a snapshot before it: the dig's first, taken before the first step).
    const int a = arm.empty() ? -1 : std::max(sim::SampleAt(arm.time, snapshot.time), 0);
    if (a >= 0) {
      const size_t n = arm.joints.size();
      for (size_t j = 0; j < n; ++j)
        view.joints.push_back(
            {arm.joints[j], arm.torque_demanded[a * n + j], arm.effort_limit[a * n + j]});
      view.faults = sim::FaultNames(arm.fault_latched[a]);
    }
    frames->Add(view);
    ++written;
    // A live line on a terminal; a line every 50 frames (and the last) otherwise.
    if (!quiet && tty) {
      std::fprintf(stderr, "\rscoopsim render: frame %d/%zu (t = %.5f s)", written,
                   snapshots.size(), snapshot.time);
    } else if (!quiet && (written % 50 == 0 || written == static_cast<int>(snapshots.size()))) {
      std::fprintf(stderr, "scoopsim render: frame %d/%zu (t = %.5f s)\n", written,
                   snapshots.size(), snapshot.time);
    }
  }
  if (!quiet && tty) std::fprintf(stderr, "\n");
  return written;
}

}  // namespace render

#include "sim/loop/world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>

#include "dem/archive.h"
#include "sim/files/bed_io.h"
#include "sim/files/saved_run.h"
#include "sim/input/exit_status.h"
#include "sim/loop/progress.h"

namespace sim {

// The dig's state: the scoop, its driver and the current pass.
struct World::Dig {
  std::unique_ptr<ScoopDriver> driver;
  int mesh = -1;          // index in the DEM system
  dem::Vec3 com_scoop;    // scoop centre of mass in l_scoop [m]
  BodyFrame body;         // the study's body frame
  dem::Vec3 trench;       // unit digging direction, world
  BedContext bed;         // surface, clearance, mesh, step
  int pass = 0;           // 1-based; passes + 1 once done
  double pass_t0 = 0;     // time the current pass began [s]
  double next_row = 0;    // time of the next /scoop/ row [s]
  bool touched = false;   // the scoop has touched a particle in this pass
  dem::Vec3 com_contact;  // CoM at first touch [m]
  double rho = 0;         // CoM travel along the trench since first touch [m]
  double rho_path = 0;    // CoM path length since first touch [m] (the study's rho)
  dem::Vec3 com_last;     // CoM at the last step, for rho_path [m]
  ScoopWrench wrench;     // of the last step
  double force_sum = 0;   // |F| over the rows after first contact, for the mean [N]
  int64_t force_rows = 0;
  double planned = 0;  // all passes [s]
  // A driver with its own wrench (ScoopDriver::OwnStep() > 0): no bed, no DEM step.
  double own_step = 0;         // its step [s]; 0: the DEM's wrench and step
  int64_t steps = 0;           // its steps since the dig began
  int64_t pass_steps = 0;      // and since the current pass began
  dem::MeshWrench own_wrench;  // of the last step
};

namespace {

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

void Row3(H5Output* out, const char* name, const dem::Vec3& v) {
  const double a[3] = {v.x, v.y, v.z};
  out->AppendRow(name, a, 3);
}

}  // namespace

World::World(const Scene& scene, int threads)
    : scene_(scene),
      system_(std::make_unique<dem::System>(scene.materials, MakeSystemConfig(scene))) {
  if (threads > 0) system_->set_num_threads(threads);
}

World::~World() = default;

void World::LoadBed(const std::string& path) {
  sim::LoadBed(path, system_.get());
  system_->Canonicalize();
  BondBed();
}

int64_t World::BondBed() {
  if (!scene_.bed.bonds.enabled || !system_->bonds().empty()) return 0;
  const double surface = BondSurface(scene_, system_->particles());
  const std::vector<dem::Bond> bonds = MakeBedBonds(*system_, scene_.bed.bonds, surface);
  system_->AddBonds(bonds);
  const size_t spheres = system_->particles().size();
  Status(
      "scoopsim: bonds: %zu made within a gap of %.4g m (%.3g per sphere; bond depths from "
      "the surface at z = %.6g m)\n",
      bonds.size(), scene_.bed.bonds.gap,
      spheres > 0 ? 2.0 * static_cast<double>(bonds.size()) / static_cast<double>(spheres) : 0.0,
      surface);
  return static_cast<int64_t>(bonds.size());
}

void World::LoadState(const std::string& path) {
  sim::LoadBed(path, system_.get());
  system_->set_sleep(scene_.sleep);
  system_->Canonicalize();
  sleep_applied_ = true;
}

void World::KeepPour(const std::string& path, double every, std::function<void()> on_keep) {
  pour_file_ = path;
  pour_every_ = every > 0 ? every : scene_.output.flush_seconds;
  on_keep_ = std::move(on_keep);
}

int World::Pour(bool quiet, SettleReport* report) {
  namespace fs = std::filesystem;
  // A pour this scene left unfinished in the keep file goes on from there: from its whole state
  // (bit for bit), or, kept by an older scoopsim, from its bed (the same bed in law, not in bits).
  PourPoint point;
  std::vector<char> state;
  if (!pour_file_.empty() && ReadPourPoint(pour_file_, scene_.yaml_text, &point, &state)) {
    if (!state.empty()) {
      try {
        system_->RestoreState(state);
      } catch (const std::runtime_error& e) {
        throw InputError(pour_file_ + ": /pour_state does not fit this scene's system (" +
                         e.what() + "); remove the file to pour anew");
      }
    } else {
      sim::LoadBed(pour_file_, system_.get());
      system_->Canonicalize();
    }
    Status("scoopsim: the pour goes on from %s: %lld of %lld bodies poured (layer %d)\n",
           pour_file_.c_str(), static_cast<long long>(point.poured),
           static_cast<long long>(scene_.bed.count), point.layers);
  }
  Progress progress("bed", scene_.bed.settle_max_time, quiet);
  progress.set_open_ended(true);  // settling ends when the bed is at rest, often well before
  // The time shown is the pour's own (a pour starts a fresh system at t = 0); a resumed pour's
  // rate and ETA count from where it went on.
  auto particle_steps = [&] {
    return system_->step_count() * static_cast<int64_t>(system_->particles().size());
  };
  progress.Begin(system_->time(), particle_steps());
  // The bed so far goes to the keep file every output.flush_seconds and when stopped.
  auto last_keep = std::chrono::steady_clock::now();
  double keep_every = pour_every_;
  auto keep = [&] {
    const auto keep0 = std::chrono::steady_clock::now();
    SaveBed(pour_file_, *system_, scene_.yaml_text, &point);
    last_keep = std::chrono::steady_clock::now();
    // A big bed's keep takes seconds: keeping costs at most a tenth of the run.
    keep_every = std::max(pour_every_, 10 * Seconds(last_keep - keep0));
    if (on_keep_) on_keep_();
  };
  SettleReport& r = *report;
  r = FillAndSettle(
      scene_, system_.get(),
      [&](const dem::System& s) {
        progress.Update(s.time(), particle_steps());
        if (!pour_file_.empty() && point.started && !StopRequested() &&
            Seconds(std::chrono::steady_clock::now() - last_keep) >= keep_every)
          keep();
        return !StopRequested();
      },
      &point);
  // Stopped by a signal: the last line says how far the pour got, not 100%.
  progress.Finish(system_->time(), particle_steps(), !StopRequested());
  // (A pour that has ended is not kept: the bed is whole, and is made ready and returned.)
  const bool ended = point.settled && point.poured >= scene_.bed.count;
  if (!pour_file_.empty() && StopRequested() && point.started && !ended && r.status.ok()) {
    keep();
    Status(
        "scoopsim: the bed poured so far (%lld of %lld bodies) is in %s; the same command goes "
        "on from it\n",
        static_cast<long long>(point.poured), static_cast<long long>(scene_.bed.count),
        pour_file_.c_str());
  }
  int status = kExitOk;
  if (!r.status.ok()) {
    Status("scoopsim: simulation unstable: %s\n", r.status.message.c_str());
    return kExitUnstable;
  }
  if (StopRequested() && !ended) return kExitStopped;
  if (system_->num_bodies() < scene_.bed.count) {
    Status(
        "scoopsim: %s: the box holds only %lld of bed.count = %lld particles; raise box.max or "
        "lower bed.count\n",
        scene_.path.c_str(), static_cast<long long>(system_->num_bodies()),
        static_cast<long long>(scene_.bed.count));
    status = kExitNotSettled;
  } else if (!r.settled) {
    Status(
        "scoopsim: bed not settled after %.3g s (mean kinetic energy %.3g J > %.3g J); raise "
        "bed.settle.max_time or bed.settle.kinetic_energy\n",
        r.sim_time, r.mean_ke, scene_.bed.settle_ke);
    status = kExitNotSettled;
  }
  // Storage and lists a function of positions and ids alone, ready to save or run.
  system_->Canonicalize();
  if (!pour_file_.empty()) {
    std::error_code ignored;
    fs::remove(pour_file_, ignored);  // finished: nothing to go on from
    fs::remove(fs::path(pour_file_).replace_extension(".xdmf"), ignored);
  }
  return status;
}

void World::OpenOutput(const std::string& path, const OutputCursor* resume) {
  owned_out_ = std::make_unique<H5Output>(path, scene_.yaml_text, SCOOPSIM_VERSION,
                                          scene_.output.flush_seconds, resume);
  out_ = owned_out_.get();
  // The step and the rule that set it (issue 44: a bond may force a smaller one than the
  // contact's rayleigh_fraction x t_R).
  out_->SetAttribute("time_step", scene_.time_step);
  out_->SetAttribute("time_step_rule", std::string(TimeStepRule(scene_)));
}

template <typename Archive>
void World::LoopFields(Archive& a) {
  a(started_);
  a(sleep_applied_);
  a(t_start_);
  a(next_row_);
  a(step0_);
  a(particle_steps_);
  a(summary_.peak_force);
  a(summary_.mean_force);
  a(summary_.peak_torque);
  a(summary_.peak_overlap);
  a(summary_.collected_mass);
  a(summary_.particles);
  a(summary_.steps);
  a(summary_.simulated);
  if (!dig_) return;
  Dig& d = *dig_;
  a(d.pass_t0);
  a(d.next_row);
  a(d.touched);
  a(d.com_contact);
  a(d.rho);
  a(d.rho_path);
  a(d.com_last);
  a(d.wrench);
  a(d.force_sum);
  a(d.force_rows);
  a(d.planned);
  a(d.bed.start_time);
  // (A dig without a bed, the arm's on a table, is never checkpointed: Bullet's state is not
  // saved, RunScene refuses it; its step counts are not listed.)
}

Checkpoint World::MakeCheckpoint() {
  Checkpoint c;
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(scene_.path, ec);
  c.scene_path = ec ? scene_.path : absolute.string();  // resumable from any folder
  c.scene_yaml = scene_.yaml_text;
  c.time = system_->time();
  if (out_) c.output_state = EncodeCursor(out_->Cursor());
  c.dem_state = system_->SaveState();
  dem::ArchiveWriter a;
  const uint8_t dig = dig_ != nullptr;
  const DigResume at = dig ? ResumePoint() : DigResume{};
  a(dig);
  a(at);
  LoopFields(a);
  c.world_state = a.bytes();
  return c;
}

void World::ResumeFrom(const Checkpoint& c, std::unique_ptr<ScoopDriver> driver,
                       const std::string& source) {
  try {
    dem::ArchiveReader a(c.world_state);
    uint8_t dig = 0;
    DigResume at;
    a(dig);
    a(at);
    if ((dig != 0) != (driver != nullptr))
      throw std::runtime_error(dig ? "a dig's checkpoint, the scene has none"
                                   : "a plain run's checkpoint, the scene has a dig");
    if (dig) StartDig(std::move(driver), &at);
    system_->RestoreState(c.dem_state);
    LoopFields(a);
    if (!a.done()) throw std::runtime_error("/world_state: bytes left over");
    // Resumed with more passes than the checkpoint's run planned (RunScene takes that change):
    // the progress line's plan is all of them. (The plan sets no datum, only the ETA and the
    // room made in /snapshots.)
    if (dig) {
      double all = 0;
      for (int pass = 1; pass <= scene_.dig.passes; ++pass)
        all += dig_->driver->PlannedDuration(pass, dig_->bed);
      dig_->planned = std::max(dig_->planned, all);
    }
  } catch (const std::runtime_error& e) {
    throw InputError(source + ": " + e.what());
  }
  // The run's start, as the uninterrupted run wrote it (StartDig wrote the fresh system's 0; a
  // plain run, started already, does not start again to write it).
  if (out_ && started_) out_->SetAttribute("start_time", t_start_);
}

void World::UseOutput(H5Output* out) {
  owned_out_.reset();
  out_ = out;
}

void World::StartDig(std::unique_ptr<ScoopDriver> driver, const DigResume* resume) {
  const DigSpec& spec = scene_.dig;
  dig_ = std::make_unique<Dig>();
  Dig& dig = *dig_;
  dig.driver = std::move(driver);
  dig.own_step = dig.driver->OwnStep();
  // The mesh and its mass properties were read and checked with the scene (LoadScene).
  dig.mesh = system_->AddMesh(spec.scoop.geometry);
  const double scoop_mass = spec.scoop.mass;
  dig.com_scoop = spec.scoop.com;
  if (out_) {
    // Absolute, so that render finds it from any folder and a resumed run (whose scene path is
    // absolute, see Checkpoint) writes the same attribute as the uninterrupted one.
    std::error_code ec;
    const std::filesystem::path mesh = std::filesystem::absolute(spec.scoop.mesh, ec);
    out_->SetAttribute("scoop_mesh", ec ? spec.scoop.mesh : mesh.lexically_normal().string());
    out_->SetAttribute("scoop_mass", scoop_mass);
    out_->SetAttribute("scoop_com_x", dig.com_scoop.x);
    out_->SetAttribute("scoop_com_y", dig.com_scoop.y);
    out_->SetAttribute("scoop_com_z", dig.com_scoop.z);
  }

  // Original surface: given, or the mean column top of the bed's central part (the columns next
  // to the walls are lower or higher by wall effects).
  // A resumed dig keeps those of its first pass.
  const dem::Particles& p = system_->particles();
  const double r_max = scene_.bed.radius_max;
  double surface = spec.surface;
  double bed_top = surface;
  if (!spec.surface_given) {
    const dem::Vec3 margin{4 * r_max, 4 * r_max, 0};
    surface = BedSurface(p, scene_.box_min + margin, scene_.box_max - margin, 4 * r_max);
  }
  for (size_t i = 0; i < p.size(); ++i) bed_top = std::max(bed_top, p.x[i].z + p.radius[i]);
  double clear_z = bed_top + 2 * r_max;
  // No bed (a driver with its own wrench): the scoop comes down from a few radii above the surface.
  if (dig.own_step > 0) clear_z = surface + 3 * r_max;
  const int first_pass = resume ? resume->first_pass : 1;
  if (resume) {
    surface = resume->surface;
    clear_z = resume->clear_z;
  }
  if (out_) out_->SetAttribute("surface", surface);
  dig.bed = {&system_->mesh(dig.mesh), surface, clear_z, StepSize(), system_->time()};
  if (!scene_.obstacles.empty()) {
    AddObstacles();
    dig.bed.mesh = &system_->mesh(dig.mesh);  // AddMesh may have moved the meshes
  }
  dig.body = StudyBodyFrame(spec.heading, scene_.gravity);
  dig.trench = {std::cos(spec.heading), std::sin(spec.heading), 0.0};
  for (int pass = first_pass; pass <= spec.passes; ++pass)
    dig.planned += dig.driver->PlannedDuration(pass, dig.bed);
  PlanSnapshots();

  system_->set_sleep(scene_.sleep);
  summary_ = DigSummary{};
  summary_.particles = static_cast<int64_t>(p.size());
  t_start_ = system_->time();
  if (out_) out_->SetAttribute("start_time", t_start_);
  step0_ = system_->step_count();
  particle_steps_ = 0;
  started_ = true;
  dig.pass = first_pass;
  if (!Done()) BeginPass();
  // A snapshot at the dig's start (the scoop placed, the arm at its first pose), as a plain run
  // has one at its start: a replay's first frame. (A resumed dig has it already.)
  if (out_ && resume == nullptr && scene_.output.snapshot_every > 0)
    out_->WriteSnapshot(system_->time(), system_->particles(), View().meshes);
}

DigResume World::ResumePoint() const { return {dig_->pass, dig_->bed.surface, dig_->bed.clear_z}; }

void World::BeginPass() {
  Dig& dig = *dig_;
  const PassStart start = dig.driver->BeginPass(dig.pass, dig.bed);
  if (start.start_buried && dig.own_step == 0) {
    // The tool is placed in the bed at its start pose (as the testbed's scoop was inserted by
    // hand): the particles it would overlap are taken out first.
    const std::vector<int64_t> cut = ParticlesTouchingMesh(
        system_->particles(), system_->mesh(dig.mesh), dig.driver->MotionAt(0.0).pose);
    system_->RemoveParticles(cut);
    Status("scoopsim: pass %d starts buried: %zu particles removed from the tool\n", dig.pass,
           cut.size());
  }
  dig.pass_t0 = system_->time();
  dig.pass_steps = 0;
  dig.next_row = dig.pass_t0;
  dig.rho = 0;
  dig.rho_path = 0;
  dig.touched = false;
  system_->SetMeshMotion(dig.mesh, dig.driver->MotionAt(0.0));
}

void World::EndPass() {
  Dig& dig = *dig_;
  // Empty the scoop: the particles in its cavity are the sample of this pass.
  double mass = 0;
  const std::vector<int64_t> held = ParticlesInCavity(
      system_->particles(), system_->mesh_motion(dig.mesh).pose, scene_.dig.scoop.cavity_min,
      scene_.dig.scoop.cavity_max, &mass, &system_->clumps());
  system_->RemoveParticles(held);
  summary_.collected_mass.push_back(mass);
  if (out_) {
    out_->AppendRow("/scoop/collected_mass", &mass, 1);
    const double count = static_cast<double>(held.size());
    out_->AppendRow("/scoop/collected_count", &count, 1);
  }
  Status("scoopsim: pass %d: rho %.1f mm, collected %zu particles, %.4g kg\n", dig.pass,
         1e3 * dig.rho, held.size(), mass);
}

const ScoopWrench* World::scoop_wrench() const { return dig_ ? &dig_->wrench : nullptr; }
int World::scoop_mesh() const { return dig_ ? dig_->mesh : -1; }

bool World::Done() const {
  if (dig_) return dig_->pass > scene_.dig.passes;
  return !(system_->time() < t_start_ + scene_.duration - 0.5 * scene_.time_step);
}

double World::PlannedDuration() const { return dig_ ? dig_->planned : scene_.duration; }

double World::StepSize() const {
  return dig_ && dig_->own_step > 0 ? dig_->own_step : scene_.time_step;
}

int64_t World::StepsDone() const {
  return dig_ && dig_->own_step > 0 ? dig_->steps : system_->step_count() - step0_;
}

void World::RecordPlainRow() {
  const double t = system_->time();
  out_->AppendRow("/series/time", &t, 1);
  const double ke = system_->KineticEnergy();
  out_->AppendRow("/series/kinetic_energy", &ke, 1);
  const double contacts = static_cast<double>(system_->neighbor_stats().contacts);
  out_->AppendRow("/series/contacts", &contacts, 1);
  std::vector<double> forces;
  for (int k = 0; k < static_cast<int>(system_->config().planes.size()); ++k) {
    const dem::Vec3 f = system_->plane_force(k);
    forces.insert(forces.end(), {f.x, f.y, f.z});
  }
  out_->AppendRow("/series/wall_force", forces.data(), static_cast<int>(forces.size()));
  RecordBondRow();
}

void World::RecordBondRow() {
  if (system_->bond_count() == 0) return;
  const double t = system_->time();
  const double intact = static_cast<double>(system_->intact_bond_count());
  out_->AppendRow("/bonds/time", &t, 1);
  out_->AppendRow("/bonds/intact", &intact, 1);
}

void World::RecordBondBreaks() {
  if (system_->bond_count() == 0) return;
  // Taken every step, written or not, so that none waits in the system (a checkpoint then holds
  // none pending) and the live view's counts come from bonds() alone.
  const std::vector<dem::BondBreak> breaks = system_->TakeBondBreaks();
  if (!out_) return;
  for (const dem::BondBreak& k : breaks) {
    const uint64_t pair[2] = {static_cast<uint64_t>(k.a), static_cast<uint64_t>(k.b)};
    const uint64_t mode = static_cast<uint64_t>(k.mode);
    out_->AppendRow("/bonds/broken/time", &k.time, 1);
    out_->AppendRow("/bonds/broken/pair", pair, 2);
    Row3(out_, "/bonds/broken/position", k.position);
    out_->AppendRow("/bonds/broken/mode", &mode, 1);
    out_->AppendRow("/bonds/broken/stress", &k.stress, 1);
  }
}

void World::RecordDigRow() {
  Dig& dig = *dig_;
  const ScoopWrench& w = dig.wrench;
  const double fm = dem::Norm(w.force_world);
  summary_.peak_force = std::max(summary_.peak_force, fm);
  summary_.peak_torque = std::max(summary_.peak_torque, dem::Norm(w.torque_world));
  if (dig.touched) {
    dig.force_sum += fm;
    ++dig.force_rows;
  }
  if (!out_) return;
  const double t = system_->time();
  const double pass = dig.pass;
  const dem::Pose& pose = system_->mesh_motion(dig.mesh).pose;
  const double contacts = static_cast<double>(system_->mesh_wrench(dig.mesh).contacts);
  const double awake = static_cast<double>(system_->neighbor_stats().awake);
  const double pose7[7] = {pose.position.x,    pose.position.y,    pose.position.z,
                           pose.orientation.w, pose.orientation.x, pose.orientation.y,
                           pose.orientation.z};
  out_->AppendRow("/scoop/time", &t, 1);
  out_->AppendRow("/scoop/pass", &pass, 1);
  out_->AppendRow("/scoop/rho", &dig.rho, 1);
  out_->AppendRow("/scoop/rho_path", &dig.rho_path, 1);
  Row3(out_, "/scoop/force_body", w.force_body);
  Row3(out_, "/scoop/torque_body", w.torque_body);
  Row3(out_, "/scoop/force_scoop", w.force_scoop);
  Row3(out_, "/scoop/torque_scoop", w.torque_scoop);
  Row3(out_, "/scoop/force_world", w.force_world);
  Row3(out_, "/scoop/torque_world", w.torque_world);
  out_->SetSeriesAttribute("/scoop/pose", "quaternion_order", kQuaternionOrder);
  out_->SetSeriesAttribute("/scoop/pose", "columns", kPoseColumns);
  out_->AppendRow("/scoop/pose", pose7, 7);
  out_->AppendRow("/scoop/contacts", &contacts, 1);
  out_->AppendRow("/series/time", &t, 1);
  out_->AppendRow("/series/awake", &awake, 1);
  const double ke = system_->KineticEnergy();
  out_->AppendRow("/series/kinetic_energy", &ke, 1);
  RecordBondRow();
  dig.driver->Record(out_, t);
}

void World::AddObstacles() {
  // Fixed rigid spheres (scene `obstacles:`): a fixed mesh each, after the scoop's; the particles
  // they overlap are taken out (the boulder was there before the bed).
  for (const ObstacleSpec& o : scene_.obstacles) {
    const int k = system_->AddMesh(SphereMesh(o.radius, o.material_index));
    dem::MeshMotion fixed;
    fixed.pose.position = o.center;
    system_->SetMeshMotion(k, fixed);
    obstacle_meshes_.push_back(k);
    const std::vector<int64_t> cut = ParticlesInSphere(system_->particles(), o.center, o.radius);
    system_->RemoveParticles(cut);
    Status("scoopsim: obstacle: sphere r %.3g m at (%.3g, %.3g, %.3g): %zu particles removed\n",
           o.radius, o.center.x, o.center.y, o.center.z, cut.size());
  }
}

namespace {

dem::StepStatus OutputFailed(double time, const std::exception& e) {
  dem::StepStatus status;
  status.flags = kOutputFailed;
  status.time = time;
  char at[64];
  std::snprintf(at, sizeof at, "output failed at t = %.6g s: ", time);
  status.message = at + std::string(e.what());
  return status;
}

}  // namespace

dem::StepStatus World::Step() noexcept {
  dem::System& system = *system_;
  try {
    if (!dig_ && !started_) StartPlain();
  } catch (const std::exception& e) {
    return OutputFailed(system.time(), e);
  }
  if (dig_ && Done()) return {};  // the scene's duration bounds Run(), not a plain Step()
  if (dig_ && dig_->own_step > 0) {
    // No bed (sim/loop/scoop_driver.h): the driver's motion and its own wrench, no DEM step; the
    // clock is the pass's start plus a whole number of the driver's steps.
    Dig& dig = *dig_;
    ++dig.steps;
    ++dig.pass_steps;
    const double tau = static_cast<double>(dig.pass_steps) * dig.own_step;
    const dem::MeshMotion motion = dig.driver->MotionAt(tau);
    system.SetMeshMotion(dig.mesh, motion);
    system.set_time(dig.pass_t0 + tau);
    dig.own_wrench = dig.driver->OwnWrench(motion.pose);
    dig.driver->Feedback(tau, dig.own_wrench);
  } else if (dig_) {
    // The scoop's pose at the end of the coming step, where Step() evaluates forces. The driver
    // (the arm's Bullet step) runs inside the step, beside the pair forces (dem/system.h): the
    // DEM does not read the scoop's pose before then.
    const double tau = system.time() + scene_.time_step - dig_->pass_t0;
    const std::function<void()> motion = [this, &tau] {  // small enough to need no allocation
      system_->SetMeshMotion(dig_->mesh, dig_->driver->MotionAt(tau));
    };
    const dem::StepStatus status = system.Step(motion);
    const dem::NeighborStats stats = system.neighbor_stats();
    particle_steps_ += stats.awake;
    summary_.peak_overlap = std::max(summary_.peak_overlap, stats.max_overlap);
    if (!status.ok()) return status;
    dig_->driver->Feedback(tau, system.mesh_wrench(dig_->mesh));
  } else {
    const dem::StepStatus status = system.Step();
    if (!status.ok()) return status;
    particle_steps_ += system.neighbor_stats().awake;
  }
  try {
    Record();
  } catch (const std::exception& e) {
    return OutputFailed(system.time(), e);
  }
  return {};
}

void World::Record() {
  dem::System& system = *system_;
  RecordBondBreaks();
  if (!dig_) {
    // A plain run: a /series/ row every output.interval.
    if (out_ && system.time() >= next_row_) {
      RecordPlainRow();
      next_row_ += scene_.output.interval;
    }
  } else {
    Dig& dig = *dig_;
    // The wrench on the scoop: the particles' (their contacts), or the driver's own without a bed.
    const dem::MeshWrench mw = dig.own_step > 0 ? dig.own_wrench : system.mesh_wrench(dig.mesh);
    const dem::Pose& pose = system.mesh_motion(dig.mesh).pose;
    dig.wrench = ComputeScoopWrench(mw, pose, dig.com_scoop, dig.body);
    const dem::Vec3 com = dem::Apply(pose, dig.com_scoop);
    // Two measures of the distance since the scoop first touched a particle in this pass:
    // rho_path, the length of the CoM's path (paper eq. 1's rho, "the relative distance covered
    // along the trench since the first contact", 0-450 mm for the Table 4 path, whose CoM path
    // is 470 mm; docs/studies.md "The table's rho"), summed step by step as chords (a 30 deg/s
    // arc of 45 mm radius differs from its chords by < 1e-9 of its length at dt = 1e-5 s); and
    // rho, the CoM's displacement along the trench (390 mm for that path).
    if (!dig.touched && mw.contacts > 0) {
      dig.touched = true;
      dig.com_contact = com;
      dig.com_last = com;
    }
    if (dig.touched) {
      dig.rho = dem::Dot(com - dig.com_contact, dig.trench);
      dig.rho_path += dem::Norm(com - dig.com_last);
      dig.com_last = com;
    }
    if (system.time() >= dig.next_row) {
      dig.next_row += scene_.dig.interval;
      RecordDigRow();
    }
  }
  const int64_t steps = StepsDone();
  if (out_ && scene_.output.snapshot_every > 0 && steps % scene_.output.snapshot_every == 0)
    out_->WriteSnapshot(system.time(), system.particles(), View().meshes);
  // A pass ends when its driver says so; the next one begins at once.
  // RunControl::on_pass_end sees the bed between the two.
  while (dig_ && halted_after_pass_ == 0 && !Done() &&
         dig_->driver->PassOver(system.time() - dig_->pass_t0)) {
    EndPass();
    const int ended = dig_->pass++;
    if (control_ && control_->on_pass_end && !control_->on_pass_end(ended)) {
      halted_after_pass_ = ended;
      break;
    }
    if (dig_->pass <= scene_.dig.passes) BeginPass();
  }
}

WorldView World::View() const {
  WorldView view;
  view.time = system_->time();
  view.particles = &system_->particles();
  view.box_min = scene_.box_min;
  view.box_max = scene_.box_max;
  view.gravity = scene_.gravity;
  if (!system_->bonds().empty()) {
    std::vector<int64_t> a, b;
    for (const dem::Bond& bond : system_->bonds()) {
      if (bond.intact) continue;
      a.push_back(bond.a);
      b.push_back(bond.b);
    }
    view.broken_bonds = BrokenBondCounts(system_->particles().id, a, b);
  }
  if (dig_) {
    view.pass = std::min(dig_->pass, scene_.dig.passes);
    view.rho = dig_->rho;
    view.force = dem::Norm(dig_->wrench.force_world);
    view.torque = dem::Norm(dig_->wrench.torque_world);
    view.meshes.push_back(
        {&system_->mesh(dig_->mesh), system_->mesh_motion(dig_->mesh).pose, MeshRole::kScoop});
    for (int k : obstacle_meshes_)
      view.meshes.push_back({&system_->mesh(k), system_->mesh_motion(k).pose, MeshRole::kObstacle});
    dig_->driver->AddToView(&view);
  }
  return view;
}

void World::StartPlain() {
  started_ = true;
  if (!sleep_applied_) system_->set_sleep(scene_.sleep);
  t_start_ = next_row_ = system_->time();
  if (out_) out_->SetAttribute("start_time", t_start_);
  step0_ = system_->step_count();
  particle_steps_ = 0;
  PlanSnapshots();
  if (out_ && scene_.output.snapshot_every > 0)
    out_->WriteSnapshot(system_->time(), system_->particles());
}

void World::PlanSnapshots() {
  if (!out_ || scene_.output.snapshot_every <= 0) return;
  const double steps = PlannedDuration() / StepSize();
  const double every = static_cast<double>(scene_.output.snapshot_every);
  // (A plan beyond what a file can index compactly only sets the most room there is.)
  out_->PlanSnapshots(static_cast<int64_t>(std::min(steps / every, 1e6)) + 2);
}

RunResult World::Run(const RunControl& control) {
  dem::System& system = *system_;
  if (!dig_ && !started_) StartPlain();
  Progress progress(dig_ ? "dig" : "run", PlannedDuration(), control.quiet);
  progress.set_clock_start(t_start_);  // one clock: the state's (README "One clock")
  progress.Begin(system.time() - t_start_, particle_steps_);  // a resumed run: from its checkpoint
  const auto wall0 = std::chrono::steady_clock::now();
  const dem::PhaseTimes phases0 = system.phase_times();

  // Frames at t0 and then every frame_every seconds, from this thread between steps, so no
  // OpenMP region is active while a frame renders.
  const double frame_every = control.frame_every > 0 ? control.frame_every
                             : dig_                  ? 0.05
                                                     : scene_.output.interval;
  const double slack = 1e-3 * StepSize();
  double next_frame = system.time();
  auto maybe_frame = [&] {
    if (!control.on_frame || system.time() < next_frame - slack) return;
    control.on_frame(View());
    while (next_frame <= system.time() + slack) {
      const double after = next_frame + frame_every;
      if (!(after > next_frame)) {  // a spacing below the clock's resolution: every step
        next_frame = system.time() + slack + StepSize();
        break;
      }
      next_frame = after;
    }
  };
  maybe_frame();

  RunResult result;
  control_ = &control;
  auto last_checkpoint = std::chrono::steady_clock::now();
  // Writes one; false (the failure said) when it could not be written.
  auto checkpoint = [&] {
    try {
      WriteCheckpoint(control.checkpoint_path, MakeCheckpoint());
      if (control.on_checkpoint) control.on_checkpoint();
      return true;
    } catch (const std::exception& e) {
      Status("scoopsim: %s\n", OutputFailed(system.time(), e).message.c_str());
      return false;
    }
  };
  if (control.checkpoint_every > 0) {
    // One at the start: a run killed before its first period (after a long pour, say) resumes.
    if (!checkpoint()) result.exit_status = kExitFailure;
  }
  if (halted_after_pass_ > 0) {  // an earlier Run() stopped between passes: go on
    halted_after_pass_ = 0;
    if (!Done()) BeginPass();
  }
  while (!Done() && result.exit_status == kExitOk) {
    const dem::StepStatus status = Step();
    if (status.flags & kOutputFailed) {
      Status("scoopsim: %s\n", status.message.c_str());
      result.exit_status = kExitFailure;
      break;
    }
    if (!status.ok()) {
      Status("scoopsim: simulation unstable: %s\n", status.message.c_str());
      result.exit_status = kExitUnstable;
      break;
    }
    maybe_frame();
    if (halted_after_pass_ > 0) {
      result.stopped_at_pass = halted_after_pass_;
      break;
    }
    const int64_t steps = StepsDone();
    // Every step (a clock read): a killed run loses at most flush_seconds of rows, however long
    // its steps take.
    if (out_) {
      try {
        out_->MaybeFlush();
      } catch (const std::exception& e) {
        Status("scoopsim: %s\n", OutputFailed(system.time(), e).message.c_str());
        result.exit_status = kExitFailure;
        break;
      }
    }
    if (steps % 64 == 0) {
      progress.Update(system.time() - t_start_, particle_steps_);
      if (control.checkpoint_every > 0 &&
          Seconds(std::chrono::steady_clock::now() - last_checkpoint) >= control.checkpoint_every) {
        if (!checkpoint()) {
          result.exit_status = kExitFailure;
          break;
        }
        last_checkpoint = std::chrono::steady_clock::now();
      }
      if (StopRequested()) {
        if (control.checkpoint_every > 0) checkpoint();  // go on from here, not the last one
        Status("scoopsim: stopped by signal %d at t = %.6g s; output closed\n", StopSignal(),
               system.time());
        result.exit_status = kExitStopped;
        break;
      }
    }
    if (control.stop_after > 0 && system.time() - t_start_ >= control.stop_after) {
      if (control.checkpoint_at_stop_after && control.checkpoint_every > 0 && !checkpoint())
        result.exit_status = kExitFailure;
      Status("scoopsim: stopped at t = %.6g s (--stop-after); output closed\n", system.time());
      result.stopped_after = true;
      break;
    }
  }
  control_ = nullptr;
  progress.Finish(system.time() - t_start_, particle_steps_, Done());
  result.wall = Seconds(std::chrono::steady_clock::now() - wall0);
  if (dig_) {
    summary_.mean_force = dig_->force_rows > 0 ? dig_->force_sum / dig_->force_rows : 0.0;
    summary_.steps = StepsDone();
    summary_.simulated = system.time() - t_start_;
    Status(
        "scoopsim: dig: %lld particles, %lld steps, %.4g s simulated (t = %.4f to %.4f s); "
        "peak |F| %.4g N, mean |F| %.4g N (after first contact), peak |T| %.4g N m; %lld "
        "neighbour builds, %.3g awake particle-steps per step\n",
        static_cast<long long>(summary_.particles), static_cast<long long>(summary_.steps),
        summary_.simulated, t_start_, system.time(), summary_.peak_force, summary_.mean_force,
        summary_.peak_torque, static_cast<long long>(system.neighbor_stats().builds),
        static_cast<double>(particle_steps_) / std::max<int64_t>(1, summary_.steps));
    // (Without a bed the DEM's phases took no time.)
    const std::string phases =
        dig_->own_step > 0
            ? std::string()
            : ": " + PhaseBreakdown(PhasesSince(system.phase_times(), phases0), result.wall);
    Status("scoopsim: dig: %.1f s wall (%.3g x real time)%s\n", result.wall,
           summary_.simulated / std::max(result.wall, 1e-9), phases.c_str());
    if (const dem::ThreadGovernor* g = system.governor(); g != nullptr && g->configured() > 1) {
      Status("scoopsim: threads: %d, fewer on %.1f%% of steps (%lld probes, %lld switches)\n",
             g->configured(), 100.0 * g->steps_fewer() / std::max<int64_t>(1, g->steps()),
             static_cast<long long>(g->probes()), static_cast<long long>(g->switches()));
    }
    try {
      dig_->driver->Finish(out_ != nullptr && !out_->failed() ? out_ : nullptr);
    } catch (const std::exception& e) {
      Status("scoopsim: output failed: %s\n", e.what());
      result.exit_status = kExitFailure;
    }
  }
  if (owned_out_) {
    // After a failed write the file keeps its last flush (the message said so): only close it.
    try {
      if (!owned_out_->failed()) {
        owned_out_->SetStateHash(system.StateHash());
        owned_out_->SetAttribute("time", system.time());
      }
      const bool failed = owned_out_->failed();
      owned_out_->Close();
      // The XDMF sidecar exists only with snapshots: a run names no file it did not write.
      if (!failed && owned_out_->snapshot_count() > 0) {
        Status("scoopsim: wrote %s (ParaView: %s)\n", owned_out_->path().c_str(),
               owned_out_->xdmf_path().c_str());
      } else if (!failed) {
        Status("scoopsim: wrote %s (no snapshots: output.snapshot_every is 0)\n",
               owned_out_->path().c_str());
      }
    } catch (const std::exception& e) {
      if (result.exit_status != kExitFailure) Status("scoopsim: output failed: %s\n", e.what());
      result.exit_status = kExitFailure;
    }
  }
  return result;
}

}  // namespace sim

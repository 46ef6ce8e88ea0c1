// The arm in the loop (sim/loop/arm_driver.cpp) on the scenes it ships with:
// scenes/arm/nominal_snow.yaml and scenes/fault/{boulder,weak_joint_ice}.yaml. Beds are poured once
// per bed and reused.
//   - the nominal snow dig raises no fault, and the arm tracks the path within 2 mm;
//   - the same path, driven by the arm and kinematically: the RMS difference of the DEM's force and
//     torque series (1 ms means) over the kinematic run's peak is within 1.5x the noise floor of
//     this coarse bed, measured as the same difference between the kinematic path and itself moved
//     0.5 mm along the trench (the arm's rms tracking error is ~0.6 mm, max 1.3 mm). The issue's
//     goal, 10% of the peak, is out of reach here: the nominal dig's wrench is 0.1-1 N, a handful
//     of 8 mm spheres, and the 0.5 mm shift alone moves it by ~26% (bench/results/vm/journal.md);
//   - determinism: the coupled dig ends in the same DEM state hash, and the same arm figures, on 1
//     and 2 threads and on a rerun (Bullet runs on one thread; the DEM is thread-count exact),
//     and that hash is pinned (kNominalArmHash);
//   - each fault scene raises JOINT_TORQUE_LIMIT on j_prox_pitch, one hold time (0.1 s, within one
//     Bullet step) after its demanded torque first reaches the effort limit: the boulder once the
//     blade is stopped by it (after ~0.55 s of push), the worn motor as the push starts (0.2 s);
//   - reaction retract: after the boulder's flag the scoop rises by the retract distance and the
//     pass ends one retract and one stop_hold later;
//   - the snapshots hold the scoop and the arm's links at the poses they had (the XDMF's meshes);
//   - a bad arm: block or URDF in a scene exits 2 with one line naming the scene, line and key.
#include "sim/loop/arm_driver.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ios>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "arm/arm_model.h"
#include "arm/kinematics.h"
#include "sim/files/arm_geometry.h"
#include "sim/files/bed_io.h"
#include "sim/files/h5_output.h"
#include "sim/files/saved_run.h"
#include "sim/input/scene.h"
#include "sim/loop/world.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;
constexpr uint64_t kJointTorqueLimit = 32;
constexpr int kProxPitch = 2;  // j_prox_pitch in the chain

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("arm_driver");
  return dir;
}

// Forwards to a driver and keeps the DEM's wrench of every step.
class Recorder : public sim::ScoopDriver {
 public:
  explicit Recorder(std::unique_ptr<sim::ScoopDriver> inner) : inner_(std::move(inner)) {}
  sim::PassStart BeginPass(int pass, const sim::BedContext& bed) override {
    return inner_->BeginPass(pass, bed);
  }
  dem::MeshMotion MotionAt(double tau) override { return inner_->MotionAt(tau); }
  void Feedback(double tau, const dem::MeshWrench& w) override {
    force.push_back(w.force);
    torque.push_back(w.torque);
    inner_->Feedback(tau, w);
  }
  bool PassOver(double tau) const override { return inner_->PassOver(tau); }
  double PlannedDuration(int pass, const sim::BedContext& bed) const override {
    return inner_->PlannedDuration(pass, bed);
  }
  void Record(sim::H5Output* out, double time) override { inner_->Record(out, time); }
  void Finish(sim::H5Output* out) override { inner_->Finish(out); }
  sim::ScoopDriver* inner() { return inner_.get(); }
  std::vector<dem::Vec3> force, torque;

 private:
  std::unique_ptr<sim::ScoopDriver> inner_;
};

sim::Scene Scene(const std::string& name) { return sim::LoadScene(kSourceDir + "/scenes/" + name); }

// The scene's bed, poured once (on 2 threads) and saved.
std::string Bed(const sim::Scene& scene, const std::string& name) {
  static std::map<std::string, std::string> beds;
  auto found = beds.find(name);
  if (found != beds.end()) return found->second;
  sim::World world(scene, 2);
  sim::SettleReport report;
  const int status = world.Pour(true, &report);
  EXPECT_TRUE(status == 0 || status == 4) << status;
  const std::string path = (TempDir() / (name + ".h5")).string();
  sim::SaveBed(path, world.system(), scene.yaml_text);
  return beds[name] = path;
}

struct DigRun {
  uint64_t hash = 0;
  int exit_status = -1;
  sim::ArmReport arm;
  std::vector<dem::Vec3> force, torque;
};

// With `output`, the run's rows go to that file.
DigRun Dig(const sim::Scene& scene, const std::string& bed, bool with_arm, int threads,
           const std::string& output = "") {
  sim::World world(scene, threads);
  world.LoadBed(bed);
  std::unique_ptr<sim::H5Output> out;
  if (!output.empty()) {
    out = std::make_unique<sim::H5Output>(output, scene.yaml_text, "test");
    world.UseOutput(out.get());
  }
  std::unique_ptr<sim::ScoopDriver> driver;
  if (with_arm) {
    driver = std::make_unique<sim::ArmDriver>(scene);
  } else {
    driver = sim::KinematicDriver::ForDig(scene.dig);
  }
  auto recorder = std::make_unique<Recorder>(std::move(driver));
  Recorder* rec = recorder.get();
  world.StartDig(std::move(recorder));
  sim::RunControl control;
  control.quiet = true;
  DigRun run;
  run.exit_status = world.Run(control).exit_status;
  run.hash = world.system().StateHash();
  if (with_arm) run.arm = static_cast<sim::ArmDriver*>(rec->inner())->report();
  run.force = rec->force;
  run.torque = rec->torque;
  if (out) out->Close();
  return run;
}

// A float64 dataset of a run file, row-major.
std::vector<double> DoubleRows(const std::string& path, const std::string& name) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  EXPECT_GE(d, 0) << name;
  const hid_t space = H5Dget_space(d);
  std::vector<double> rows(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
  if (!rows.empty()) H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows.data());
  H5Sclose(space);
  H5Dclose(d);
  H5Fclose(f);
  return rows;
}

// /arm/fault_bits (uint64 rows) of a run file.
std::vector<uint64_t> FaultBitRows(const std::string& path) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, "/arm/fault_bits", H5P_DEFAULT);
  const hid_t type = H5Dget_type(d);
  EXPECT_EQ(H5Tget_class(type), H5T_INTEGER);
  const hid_t space = H5Dget_space(d);
  std::vector<uint64_t> rows(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
  if (!rows.empty()) H5Dread(d, H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows.data());
  H5Sclose(space);
  H5Tclose(type);
  H5Dclose(d);
  H5Fclose(f);
  return rows;
}

// The (flag, joint_name) fields of /arm/fault_events, read by name from its records (and each
// record's time into *times when given).
std::vector<std::pair<uint64_t, std::string>> FaultEventRows(const std::string& path,
                                                             std::vector<double>* times = nullptr) {
  struct Row {
    double time;
    uint64_t flag;
    char joint_name[64];
  };
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, "/arm/fault_events", H5P_DEFAULT);
  EXPECT_GE(d, 0) << path << ": no /arm/fault_events";
  const hid_t text = H5Tcopy(H5T_C_S1);
  H5Tset_size(text, 64);
  const hid_t type = H5Tcreate(H5T_COMPOUND, sizeof(Row));
  H5Tinsert(type, "time", HOFFSET(Row, time), H5T_NATIVE_DOUBLE);
  H5Tinsert(type, "flag", HOFFSET(Row, flag), H5T_NATIVE_UINT64);
  H5Tinsert(type, "joint_name", HOFFSET(Row, joint_name), text);
  const hid_t space = H5Dget_space(d);
  std::vector<Row> rows(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
  if (!rows.empty()) H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows.data());
  std::vector<std::pair<uint64_t, std::string>> out;
  for (const Row& r : rows) {
    out.emplace_back(r.flag, r.joint_name);
    if (times != nullptr) times->push_back(r.time);
  }
  H5Sclose(space);
  H5Tclose(type);
  H5Tclose(text);
  H5Dclose(d);
  H5Fclose(f);
  return out;
}

std::string NominalOutput() { return (TempDir() / "nominal.h5").string(); }

// The nominal coupled dig on 1 thread, run once and shared by the tests below.
const DigRun& NominalArm() {
  static const DigRun run = [] {
    const sim::Scene scene = Scene("arm/nominal_snow.yaml");
    return Dig(scene, Bed(scene, "snow"), true, 1, NominalOutput());
  }();
  return run;
}

// RMS over windows of `window` steps of |mean(a) - mean(b)|, over the peak window |mean(b)|.
double WindowedRmsOverPeak(const std::vector<dem::Vec3>& a, const std::vector<dem::Vec3>& b,
                           size_t window) {
  const size_t n = std::min(a.size(), b.size());
  double sum2 = 0, peak = 0;
  int windows = 0;
  for (size_t s = 0; s + window <= n; s += window) {
    dem::Vec3 ma, mb;
    for (size_t i = s; i < s + window; ++i) {
      ma = ma + a[i];
      mb = mb + b[i];
    }
    ma = (1.0 / window) * ma;
    mb = (1.0 / window) * mb;
    sum2 += dem::Norm2(ma - mb);
    peak = std::max(peak, dem::Norm(mb));
    ++windows;
  }
  return peak > 0 ? std::sqrt(sum2 / windows) / peak : 0.0;
}

TEST(ArmDriverTest, NominalSnowDigRaisesNoFault) {
  const DigRun& run = NominalArm();
  ASSERT_EQ(run.exit_status, 0);
  EXPECT_EQ(run.arm.latched, 0u);
  EXPECT_TRUE(run.arm.events.empty());
  EXPECT_TRUE(FaultEventRows(NominalOutput()).empty());  // present, zero rows
  const std::vector<uint64_t> bits = FaultBitRows(NominalOutput());
  EXPECT_FALSE(bits.empty());
  EXPECT_EQ(std::count(bits.begin(), bits.end(), 0u), static_cast<std::ptrdiff_t>(bits.size()));
  EXPECT_EQ(run.arm.time_scale, 1.0);  // the scene's speeds are within the joints' limits
  EXPECT_LT(run.arm.tracking_max, 2e-3);
  for (size_t i = 0; i < run.arm.joints.size(); ++i)
    EXPECT_LT(run.arm.peak_demanded[i], run.arm.effort_limit[i]) << run.arm.joints[i];
  std::printf("nominal: tracking max %.3g mm, rms %.3g mm, angle max %.3g deg\n",
              1e3 * run.arm.tracking_max, 1e3 * run.arm.tracking_rms,
              run.arm.tracking_angle_max * 180 / M_PI);
}

TEST(ArmDriverTest, SamePathByArmAndKinematicallyGivesTheSameWrench) {
  const sim::Scene scene = Scene("arm/nominal_snow.yaml");
  const DigRun& arm = NominalArm();
  const DigRun kin = Dig(scene, Bed(scene, "snow"), false, 1);
  sim::Scene shifted_scene = scene;
  shifted_scene.dig.trajectory.pivot_start.x += 0.5e-3;
  const DigRun shifted = Dig(shifted_scene, Bed(scene, "snow"), false, 1);
  ASSERT_EQ(kin.exit_status, 0);
  ASSERT_EQ(arm.force.size(), kin.force.size());  // same duration, same step
  ASSERT_EQ(shifted.force.size(), kin.force.size());
  const size_t window = static_cast<size_t>(std::lround(1e-3 / scene.time_step));
  const double force = WindowedRmsOverPeak(arm.force, kin.force, window);
  const double torque = WindowedRmsOverPeak(arm.torque, kin.torque, window);
  const double force_floor = WindowedRmsOverPeak(shifted.force, kin.force, window);
  const double torque_floor = WindowedRmsOverPeak(shifted.torque, kin.torque, window);
  std::printf(
      "arm vs kinematic: force %.3g, torque %.3g of the peak; kinematic moved 0.5 mm vs "
      "kinematic: force %.3g, torque %.3g; tracking rms %.3g mm, max %.3g mm\n",
      force, torque, force_floor, torque_floor, 1e3 * arm.arm.tracking_rms,
      1e3 * arm.arm.tracking_max);
  EXPECT_LE(force, std::max(0.10, 1.5 * force_floor));
  EXPECT_LE(torque, std::max(0.10, 1.5 * torque_floor));
}

// The coupled nominal dig's DEM state hash at its end (issue 22's determinism golden, beside
// tiny_dig's in tests/sim/world_test.cpp): the arm's controller, Bullet's step and the DEM all
// feed it, so any change to one of them shows here. History (newest first):
//   348ed918456f9404  2026-12-06  the DEM gets the scoop at Bullet's state after the step to the
//                                 same time (FK(q)), no longer the one before it (FK(q - h qd),
//                                 up to 2.8e-6 m off): ArmDriver::MotionAt took its copy of the
//                                 Bullet state before stepping Bullet (DemGetsTheScoopAt...).
//   c6302114fbd9bf8c  2026-12-03  the same on every x86-64 host: built without FMA and AVX-512
//                                 and with scalar Eigen (top-level CMakeLists.txt). The old
//                                 value held on the AVX-512 host it was pinned on; an AVX2 host
//                                 gave 5587e1da0446ce33 (GCC 12 fused a multiply-add in the
//                                 inertias' principal axes). Now an SSE2-only build
//                                 (SCOOPSIM_NATIVE=OFF) and an AVX2 one give this value.
//   e4db6b4a2e5a0b45  2026-12-03  the arm's rates solved with M by CRBA and an active set, set
//                                 on the multibody and stepped by stepPositionsMultiDof, not
//                                 stepSimulation: the same physics, other rounding (the D term
//                                 stays explicit coupled; implicit gave 31d96a7d5166f9b3;
//                                 journal section 13).
//   ad8b0ebb06884d63  2026-12-03  pinned (with tiny_dig's 3480ffbd08eaa986).
constexpr uint64_t kNominalArmHash = 0x348ed918456f9404ull;

TEST(ArmDriverTest, CoupledDigIsDeterministicOnOneAndTwoThreadsAndRerun) {
  const sim::Scene scene = Scene("arm/nominal_snow.yaml");
  const DigRun& one = NominalArm();
  const DigRun two = Dig(scene, Bed(scene, "snow"), true, 2);
  const DigRun again = Dig(scene, Bed(scene, "snow"), true, 1);
  EXPECT_EQ(one.hash, two.hash);
  EXPECT_EQ(one.hash, again.hash);
  EXPECT_EQ(one.arm.peak_demanded, two.arm.peak_demanded);
  EXPECT_EQ(one.arm.peak_demanded, again.arm.peak_demanded);
  EXPECT_EQ(one.arm.tracking_rms, two.arm.tracking_rms);
  EXPECT_EQ(one.force.size(), again.force.size());
  EXPECT_EQ(one.hash, kNominalArmHash)
      << std::hex << one.hash << ": the coupled physics changed; if on purpose, update "
      << "kNominalArmHash and say why";
}

// The first event is JOINT_TORQUE_LIMIT on j_prox_pitch, one hold time after that joint's demand
// first reached its limit (the monitor's rule: within one sample, here one Bullet step).
void ExpectTorqueLimitOnProxPitch(const DigRun& run, const sim::Scene& scene, double earliest,
                                  double latest, double dig_start) {
  ASSERT_EQ(run.exit_status, 0);
  ASSERT_FALSE(run.arm.events.empty());
  const sim::ArmReport::Event& e = run.arm.events.front();
  EXPECT_EQ(e.flag, kJointTorqueLimit);
  EXPECT_EQ(e.joint, kProxPitch);
  EXPECT_DOUBLE_EQ(e.limit, run.arm.effort_limit[kProxPitch]);
  const double first = run.arm.first_saturation[kProxPitch] - dig_start;
  const double h = scene.arm.substeps * scene.time_step;
  EXPECT_GE(e.time - dig_start - first, scene.arm.hold_time - 1e-9);
  EXPECT_LE(e.time - dig_start - first, scene.arm.hold_time + h + 1e-9);
  EXPECT_GE(first, earliest);
  EXPECT_LE(first, latest);
  std::printf(
      "JOINT_TORQUE_LIMIT on %s: demand at the limit from %.4f s into the dig, event at "
      "%.4f s (|demanded| %.4g N m, limit %.4g N m)\n",
      run.arm.joints[e.joint].c_str(), first, e.time - dig_start, e.value, e.limit);
}

TEST(ArmDriverTest, BoulderRaisesJointTorqueLimit) {
  const sim::Scene scene = Scene("fault/boulder.yaml");
  const std::string bed = Bed(Scene("arm/nominal_snow.yaml"), "snow");  // the same bed
  sim::World probe(scene, 1);
  probe.LoadBed(bed);
  const double start = probe.system().time();
  const std::string output = (TempDir() / "boulder.h5").string();
  const DigRun run = Dig(scene, bed, true, 2, output);
  // The blade meets the sphere in the push; the demand reaches 73 N m ~0.69 s into it.
  ExpectTorqueLimitOnProxPitch(run, scene, 0.45, 0.9, start);
  EXPECT_GT(run.arm.peak_demanded[kProxPitch], run.arm.effort_limit[kProxPitch]);
  // The rows show the fault (issue 40): the stop reaction drops the demand within the event's
  // row, so only the OR over the row's interval holds bit 32; the event names its joint.
  const std::vector<uint64_t> bits = FaultBitRows(output);
  EXPECT_TRUE(std::any_of(bits.begin(), bits.end(),
                          [](uint64_t b) { return (b & kJointTorqueLimit) != 0; }));
  const auto events = FaultEventRows(output);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front(), std::make_pair(kJointTorqueLimit, std::string("j_prox_pitch")));
  // The run's summary attributes hold the bits and the count as integers (uint64), not floats.
  const hid_t f = H5Fopen(output.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  for (const char* name : {"arm_fault_latched", "arm_fault_events"}) {
    const hid_t a = H5Aopen(f, name, H5P_DEFAULT);
    ASSERT_GE(a, 0) << name;
    const hid_t type = H5Aget_type(a);
    EXPECT_EQ(H5Tget_class(type), H5T_INTEGER) << name;
    uint64_t value = 0;
    H5Aread(a, H5T_NATIVE_UINT64, &value);
    EXPECT_EQ(value, std::string(name) == "arm_fault_latched" ? kJointTorqueLimit : events.size());
    H5Tclose(type);
    H5Aclose(a);
  }
  H5Fclose(f);
}

TEST(ArmDriverTest, WornMotorDiggingIceRaisesJointTorqueLimit) {
  const sim::Scene scene = Scene("fault/weak_joint_ice.yaml");
  const std::string bed = Bed(scene, "ice");
  sim::World probe(scene, 1);
  probe.LoadBed(bed);
  const double start = probe.system().time();
  const std::string output = (TempDir() / "weak_joint.h5").string();
  const DigRun run = Dig(scene, bed, true, 2, output);
  // Holding still (0-0.2 s) is within the derated limit; the push starts at 0.2 s.
  ExpectTorqueLimitOnProxPitch(run, scene, 0.2, 0.21, start);
  EXPECT_NEAR(run.arm.effort_limit[kProxPitch], 0.16 * 73.0, 1e-9);
  // The URDF's limit is kept (73 N m in the scene's model and in /arm/effort_limit), the derate
  // beside it (/arm/effort_derate); their product, bit for bit, is the limit the event was raised
  // against and the one readers (sim::SavedRun: render's torque bars) get.
  constexpr int kJoints = 6;
  EXPECT_EQ(scene.arm.model->joints[kProxPitch].effort, 73.0);
  EXPECT_EQ(scene.arm.derate[kProxPitch], 0.16);
  const std::vector<double> limit = DoubleRows(output, "/arm/effort_limit");
  const std::vector<double> derate = DoubleRows(output, "/arm/effort_derate");
  ASSERT_EQ(limit.size(), derate.size());
  ASSERT_GE(limit.size(), static_cast<size_t>(kJoints));
  for (size_t k = 0; k < limit.size(); ++k) {
    const int j = static_cast<int>(k % kJoints);
    EXPECT_EQ(limit[k], scene.arm.model->joints[j].effort) << k;
    EXPECT_EQ(derate[k], j == kProxPitch ? 0.16 : 1.0) << k;
  }
  ASSERT_FALSE(run.arm.events.empty());
  EXPECT_EQ(73.0 * 0.16, run.arm.events.front().limit);
  EXPECT_EQ(73.0 * 0.16, run.arm.effort_limit[kProxPitch]);
  const sim::ArmSeries saved = sim::SavedRun(output).Arm();
  ASSERT_EQ(saved.effort_limit.size(), limit.size());
  EXPECT_EQ(saved.effort_limit[kProxPitch], 73.0 * 0.16);
  EXPECT_EQ(saved.effort_limit[kProxPitch - 1], scene.arm.model->joints[kProxPitch - 1].effort);
}

// Reaction retract: the boulder scene with arm.faults.reaction retract (up 5 cm at 2 cm/s, then a
// 0.25 s hold). Once JOINT_TORQUE_LIMIT is raised (the path's lift comes only after the whole
// push, 1.4 s in, so the scoop is still at its pushing depth then), the scoop's origin rises
// by the retract distance, within 20% (the PID tracks the 2.5 s retract path with a lag and the
// bed and boulder load the scoop), moves less than 1 cm horizontally, and the pass ends one
// retract (2.5 s) and one stop_hold after the flag, within one DEM step.
TEST(ArmDriverTest, BoulderWithRetractLiftsTheScoop) {
  sim::Scene scene = Scene("fault/boulder.yaml");
  scene.arm.reaction = sim::ArmReaction::kRetract;
  const std::string bed = Bed(Scene("arm/nominal_snow.yaml"), "snow");
  sim::World world(scene, 2);
  world.LoadBed(bed);
  auto driver = std::make_unique<sim::ArmDriver>(scene);
  const sim::ArmDriver* arm = driver.get();
  world.StartDig(std::move(driver));
  ASSERT_EQ(world.system().mesh(0).triangles.size(), scene.dig.scoop.geometry.triangles.size());
  std::vector<double> time;
  std::vector<dem::Vec3> origin;  // the scoop's (l_scoop's) origin after each step
  while (!world.Done()) {
    ASSERT_TRUE(world.Step().ok());
    time.push_back(world.system().time());
    origin.push_back(world.system().mesh_motion(0).pose.position);
  }
  const sim::ArmReport& report = arm->report();
  ASSERT_FALSE(report.events.empty());
  const double flag = report.events.front().time;
  EXPECT_EQ(report.events.front().flag, kJointTorqueLimit);
  const size_t at = std::lower_bound(time.begin(), time.end(), flag) - time.begin();
  ASSERT_LT(at, time.size());
  const dem::Vec3 rise = origin.back() - origin[at];
  const double length = scene.arm.retract_distance / scene.arm.retract_speed;
  std::printf(
      "retract: flag at %.4f s; the scoop rose %.2f mm and moved %.2f mm sideways by the "
      "pass's end %.4f s later\n",
      flag, 1e3 * rise.z, 1e3 * std::hypot(rise.x, rise.y), time.back() - flag);
  EXPECT_NEAR(rise.z, scene.arm.retract_distance, 0.2 * scene.arm.retract_distance);
  EXPECT_LT(std::hypot(rise.x, rise.y), 0.01);
  EXPECT_NEAR(time.back() - flag, length + scene.arm.stop_hold,
              scene.arm.substeps * scene.time_step + scene.time_step);
}

// Bullet first (the default timing): the DEM's step to tau gets the scoop where Bullet's step to
// tau left it. The pose MotionAt hands the DEM is l_scoop by forward kinematics (arm::LinkPose,
// a computation apart from Bullet's) at Bullet's joint positions after that call, to 1e-12 m in
// position and 1e-12 in the quaternion (found ~1e-15), over the nominal dig's first 3000 steps
// (0.11 s, the scoop accelerating to 0.05 m/s). The pose one Bullet step back, FK(q - h qd),
// must be more than 1e-7 m off (a step at ~0.05 m/s is ~2e-6 m): the check tells a pose one
// step old (the defect fixed on 2026-12-06) from the right one.
TEST(ArmDriverTest, DemGetsTheScoopAtBulletsCurrentJointPositions) {
  const sim::Scene scene = Scene("arm/nominal_snow.yaml");
  ASSERT_EQ(scene.arm.timing, sim::CouplingTiming::kBulletFirst);
  const arm::ArmModel model = arm::LoadArmModel(scene.arm.urdf);
  sim::World world(scene, 1);
  world.LoadBed(Bed(scene, "snow"));
  class Checker : public Recorder {
   public:
    Checker(std::unique_ptr<sim::ArmDriver> arm, const arm::ArmModel& model, double h)
        : Recorder(std::move(arm)), model_(model), h_(h) {}
    dem::MeshMotion MotionAt(double tau) override {
      const dem::MeshMotion m = Recorder::MotionAt(tau);
      const auto* arm = static_cast<const sim::ArmDriver*>(inner());
      const sim::ArmDriver::JointState s = arm->joint_state();
      const std::vector<double>& b = arm->report().base;
      Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
      base.linear() = Eigen::AngleAxisd(b[3], Eigen::Vector3d::UnitZ()).toRotationMatrix();
      base.translation() = Eigen::Vector3d(b[0], b[1], b[2]);
      const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(s.q.data(), s.q.size());
      const Eigen::VectorXd qd = Eigen::Map<const Eigen::VectorXd>(s.qd.data(), s.qd.size());
      now = std::max(now, Off(arm::LinkPose(model_, q, "l_scoop", base), m.pose));
      back = std::max(back, Off(arm::LinkPose(model_, q - h_ * qd, "l_scoop", base), m.pose));
      return m;
    }
    double now = 0, back = 0;

   private:
    static double Off(const Eigen::Isometry3d& fk, const dem::Pose& p) {
      const Eigen::Quaterniond q(fk.linear());
      const double dq = std::min(
          std::max({std::abs(q.w() - p.orientation.w), std::abs(q.x() - p.orientation.x),
                    std::abs(q.y() - p.orientation.y), std::abs(q.z() - p.orientation.z)}),
          std::max({std::abs(q.w() + p.orientation.w), std::abs(q.x() + p.orientation.x),
                    std::abs(q.y() + p.orientation.y), std::abs(q.z() + p.orientation.z)}));
      const Eigen::Vector3d t = fk.translation();
      return std::max({dq, std::abs(t.x() - p.position.x), std::abs(t.y() - p.position.y),
                       std::abs(t.z() - p.position.z)});
    }
    const arm::ArmModel& model_;
    double h_;
  };
  auto checker = std::make_unique<Checker>(std::make_unique<sim::ArmDriver>(scene, false), model,
                                           scene.arm.substeps * scene.time_step);
  Checker* c = checker.get();
  world.StartDig(std::move(checker));
  for (int i = 0; i < 3000; ++i) ASSERT_TRUE(world.Step().ok());
  std::printf("DEM's scoop pose vs FK(q): %.3g; vs FK(q - h qd): %.3g\n", c->now, c->back);
  EXPECT_LT(c->now, 1e-12);
  EXPECT_GT(c->back, 1e-7);
}

// A frame at the dig's start draws the torques holding the arm up (the PID's preloaded integral,
// arm::GravityTorques), not empty bars: the view's demanded torques before the first step are,
// for every joint, those of the first step within 2% of the joint's limit, and j_prox_pitch's is
// a visible share of its limit (> 5%; ~5.5 N m of 73 in the nominal pose).
TEST(ArmDriverTest, TorqueBarsAtTheDigsStartShowTheHoldingTorques) {
  const sim::Scene scene = Scene("arm/nominal_snow.yaml");
  sim::World world(scene, 1);
  world.LoadBed(Bed(scene, "snow"));
  auto driver = std::make_unique<sim::ArmDriver>(scene);
  const sim::ArmDriver* arm = driver.get();
  world.StartDig(std::move(driver));
  auto joints = [arm] {
    sim::WorldView view;  // what World::View() hands a frame
    arm->AddToView(&view);
    return view.joints;
  };
  const std::vector<sim::JointView> first = joints();
  ASSERT_TRUE(world.Step().ok());
  const std::vector<sim::JointView> stepped = joints();
  ASSERT_EQ(first.size(), 6u);
  ASSERT_EQ(stepped.size(), 6u);
  for (size_t j = 0; j < first.size(); ++j)
    EXPECT_NEAR(first[j].torque, stepped[j].torque, 0.02 * first[j].limit) << first[j].name;
  EXPECT_GT(std::abs(first[kProxPitch].torque), 0.05 * first[kProxPitch].limit);
  std::printf("frame 0: j_prox_pitch %.4g N m of %.4g (%.1f%%)\n", first[kProxPitch].torque,
              first[kProxPitch].limit,
              100 * std::abs(first[kProxPitch].torque) / first[kProxPitch].limit);
}

// The snapshots of a coupled dig hold the scoop and the arm's links where they were. The nominal
// dig, stepped 0.3 s with a snapshot at its start and every 2000 steps: at each snapshot the test
// records the
// scoop's DEM pose and Bullet's joint positions. In the file (read back through sim::SavedRun),
// the scoop's points are the scene's scoop mesh moved by that pose, and the arm's points are
// sim::ArmGeometry's link meshes at the poses forward kinematics gives for those joint positions
// (exactly: the same double arithmetic), each with its own triangles after the previous parts'
// vertices.
TEST(ArmDriverTest, SnapshotsHoldTheScoopAndTheLinksWhereTheyWere) {
  sim::Scene scene = Scene("arm/nominal_snow.yaml");
  scene.output.snapshot_every = 2000;
  const std::string path = (TempDir() / "snapshots.h5").string();
  std::vector<dem::Pose> scoop;
  std::vector<std::vector<double>> q;
  sim::ArmBase base;
  {
    sim::World world(scene, 1);
    world.LoadBed(Bed(scene, "snow"));
    world.OpenOutput(path);
    auto driver = std::make_unique<sim::ArmDriver>(scene);
    const sim::ArmDriver* arm = driver.get();
    world.StartDig(std::move(driver));
    const double start = world.system().time();
    // The first snapshot, at the dig's start: the scoop placed, the arm at its first pose.
    int64_t snapshots = world.output()->snapshot_count();
    ASSERT_EQ(snapshots, 1);
    scoop.push_back(world.system().mesh_motion(0).pose);
    q.push_back(arm->JointPositions());
    while (world.system().time() - start < 0.3) {
      ASSERT_TRUE(world.Step().ok());
      if (world.output()->snapshot_count() == snapshots) continue;
      snapshots = world.output()->snapshot_count();
      scoop.push_back(world.system().mesh_motion(0).pose);
      q.push_back(arm->JointPositions());
    }
    const std::vector<double>& b = arm->report().base;
    base = {{b[0], b[1], b[2]}, b[3]};
    world.output()->Close();
  }
  ASSERT_GE(scoop.size(), 3u);
  const sim::ArmGeometry geometry(scene.arm.model);
  const sim::SavedRun run(path);
  const std::vector<sim::SnapshotInfo> infos = run.Snapshots();
  ASSERT_EQ(infos.size(), scoop.size());
  const dem::TriangleMesh& tool = scene.dig.scoop.geometry;
  for (size_t k = 0; k < infos.size(); ++k) {
    const std::vector<sim::SnapshotMesh> meshes = run.ReadSnapshotMeshes(infos[k]);
    ASSERT_EQ(meshes.size(), 2u);  // sorted by name
    ASSERT_EQ(meshes[0].name, "arm");
    ASSERT_EQ(meshes[1].name, "scoop");
    const dem::TriangleMesh& s = meshes[1].mesh;
    ASSERT_EQ(s.vertices.size(), tool.vertices.size());
    ASSERT_EQ(s.triangles, tool.triangles);
    for (size_t v = 0; v < s.vertices.size(); ++v) {
      const dem::Vec3 want = dem::Apply(scoop[k], tool.vertices[v]);
      EXPECT_EQ(s.vertices[v].x, want.x);
      EXPECT_EQ(s.vertices[v].y, want.y);
      EXPECT_EQ(s.vertices[v].z, want.z);
    }
    const std::vector<dem::Pose> poses = geometry.Poses(q[k].data(), base);
    const dem::TriangleMesh& a = meshes[0].mesh;
    size_t v0 = 0, t0 = 0;
    for (int part = 0; part < geometry.parts(); ++part) {
      const dem::TriangleMesh& link = geometry.mesh(part);
      for (size_t v = 0; v < link.vertices.size(); ++v) {
        const dem::Vec3 want = dem::Apply(poses[part], link.vertices[v]);
        ASSERT_LT(v0 + v, a.vertices.size());
        EXPECT_EQ(a.vertices[v0 + v].x, want.x);
        EXPECT_EQ(a.vertices[v0 + v].y, want.y);
        EXPECT_EQ(a.vertices[v0 + v].z, want.z);
      }
      for (size_t t = 0; t < link.triangles.size(); ++t)
        for (int c = 0; c < 3; ++c)
          EXPECT_EQ(a.triangles[t0 + t][c], static_cast<int32_t>(v0) + link.triangles[t][c]);
      v0 += link.vertices.size();
      t0 += link.triangles.size();
    }
    EXPECT_EQ(v0, a.vertices.size());
    EXPECT_EQ(t0, a.triangles.size());
  }
}

// The first number after `prefix` in `text` (NaN when absent).
double NumberAfter(const std::string& text, const std::string& prefix) {
  const size_t at = text.find(prefix);
  return at == std::string::npos ? std::nan("")
                                 : std::strtod(text.c_str() + at + prefix.size(), nullptr);
}

// One clock (README "One clock"): every time a run prints is the time its datasets hold. The
// nominal scene from its saved bed with j_prox_pitch derated to 5% (below its gravity torque, ~4 N
// m, so the flag rises one hold time in) and a snapshot every 1000 steps, stopped 0.15 s into the
// dig, on the command line (`--set`). Compared, to the digits printed (4 decimals: 5e-5 s; 6
// significant: 1e-6 s): the dig's start on stderr and the root attribute start_time, the first
// /arm/ and /scoop/ rows (within one row, dig.interval) and the first snapshot (exactly); the
// fault's time on stderr and /arm/fault_events, and the first /arm/ row with the flag latched
// (within one row after it); the stop on stderr, the dig's end and the progress line's last time,
// and the last /arm/ and /scoop/ rows and snapshot (within one row before it).
TEST(ArmDriverTest, StderrAndDatasetsShareOneClock) {
  const std::string scene_path = kSourceDir + "/scenes/arm/nominal_snow.yaml";
  const std::string bed = Bed(Scene("arm/nominal_snow.yaml"), "snow");
  const std::string out = (TempDir() / "clock.h5").string();
  const std::string err = (TempDir() / "clock.txt").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim(
                "run " + scene_path + " -o " + out + " --stop-after 0.15 --threads 1 --set " +
                    "bed.file=" + bed + " --set arm.derate.j_prox_pitch=0.05 --set " +
                    "output.snapshot_every=1000",
                err),
            0);
  const std::string text = scoopsim_test::ReadText(err);
  const double dig_start = NumberAfter(text, "s simulated (t = ");
  const double dig_end = NumberAfter(text.substr(text.find("s simulated (t = ")), " to ");
  const double fault = NumberAfter(text, "fault JOINT_TORQUE_LIMIT at t = ");
  const double stop = NumberAfter(text, "stopped at t = ");
  // The progress line's last "t NOW/END s" (the line that reads 100% or where it stopped).
  const size_t last_progress = text.rfind("dig ");
  ASSERT_NE(last_progress, std::string::npos) << text;
  const double progress = NumberAfter(text.substr(last_progress), "  t ");
  ASSERT_TRUE(std::isfinite(dig_start) && std::isfinite(dig_end) && std::isfinite(fault) &&
              std::isfinite(stop) && std::isfinite(progress))
      << text;

  const sim::SavedRun run(out);
  const sim::Scene scene = Scene("arm/nominal_snow.yaml");
  const double row = scene.dig.interval, printed4 = 5e-5, printed6 = 1e-6 * stop;
  const double start_time = run.RootNumber("start_time", std::nan(""));
  EXPECT_NEAR(dig_start, start_time, printed4);
  EXPECT_NEAR(dig_end, stop, printed4);
  EXPECT_NEAR(progress, stop, printed4);
  EXPECT_GT(stop, start_time + 0.15 - printed6);

  const sim::ArmSeries arm = run.Arm();
  const sim::ScoopSeries scoop = run.Scoop();
  ASSERT_FALSE(arm.empty());
  ASSERT_FALSE(scoop.time.empty());
  for (const std::vector<double>* t : {&arm.time, &scoop.time}) {
    EXPECT_GE(t->front(), start_time);
    EXPECT_LE(t->front(), start_time + row);
    EXPECT_LE(t->back(), stop + printed6);
    EXPECT_GE(t->back(), stop - row - printed6);
  }
  const std::vector<sim::SnapshotInfo> snapshots = run.Snapshots();
  ASSERT_GE(snapshots.size(), 2u);
  EXPECT_EQ(snapshots.front().time, start_time);
  EXPECT_LE(snapshots.back().time, stop + printed6);

  std::vector<double> events;
  FaultEventRows(out, &events);
  ASSERT_FALSE(events.empty());
  EXPECT_NEAR(events.front(), fault, printed4);
  size_t latched = 0;
  while (latched < arm.time.size() && (arm.fault_latched[latched] & kJointTorqueLimit) == 0)
    ++latched;
  ASSERT_LT(latched, arm.time.size());
  EXPECT_GE(arm.time[latched], fault - printed4);
  EXPECT_LE(arm.time[latched], fault + row + printed4);
  EXPECT_GT(fault, start_time + scene.arm.hold_time - printed4);  // one clock, not the dig's
  std::printf(
      "one clock: dig from t = %.4f s (start_time %.6f s); fault at t = %.4f s (stderr), %.6f s "
      "(/arm/fault_events), first latched row %.6f s; stop at t = %.6g s, last /arm/ row %.6f s\n",
      dig_start, start_time, fault, events.front(), arm.time[latched], stop, arm.time.back());
}

// A scene with the nominal scene's keys and `arm` as its arm: block.
std::string WriteArmScene(const std::string& name, const std::string& arm) {
  std::ifstream in(kSourceDir + "/scenes/arm/nominal_snow.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("arm:\n");
  const size_t end = text.find("sleep:", at);
  // The default URDF is named relative to the scene's folder: name it absolutely unless the
  // block names its own.
  const std::string block = arm.find("urdf:") != std::string::npos
                                ? arm
                                : "arm:\n  urdf: " + kSourceDir + "/assets/lander_arm.urdf\n" +
                                      arm.substr(std::string("arm:\n").size());
  text = text.substr(0, at) + block + text.substr(end);
  const std::string base = kSourceDir + "/scenes/arm/";
  for (const char* rel : {"../materials.yaml", "../../assets/scoop.stl"}) {
    const size_t p = text.find(rel);
    text.replace(p, std::string(rel).size(), base + rel);
  }
  const fs::path path = TempDir() / name;
  std::ofstream(path) << text;
  return path.string();
}

// Exit 2 and one line that names `expected` (the scene file, its line, the key).
void ExpectBadScene(const std::string& scene, const std::string& expected) {
  const std::string err = (TempDir() / "err.txt").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim(
                "run " + scene + " -o " + (TempDir() / "x.h5").string() + " --quiet", err),
            2);
  std::ifstream in(err);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find(expected), std::string::npos) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
}

TEST(ArmDriverTest, BadArmBlockExitsTwoWithOneLine) {
  const fs::path not_xml = TempDir() / "not_xml.urdf";
  std::ofstream(not_xml) << "this is not a robot\n";
  const std::string a = WriteArmScene("bad_urdf.yaml", "arm:\n  urdf: " + not_xml.string() + "\n");
  ExpectBadScene(a, "bad_urdf.yaml:");
  ExpectBadScene(a, "arm.urdf: expected a URDF the arm builder accepts");
  const std::string b = WriteArmScene("missing_urdf.yaml", "arm:\n  urdf: nowhere.urdf\n");
  ExpectBadScene(b, "arm.urdf");
  const std::string c = WriteArmScene("bad_joint.yaml", "arm:\n  derate: {j_elbow: 0.5}\n");
  ExpectBadScene(c, "arm.derate: expected a joint of the chain");
  const std::string d = WriteArmScene("bad_factor.yaml", "arm:\n  derate: {j_prox_pitch: 1.5}\n");
  ExpectBadScene(d, "arm.derate.j_prox_pitch: expected a number in (0, 1]");
  const std::string e = WriteArmScene("bad_substeps.yaml", "arm:\n  substeps: 50\n");
  ExpectBadScene(e, "arm.substeps: expected an integer <= 2");
  const std::string f = WriteArmScene("bad_key.yaml", "arm:\n  gain: {}\n");
  ExpectBadScene(f, "arm.gain: expected one of the keys");
  const std::string g = WriteArmScene("bad_reaction.yaml", "arm:\n  faults: {reaction: panic}\n");
  ExpectBadScene(g, "arm.faults.reaction: expected continue, stop or retract, got panic");
  const std::string h = WriteArmScene("bad_d_term.yaml", "arm:\n  d_term: halfway\n");
  ExpectBadScene(h, "arm.d_term: expected implicit or explicit, got halfway");
  const std::string i = WriteArmScene("bad_step.yaml", "arm:\n  step: 2.5e-3\n");
  ExpectBadScene(i, "arm.step: expected a step only with arm.wrench: table");
  // Defect: a dig path 100 m out of the arm's reach passed `check` and ran to exit 0 with no
  // wrench ("no fault"). More than 50 mm out of reach is refused by the preflight, before the bed.
  const std::string j =
      WriteArmScene("far_base.yaml", "arm:\n  base: {reach: [100, 0.175], height: 0.172}\n");
  ExpectBadScene(j, "far_base.yaml: arm.base: expected the dig's path within the arm's reach");
}

}  // namespace

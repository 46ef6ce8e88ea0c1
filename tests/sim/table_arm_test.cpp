// The table-driven arm (sim/loop/table_arm.cpp): the lander's arm in Bullet, its scoop wrench from
// a synthetic wrench table (written by the test as case files, built with sim::BuildWrenchTable),
// no DEM, run by `scoopsim run` (sim::RunScene: World's loop with sim::TableArmDriver). The
// scene: the arm of scenes/arm/nominal_snow.yaml, the scoop started buried (first contact at
// once).
//   - steady joint torques: holding still under a constant table wrench W, the demanded torques
//     differ from those under a zero table by -J^T W (arm::PointJacobian at the CoM, world axes,
//     at the held pose), within 0.5% of max |J^T W| (what is left of the settling); on the
//     lander's URDF with its joint friction set to 0 (a joint held by Coulomb friction takes up
//     any change below its friction, 0.3-4.6 N m, so its demanded torque need not change);
//   - rho: on a 0.05 m push the wrench applied is the table's at the running maximum of the CoM's
//     travel along the trench since first contact (the CoM from /scoop/pose and the scoop_com
//     attributes; the maximum over every step lies within 1 um above the one over the rows; a
//     wrench linear in rho: to k x 1 um + 1e-9), the run's /scoop/rho is the CoM's displacement
//     along the trench since first contact (as in a coupled dig, to 1e-12 m) and ends within 2 mm
//     of 0.05 m;
//   - the layout: the /scoop/ datasets of a coupled dig (pose, force_body, contacts all 0: no
//     particles), no /scoop/com;
//   - a table wrench past a joint's capacity raises JOINT_TORQUE_LIMIT on the joint that the
//     Jacobian says needs the largest share of its effort (the others stay under 90% of theirs);
//   - out of the domain: a bite depth outside the table's, a material or a pass it does not hold,
//     a missing table file and a scene without dig.surface are refused before the run (one line
//     naming the file and the key, exit 2 from the CLI); rho
//     past the table's data holds the last value (the run reports the steps it held);
//   - determinism: the same rows on 1 and 2 threads (the run is single-threaded: Bullet only).
#include "sim/loop/table_arm.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "arm/kinematics.h"
#include "dem/transform.h"
#include "sim/files/h5_output.h"
#include "sim/files/saved_run.h"
#include "sim/files/wrench_table.h"
#include "sim/input/scene.h"
#include "sim/studies/commands.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;
constexpr uint64_t kJointTorqueLimit = 32;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("table_arm");
  return dir;
}

// A table of one case (snow, bite depth 20 mm, one pass) whose l_scoop wrench is w0 + k rho at
// every rho in 0..rows x 2.5 mm (rows every 2.5 mm after two rows without contact); the
// body-frame datasets hold the same numbers (unused here). Returns TABLE.h5.
std::string WriteTable(const std::string& name, const std::array<double, 6>& w0,
                       const std::array<double, 6>& k = {}, int rows = 80) {
  const fs::path dir = TempDir() / name;
  fs::create_directories(dir / "cases");
  {
    const std::string scene =
        "materials: materials.yaml\nbed: {material: snow, radius: 0.008, count: 10}\n"
        "dig: {bite_depth: 0.02, passes: 1}\n";
    sim::H5Output out((dir / "cases" / "snow_b20.h5").string(), scene, "test");
    double t = 0;
    for (int i = -2; i <= rows; ++i) {
      const double p = 1, rho = std::max(0, i) * 2.5e-3, contacts = i < 0 ? 0 : 3;
      double v[6];
      for (int q = 0; q < 6; ++q) v[q] = w0[q] + k[q] * rho;
      out.AppendRow("/scoop/time", &t, 1);
      out.AppendRow("/scoop/pass", &p, 1);
      out.AppendRow("/scoop/rho", &rho, 1);
      out.AppendRow("/scoop/contacts", &contacts, 1);
      out.AppendRow("/scoop/force_scoop", v, 3);
      out.AppendRow("/scoop/torque_scoop", v + 3, 3);
      out.AppendRow("/scoop/force_body", v, 3);
      out.AppendRow("/scoop/torque_body", v + 3, 3);
      t += 1e-3;
    }
    out.Close();
  }
  const std::string table = (dir / "table.h5").string();
  // The table of along-trench rho these tests check TableWrench's rho against (1 mm grid).
  sim::WrenchTableOptions options;
  options.rho_step_mm = 1;
  options.rho = sim::RhoDefinition::kAlong;
  sim::BuildWrenchTable(dir.string(), table, options);
  return table;
}

// The arm of nominal_snow.yaml on a table: `moves` the path, a 20 mm bite started buried.
std::string SceneText(const std::string& table, const std::string& moves,
                      const std::string& material = "snow", double bite = 0.02, int passes = 1,
                      const std::string& urdf = kSourceDir + "/assets/lander_arm.urdf") {
  std::ostringstream s;
  s << "materials: " << kSourceDir << "/scenes/materials.yaml\n"
    << "gravity: [0, 0, -1.3]\n"
    << "time_step: {rayleigh_fraction: 0.25}\n"
    << "box: {min: [0, 0, 0], max: [0.32, 0.19, 0.15], wall_material: wall}\n"
    << "bed: {material: " << material << ", radius: 8.0e-3, count: 1250, seed: 5}\n"
    << "dig:\n"
    << "  scoop: {mesh: " << kSourceDir << "/assets/scoop.stl, material: aluminium}\n"
    << "  trajectory: {preset: none, start: [0.11, 0.095], initial_pitch: 0, moves: " << moves
    << "}\n"
    << "  start_buried: true\n"
    << "  passes: " << passes << "\n"
    << "  bite_depth: " << bite << "\n"
    << "  surface: 0.08\n"
    << "  interval: 1.0e-3\n"
    << "arm: {urdf: " << urdf << ", substeps: 1, wrench: table, "
    << "table: " << table << ", faults: {hold_time: 0.1, reaction: continue}}\n";
  return s.str();
}

std::string WriteScene(const std::string& name, const std::string& text) {
  const std::string path = (TempDir() / (name + ".yaml")).string();
  std::ofstream(path) << text;
  return path;
}

// A dataset of an output file, row-major, and its width.
std::vector<double> ReadRows(const std::string& path, const std::string& name, int* width) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0) << path;
  const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  EXPECT_GE(d, 0) << name;
  const hid_t space = H5Dget_space(d);
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
  *width = rank == 2 ? static_cast<int>(dims[1]) : 1;
  std::vector<double> v(dims[0] * *width);
  if (!v.empty()) H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Sclose(space);
  H5Dclose(d);
  H5Fclose(f);
  return v;
}

double RootAttribute(const std::string& path, const std::string& name) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t a = H5Aopen(f, name.c_str(), H5P_DEFAULT);
  double v = NAN;
  H5Aread(a, H5T_NATIVE_DOUBLE, &v);
  H5Aclose(a);
  H5Fclose(f);
  return v;
}

struct TableRun {
  sim::Scene scene;
  std::string output;
  int exit_status = 0;
};

TableRun RunTable(const std::string& name, const std::string& scene_text, int threads = 1) {
  TableRun r{
      sim::LoadScene(WriteScene(name, scene_text)), (TempDir() / (name + ".h5")).string(), {}};
  sim::RunOptions options;
  options.output = r.output;
  options.quiet = true;
  options.threads = threads;
  r.exit_status = sim::RunScene(r.scene, options);
  return r;
}

// Mean of the last `rows` rows of a (n x width) dataset.
Eigen::VectorXd TailMean(const std::string& path, const std::string& name, int rows) {
  int w = 0;
  const std::vector<double> v = ReadRows(path, name, &w);
  const int n = static_cast<int>(v.size()) / w;
  Eigen::VectorXd m = Eigen::VectorXd::Zero(w);
  for (int r = n - rows; r < n; ++r)
    for (int c = 0; c < w; ++c) m[c] += v[r * w + c] / rows;
  return m;
}

Eigen::Isometry3d Base(const std::string& path) {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.linear() =
      Eigen::AngleAxisd(RootAttribute(path, "arm_base_yaw"), Eigen::Vector3d::UnitZ()).matrix();
  base.translation() =
      Eigen::Vector3d(RootAttribute(path, "arm_base_x"), RootAttribute(path, "arm_base_y"),
                      RootAttribute(path, "arm_base_z"));
  return base;
}

// J^T W at q for a wrench given in l_scoop axes about the scoop's CoM (the table's frame).
Eigen::VectorXd JtW(const sim::Scene& scene, const Eigen::VectorXd& q,
                    const Eigen::Isometry3d& base, const std::array<double, 6>& w) {
  const arm::ArmModel& model = *scene.arm.model;
  const Eigen::Isometry3d scoop = arm::LinkPose(model, q, model.tip_link, base);
  const dem::Vec3& c = scene.dig.scoop.com;
  const Eigen::Vector3d com = scoop * Eigen::Vector3d(c.x, c.y, c.z);
  Eigen::Matrix<double, 6, 1> wv;
  wv.head<3>() = scoop.linear() * Eigen::Vector3d(w[0], w[1], w[2]);
  wv.tail<3>() = scoop.linear() * Eigen::Vector3d(w[3], w[4], w[5]);
  return arm::PointJacobian(model, q, model.dof(), com, base).transpose() * wv;
}

// Long enough to settle: j_scoop_yaw creeps with time constant damping / P = 50 / 100 = 0.5 s.
const std::string kHold = "[{hold: 3.0}]";

// The lander's URDF with every joint's Coulomb friction 0 (beside a copy of its mesh).
std::string FrictionlessUrdf() {
  static const std::string path = [] {
    std::ifstream in(kSourceDir + "/assets/lander_arm.urdf");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const fs::path dir = TempDir() / "frictionless";
    fs::create_directories(dir);
    fs::copy_file(kSourceDir + "/assets/scoop.stl", dir / "scoop.stl",
                  fs::copy_options::overwrite_existing);
    std::ofstream(dir / "lander_arm.urdf")
        << std::regex_replace(text, std::regex("friction=\"[^\"]*\""), "friction=\"0\"");
    return (dir / "lander_arm.urdf").string();
  }();
  return path;
}

std::string HoldScene(const std::string& table) {
  return SceneText(table, kHold, "snow", 0.02, 1, FrictionlessUrdf());
}
const std::array<double, 6> kW = {6, -3, 9, 0.3, 0.5, -0.4};  // [N], [N m], l_scoop at the CoM

// Two holds, zero table and constant table, shared by the tests below.
const TableRun& HoldZero() {
  static const TableRun r = RunTable("hold_zero", HoldScene(WriteTable("zero", {})));
  return r;
}
const TableRun& HoldConstant() {
  static const TableRun r = RunTable("hold_w", HoldScene(WriteTable("constant", kW)));
  return r;
}

TEST(TableArm, SteadyJointTorquesChangeByMinusJacobianTransposeTimesTheTableWrench) {
  const TableRun& zero = HoldZero();
  const TableRun& loaded = HoldConstant();
  ASSERT_EQ(zero.exit_status, 0);
  ASSERT_EQ(loaded.exit_status, 0);
  constexpr int kRows = 50;  // the last 50 ms of the hold
  const Eigen::VectorXd tau0 = TailMean(zero.output, "/arm/torque_demanded", kRows);
  const Eigen::VectorXd tau1 = TailMean(loaded.output, "/arm/torque_demanded", kRows);
  const Eigen::VectorXd q = TailMean(loaded.output, "/arm/joint_position", kRows);
  const Eigen::VectorXd expected = -JtW(loaded.scene, q, Base(loaded.output), kW);
  const double tol = 5e-3 * expected.cwiseAbs().maxCoeff();
  for (int i = 0; i < q.size(); ++i)
    EXPECT_NEAR(tau1[i] - tau0[i], expected[i], tol) << "joint " << i;
  // The wrench applied is the table's, in its frame (turned to world axes and back for the row:
  // a few ulp of |F|).
  int w = 0;
  const std::vector<double> f = ReadRows(loaded.output, "/scoop/force_scoop", &w);
  const double ulps = 1e-14 * std::hypot(kW[0], kW[1], kW[2]);
  EXPECT_NEAR(f[f.size() - 3], kW[0], ulps);
  EXPECT_NEAR(f[f.size() - 1], kW[2], ulps);
}

// The CoM of each /scoop/pose row (world) [m], 3 per row.
std::vector<double> ComRows(const TableRun& r) {
  int w = 0;
  const std::vector<double> pose = ReadRows(r.output, "/scoop/pose", &w);
  const dem::Vec3 c{RootAttribute(r.output, "scoop_com_x"), RootAttribute(r.output, "scoop_com_y"),
                    RootAttribute(r.output, "scoop_com_z")};
  std::vector<double> com;
  for (size_t i = 0; i + 7 <= pose.size(); i += 7) {
    dem::Pose p;
    p.position = {pose[i], pose[i + 1], pose[i + 2]};
    p.orientation = {pose[i + 3], pose[i + 4], pose[i + 5], pose[i + 6]};
    const dem::Vec3 x = dem::Apply(p, c);
    com.insert(com.end(), {x.x, x.y, x.z});
  }
  return com;
}

TEST(TableArm, TheTableRowIsPickedByTheRunningMaximumOfTheCoMTravelAlongTheTrench) {
  const std::array<double, 6> w0 = {-1, 0.5, 2, 0.1, -0.2, 0.05};
  const std::array<double, 6> k = {-20, 5, 30, 1, -2, 0.5};  // per m of rho
  const TableRun r = RunTable(
      "push", SceneText(WriteTable("linear", w0, k),
                        "[{translate: [1, 0, 0], speed: 0.05, distance: 0.05}, {hold: 0.3}]"));
  ASSERT_EQ(r.exit_status, 0);
  int w = 0;
  const std::vector<double> rho = ReadRows(r.output, "/scoop/rho", &w);
  const std::vector<double> com = ComRows(r);
  const std::vector<double> force = ReadRows(r.output, "/scoop/force_scoop", &w);
  const std::vector<double> torque = ReadRows(r.output, "/scoop/torque_scoop", &w);
  ASSERT_GT(rho.size(), 100u);
  ASSERT_EQ(com.size(), 3 * rho.size());
  // First contact at the first step (buried); the first row is that step.
  double best = 0;
  for (size_t i = 0; i < rho.size(); ++i) {
    const double along = com[3 * i] - com[0];  // heading 0: the trench is world +x
    best = std::max(best, along);
    EXPECT_NEAR(rho[i], along, 1e-12) << "row " << i;
    // The rows sample the steps: the table's rho (the maximum over every step) is at least the
    // rows' maximum, and above it by no more than the CoM's jitter between two rows (1 um).
    for (int q = 0; q < 3; ++q) {
      EXPECT_NEAR(force[3 * i + q], w0[q] + k[q] * best,
                  std::abs(k[q]) * 1e-6 + 1e-9 * (1 + std::abs(w0[q])))
          << "row " << i;
      EXPECT_NEAR(torque[3 * i + q], w0[3 + q] + k[3 + q] * best, std::abs(k[3 + q]) * 1e-6 + 1e-9)
          << "row " << i;
    }
  }
  EXPECT_NEAR(rho.back(), 0.05, 2e-3);
  // The coupled dig's layout: the same /scoop/ datasets, no particle in contact.
  const std::vector<double> contacts = ReadRows(r.output, "/scoop/contacts", &w);
  ASSERT_EQ(contacts.size(), rho.size());
  for (double c : contacts) EXPECT_EQ(c, 0.0);
  for (const char* name : {"/scoop/force_body", "/scoop/torque_world"}) {
    EXPECT_EQ(ReadRows(r.output, name, &w).size(), 3 * rho.size()) << name;
    EXPECT_EQ(w, 3) << name;
  }
  EXPECT_EQ(ReadRows(r.output, "/scoop/rho_path", &w).size(), rho.size());
  const hid_t f = H5Fopen(r.output.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_EQ(H5Lexists(f, "/scoop/com", H5P_DEFAULT), 0);
  H5Fclose(f);
}

TEST(TableArm, AWrenchPastAJointsCapacityRaisesJointTorqueLimitOnThatJoint) {
  // At the held pose, find a wrench axis (l_scoop, at the CoM) and a size for which one joint
  // needs 1.5x its effort and every other under 0.9x of its own.
  const TableRun& zero = HoldZero();
  const arm::ArmModel& model = *zero.scene.arm.model;
  const Eigen::VectorXd q = TailMean(zero.output, "/arm/joint_position", 50);
  const Eigen::VectorXd tau0 = TailMean(zero.output, "/arm/torque_demanded", 50);
  const Eigen::Isometry3d base = Base(zero.output);
  const int n = model.dof();
  int expected_joint = -1;
  std::array<double, 6> w{};
  for (int axis = 0; axis < 6 && expected_joint < 0; ++axis) {
    for (double sign : {1.0, -1.0}) {
      std::array<double, 6> unit{};
      unit[axis] = sign;
      const Eigen::VectorXd per = -JtW(zero.scene, q, base, unit);
      // Smallest size at which some joint reaches 1.5x its effort.
      double size = 1e300;
      int joint = -1;
      for (int i = 0; i < n; ++i) {
        const double e = model.joints[i].effort;
        for (double target : {1.5 * e, -1.5 * e}) {
          const double s = (target - tau0[i]) / per[i];
          if (s > 0 && s < size) {
            size = s;
            joint = i;
          }
        }
      }
      bool alone = joint >= 0;
      for (int i = 0; i < n && alone; ++i)
        if (i != joint) alone = std::abs(tau0[i] + size * per[i]) < 0.9 * model.joints[i].effort;
      if (alone) {
        expected_joint = joint;
        for (int c = 0; c < 6; ++c) w[c] = size * unit[c];
        break;
      }
    }
  }
  ASSERT_GE(expected_joint, 0) << "no wrench axis loads one joint alone";
  const TableRun r = RunTable("overload", HoldScene(WriteTable("overload", w)));
  ASSERT_EQ(r.exit_status, 0);
  // /arm/fault_events: one record per event; its flag and joint fields, read by name.
  struct Event {
    uint64_t flag;
    int32_t joint;
  };
  std::vector<Event> events;
  {
    const hid_t f = H5Fopen(r.output.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    const hid_t d = H5Dopen2(f, "/arm/fault_events", H5P_DEFAULT);
    ASSERT_GE(d, 0);
    const hid_t type = H5Tcreate(H5T_COMPOUND, sizeof(Event));
    H5Tinsert(type, "flag", HOFFSET(Event, flag), H5T_NATIVE_UINT64);
    H5Tinsert(type, "joint", HOFFSET(Event, joint), H5T_NATIVE_INT32);
    const hid_t space = H5Dget_space(d);
    events.resize(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
    if (!events.empty()) H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, events.data());
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(d);
    H5Fclose(f);
  }
  bool found = false;
  for (const Event& e : events) {
    if (e.flag != kJointTorqueLimit) continue;
    EXPECT_EQ(e.joint, expected_joint) << model.joints[expected_joint].name;
    found = true;
    break;
  }
  EXPECT_TRUE(found) << "no JOINT_TORQUE_LIMIT for " << model.joints[expected_joint].name;
}

TEST(TableArm, OutOfDomainInputsAreRefusedBeforeTheRunWithOneLineAndExit2) {
  const std::string table = WriteTable("domain", kW);
  struct Case {
    std::string name, text, needle;
  };
  const std::vector<Case> cases = {
      {"ice", SceneText(table, kHold, "ice"), "material 'ice' is not in the table"},
      {"deep", SceneText(table, kHold, "snow", 0.03), "bite depth 30 mm is outside"},
      {"passes", SceneText(table, kHold, "snow", 0.02, 2), "pass 2 is not in the table"},
      {"missing", SceneText(table + ".missing", kHold), "arm.table"},
      {"no_surface", std::regex_replace(SceneText(table, kHold), std::regex("  surface: .*\n"), ""),
       "dig.surface"},
      {"long_step",
       std::regex_replace(SceneText(table, kHold), std::regex("substeps: 1"), "step: 5.0e-3"),
       "arm.step: expected a step <= 0.0025 s (arm.d_term: implicit)"},
      {"explicit_step",
       std::regex_replace(SceneText(table, kHold), std::regex("substeps: 1"),
                          "step: 1.0e-3, d_term: explicit"),
       "arm.step: expected a step <= 0.0001 s (arm.d_term: explicit)"},
  };
  for (const Case& c : cases) {
    const std::string scene = WriteScene("bad_" + c.name, c.text);
    const std::string err = (TempDir() / ("bad_" + c.name + ".err")).string();
    EXPECT_EQ(scoopsim_test::RunScoopsim(
                  "run " + scene + " -o " + (TempDir() / "bad.h5").string() + " --quiet", err),
              2)
        << c.name;
    std::ifstream in(err);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find(c.needle), std::string::npos) << c.name << ": " << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << c.name << ": " << text;
  }
}

TEST(TableArm, RhoPastTheTablesDataHoldsTheLastValue) {
  // The table's data ends at rho 20 mm; a 50 mm push goes past it.
  const std::array<double, 6> w0 = {-1, 0, 1, 0, 0, 0}, k = {-10, 0, 10, 0, 0, 0};
  const TableRun r = RunTable(
      "past", SceneText(WriteTable("short", w0, k, 8),
                        "[{translate: [1, 0, 0], speed: 0.05, distance: 0.05}, {hold: 0.1}]"));
  ASSERT_EQ(r.exit_status, 0);
  int w = 0;
  const std::vector<double> rho = ReadRows(r.output, "/scoop/rho", &w);
  const std::vector<double> force = ReadRows(r.output, "/scoop/force_scoop", &w);
  ASSERT_GT(rho.back(), 0.03);
  EXPECT_NEAR(force[force.size() - 3], w0[0] + k[0] * 0.02, 1e-12);
}

TEST(TableArm, SameRowsOnOneAndTwoThreads) {
  const std::string text = SceneText(WriteTable("threads", kW), "[{hold: 0.2}]");
  const TableRun a = RunTable("threads1", text, 1);
  const TableRun b = RunTable("threads2", text, 2);
  for (const char* name : {"/arm/joint_position", "/arm/torque_demanded", "/scoop/force_scoop"}) {
    int w = 0;
    EXPECT_EQ(ReadRows(a.output, name, &w), ReadRows(b.output, name, &w)) << name;
  }
}

// The table-driven arm writes snapshots, so `scoopsim render` replays its runs: one at its start
// and one every output.snapshot_every arm steps, each with the scoop and the arm's links and no
// particles; and --stop-after ends it (a 0.5 s hold stopped at 0.2 s, the step 3.68e-5 s, a
// snapshot every 1000 steps: 1 + steps / 1000 of them, at k * 1000 * h within 1e-12 s).
TEST(TableArm, SnapshotsHoldTheScoopAndTheArmAndStopAfterEndsTheRun) {
  const sim::Scene scene =
      sim::LoadScene(WriteScene("snap", SceneText(WriteTable("snap", kW), "[{hold: 0.5}]") +
                                            "output: {snapshot_every: 1000}\n"));
  sim::RunOptions options;
  options.output = (TempDir() / "snap.h5").string();
  options.quiet = true;
  options.stop_after = 0.2;
  ASSERT_EQ(sim::RunScene(scene, options), 0);
  const double h = scene.time_step;
  const double simulated = RootAttribute(options.output, "time");
  EXPECT_GE(simulated, 0.2 - 1e-12);
  EXPECT_LT(simulated, 0.2 + h);
  const int64_t steps = std::llround(simulated / h);
  const sim::SavedRun run(options.output);
  const std::vector<sim::SnapshotInfo> snapshots = run.Snapshots();
  ASSERT_EQ(static_cast<int64_t>(snapshots.size()), 1 + steps / 1000);
  ASSERT_GE(snapshots.size(), 2u);
  EXPECT_EQ(snapshots[0].time, 0.0);
  EXPECT_NEAR(snapshots[1].time, 1000 * h, 1e-12);
  for (const sim::SnapshotInfo& snapshot : snapshots) {
    dem::Particles particles;
    run.ReadSnapshot(snapshot, &particles);
    EXPECT_EQ(particles.size(), 0u);
    const std::vector<sim::SnapshotMesh> meshes = run.ReadSnapshotMeshes(snapshot);
    ASSERT_EQ(meshes.size(), 2u);
    EXPECT_EQ(meshes[0].name, "arm");
    EXPECT_GT(meshes[0].mesh.triangles.size(), 0u);
    EXPECT_EQ(meshes[1].name, "scoop");
    EXPECT_EQ(meshes[1].mesh.vertices.size(), scene.dig.scoop.geometry.vertices.size());
  }
}

}  // namespace

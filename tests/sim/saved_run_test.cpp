// Tests sim/files/saved_run.cpp: a run written by sim::H5Output reads back exactly (stored scene text
// and its box, gravity and render block; root attributes; snapshots in order with their particles
// in id order; the /scoop/ series), and every file it cannot read as a run (missing, not HDF5,
// without snapshots, with a snapshot dataset of the wrong shape, with a bad stored render block)
// is an InputError naming the file.
#include "sim/files/saved_run.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/files/h5_output.h"
#include "sim/files/internal_h5.h"
#include "tests/cli_util.h"

namespace sim {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("saved_run");
  return dir;
}

const char* const kSceneYaml =
    "gravity: [0, 0, -1.3]\n"
    "box: {min: [0, -0.05, 0], max: [0.2, 0.05, 0.1], wall_material: wall}\n"
    "render: {camera: trench_side, color_by: depth, size: [320, 180], every: 0.002}\n"
    "notes: keys a viewer does not read are not checked\n";

// Exact equality of two vectors, printed when it fails.
::testing::AssertionResult Same(const dem::Vec3& a, const dem::Vec3& b) {
  if (a.x == b.x && a.y == b.y && a.z == b.z) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "(" << a.x << ", " << a.y << ", " << a.z << ") != ("
                                       << b.x << ", " << b.y << ", " << b.z << ")";
}

// n particles stored out of id order (ids 2, 0, 1 for n = 3; 4, 2, 0, 3, 1 for n = 5), each
// field a different function of the id.
dem::Particles Shuffled(int n, double offset) {
  dem::Particles p;
  for (int i = 0; i < n; ++i) {
    const int64_t id = (3 * i + n - 1) % n;
    p.id.push_back(id);
    p.x.push_back({offset + 0.1 * id, -0.01 * id, 0.003 + id});
    p.v.push_back({0.5 * id, 1.0 / 3.0, -id - offset});
    p.w.push_back({id * 1e-3, 7.0, offset});
    p.radius.push_back(0.002 + 1e-4 * id);
    p.material.push_back(static_cast<int32_t>(id % 3));
  }
  return p;
}

// Three scoop samples at t = 0.1, 0.2, 0.3 s, pass 1 then 2.
constexpr int kSamples = 3;
double SampleTime(int k) { return 0.1 * (k + 1); }
dem::Vec3 SampleForce(int k) { return {1.5 * k, -2.0, 0.25 + k}; }
dem::Pose SamplePose(int k) {
  return {{0.01 * k, 0.02, 0.3 - 0.01 * k}, {0.5, 0.5, -0.5, 0.5 + 0.1 * k}};
}

// A run like a dig's: two snapshots, the /scoop/ series and the scoop_mesh attribute.
void WriteRun(const std::string& path) {
  H5Output out(path, kSceneYaml, "9.9.9");
  out.WriteSnapshot(0.0, Shuffled(5, 0.0));
  out.WriteSnapshot(0.25, Shuffled(3, 10.0));
  for (int k = 0; k < kSamples; ++k) {
    const double t = SampleTime(k), pass = k < 2 ? 1 : 2, rho = 0.01 * k;
    const dem::Vec3 f = SampleForce(k);
    const dem::Pose q = SamplePose(k);
    const double force[3] = {f.x, f.y, f.z};
    const double torque[3] = {-f.z, f.x, 2 * f.y};
    const double pose[7] = {q.position.x,    q.position.y,    q.position.z,   q.orientation.w,
                            q.orientation.x, q.orientation.y, q.orientation.z};
    out.AppendRow("/scoop/time", &t, 1);
    out.AppendRow("/scoop/pass", &pass, 1);
    out.AppendRow("/scoop/rho", &rho, 1);
    out.AppendRow("/scoop/force_world", force, 3);
    out.AppendRow("/scoop/torque_world", torque, 3);
    out.AppendRow("/scoop/pose", pose, 7);
  }
  out.SetAttribute("scoop_mesh", "assets/scoop.stl");
  out.Close();
}

// Runs `read` and expects an InputError whose message holds every one of `parts`.
template <typename F>
void ExpectInputError(F read, const std::vector<std::string>& parts) {
  try {
    read();
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    for (const std::string& part : parts) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "'" << e.what() << "' lacks '" << part << "'";
    }
  }
}

TEST(SavedRunTest, ReadsBackWhatH5OutputWrote) {
  const std::string path = (TempDir() / "run.h5").string();
  WriteRun(path);
  const SavedRun run(path);
  EXPECT_EQ(run.path(), path);

  // Root attributes; an absent one is "".
  EXPECT_EQ(run.SceneYaml(), kSceneYaml);
  EXPECT_EQ(run.RootAttribute("version"), "9.9.9");
  EXPECT_EQ(run.RootAttribute("scoop_mesh"), "assets/scoop.stl");
  EXPECT_EQ(run.RootAttribute("no_such_attribute"), "");

  // The stored scene, parsed by sim's scene code.
  const StoredScene scene = run.Scene();
  ASSERT_TRUE(scene.has_box);
  EXPECT_TRUE(Same(scene.box_min, dem::Vec3{0, -0.05, 0}));
  EXPECT_TRUE(Same(scene.box_max, dem::Vec3{0.2, 0.05, 0.1}));
  ASSERT_TRUE(scene.has_gravity);
  EXPECT_TRUE(Same(scene.gravity, dem::Vec3{0, 0, -1.3}));
  EXPECT_EQ(scene.render.camera_preset, "trench_side");
  EXPECT_EQ(scene.render.color_by, "depth");
  EXPECT_EQ(scene.render.width, 320);
  EXPECT_EQ(scene.render.height, 180);
  EXPECT_EQ(scene.render.every, 0.002);

  // Snapshots in order; particles in id order, bit for bit.
  const std::vector<SnapshotInfo> snapshots = run.Snapshots();
  ASSERT_EQ(snapshots.size(), 2u);
  EXPECT_EQ(snapshots[0].group, "/snapshots/000000");
  EXPECT_EQ(snapshots[0].time, 0.0);
  EXPECT_EQ(snapshots[1].group, "/snapshots/000001");
  EXPECT_EQ(snapshots[1].time, 0.25);
  for (const auto& [snapshot, written] :
       {std::pair{snapshots[0], Shuffled(5, 0.0)}, std::pair{snapshots[1], Shuffled(3, 10.0)}}) {
    SCOPED_TRACE(snapshot.group);
    dem::Particles p;
    p.mass = {1.0};  // stale contents are replaced
    run.ReadSnapshot(snapshot, &p);
    ASSERT_EQ(p.size(), written.size());
    EXPECT_TRUE(p.mass.empty());
    for (size_t i = 0; i < written.size(); ++i) {
      const size_t k = static_cast<size_t>(written.id[i]);  // row k holds id k
      EXPECT_EQ(p.id[k], written.id[i]);
      EXPECT_TRUE(Same(p.x[k], written.x[i]));
      EXPECT_TRUE(Same(p.v[k], written.v[i]));
      EXPECT_TRUE(Same(p.w[k], written.w[i]));
      EXPECT_EQ(p.radius[k], written.radius[i]);
      EXPECT_EQ(p.material[k], written.material[i]);
    }
  }

  // The scoop's series.
  const ScoopSeries scoop = run.Scoop();
  ASSERT_EQ(scoop.time.size(), static_cast<size_t>(kSamples));
  ASSERT_EQ(scoop.pass.size(), scoop.time.size());
  ASSERT_EQ(scoop.rho.size(), scoop.time.size());
  ASSERT_EQ(scoop.force_world.size(), scoop.time.size());
  ASSERT_EQ(scoop.torque_world.size(), scoop.time.size());
  ASSERT_EQ(scoop.pose.size(), scoop.time.size());
  for (int k = 0; k < kSamples; ++k) {
    EXPECT_EQ(scoop.time[k], SampleTime(k));
    EXPECT_EQ(scoop.pass[k], k < 2 ? 1 : 2);
    EXPECT_EQ(scoop.rho[k], 0.01 * k);
    EXPECT_TRUE(Same(scoop.force_world[k], SampleForce(k)));
    const dem::Vec3 f = SampleForce(k);
    EXPECT_TRUE(Same(scoop.torque_world[k], dem::Vec3{-f.z, f.x, 2 * f.y}));
    EXPECT_TRUE(Same(scoop.pose[k].position, SamplePose(k).position));
    EXPECT_EQ(scoop.pose[k].orientation.w, SamplePose(k).orientation.w);
    EXPECT_EQ(scoop.pose[k].orientation.x, SamplePose(k).orientation.x);
    EXPECT_EQ(scoop.pose[k].orientation.y, SamplePose(k).orientation.y);
    EXPECT_EQ(scoop.pose[k].orientation.z, SamplePose(k).orientation.z);
  }
  // The sample at or before a time, 1e-9 s of slack for rounding.
  EXPECT_EQ(scoop.SampleAt(0.05), -1);
  EXPECT_EQ(scoop.SampleAt(0.1 - 5e-10), 0);
  EXPECT_EQ(scoop.SampleAt(0.25), 1);
  EXPECT_EQ(scoop.SampleAt(5.0), 2);
}

// A run without a scene text, a dig or attributes: no box, default render block, no scoop.
TEST(SavedRunTest, WhatARunLacksIsEmpty) {
  const std::string path = (TempDir() / "bare.h5").string();
  {
    H5Output out(path, "", "v");
    out.WriteSnapshot(1.0, Shuffled(3, 0.0));
  }
  const SavedRun run(path);
  EXPECT_EQ(run.SceneYaml(), "");
  EXPECT_EQ(run.RootAttribute("scoop_mesh"), "");
  const StoredScene scene = run.Scene();
  EXPECT_FALSE(scene.has_box);
  EXPECT_FALSE(scene.has_gravity);
  EXPECT_EQ(scene.render.camera_preset, RenderSpec{}.camera_preset);
  EXPECT_EQ(scene.render.width, RenderSpec{}.width);
  EXPECT_TRUE(run.Scoop().empty());
  EXPECT_EQ(run.Snapshots().size(), 1u);
}

TEST(SavedRunTest, FilesThatAreNotRunsNameThePath) {
  // Missing, and not HDF5 at all.
  const std::string missing = (TempDir() / "missing.h5").string();
  ExpectInputError([&] { SavedRun run(missing); }, {missing, "not a readable HDF5 file"});
  const std::string text = (TempDir() / "text.h5").string();
  std::ofstream(text) << "not hdf5\n";
  ExpectInputError([&] { SavedRun run(text); }, {text, "not a readable HDF5 file"});

  // A run without snapshots opens (its scene and series can be read) but has no snapshot list.
  const std::string no_snapshots = (TempDir() / "no_snapshots.h5").string();
  {
    H5Output out(no_snapshots, kSceneYaml, "v");
    const double t = 0;
    out.AppendRow("/series/time", &t, 1);
  }
  const SavedRun run(no_snapshots);
  EXPECT_TRUE(run.Scene().has_box);
  ExpectInputError([&] { run.Snapshots(); }, {no_snapshots, "/snapshots", "snapshot_every"});

  // A stored render block LoadScene would refuse names the file, the line and the key.
  const std::string bad_render = (TempDir() / "bad_render.h5").string();
  {
    H5Output out(bad_render, "box: {min: [0, 0, 0], max: [1, 1, 1]}\nrender: {size: [8, 8]}\n",
                 "v");
  }
  ExpectInputError([&] { SavedRun(bad_render).Scene(); },
                   {bad_render + ":scene_yaml:2: render.size", "[16, 4096]"});
}

// A snapshot dataset of the wrong shape is refused naming the file and the dataset.
TEST(SavedRunTest, ABrokenSnapshotNamesTheDataset) {
  const std::string path = (TempDir() / "broken.h5").string();
  WriteRun(path);
  {
    const h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
    ASSERT_TRUE(file.valid());
    ASSERT_GE(H5Ldelete(file.get(), "/snapshots/000001/radius", H5P_DEFAULT), 0);
    const h5::Handle group(H5Gopen2(file.get(), "/snapshots/000001", H5P_DEFAULT), H5Gclose);
    const double radius[2] = {0.01, 0.01};
    h5::WriteArray(group.get(), "radius", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, radius, 2, 1);
  }
  const SavedRun run(path);
  const std::vector<SnapshotInfo> snapshots = run.Snapshots();
  dem::Particles p;
  run.ReadSnapshot(snapshots[0], &p);  // the first one is whole
  EXPECT_EQ(p.size(), 5u);
  ExpectInputError([&] { run.ReadSnapshot(snapshots[1], &p); },
                   {path, "/snapshots/000001/radius", "expected shape (3), got (2)"});
}

}  // namespace
}  // namespace sim

// Frame sequences: the quick dig rendered at two times (not blank, and different), the
// `render:` block of a scene, the CLI end to end (`scoopsim run --frames`, `scoopsim render`), one
// colour range per sequence (running and saved), and a saved run's stored meshes drawn.
#include "render/frames.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/bench.h"
#include "render/saved_run.h"
#include "sim/loop/bed.h"
#include "sim/studies/commands.h"
#include "sim/files/h5_output.h"
#include "sim/input/scene.h"
#include "tests/cli_util.h"

namespace render {
namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("render");
  return dir;
}

int Scoopsim(const std::string& args, const std::string& stderr_file = "/dev/null") {
  return scoopsim_test::RunScoopsim(args, stderr_file);
}

// Width and height of a PNG: big-endian 32-bit words at bytes 16 and 20 (the IHDR chunk).
void PngSize(const fs::path& png, int* width, int* height) {
  std::ifstream in(png, std::ios::binary);
  unsigned char b[24] = {};
  in.read(reinterpret_cast<char*>(b), sizeof(b));
  *width = (b[16] << 24) | (b[17] << 16) | (b[18] << 8) | b[19];
  *height = (b[20] << 24) | (b[21] << 16) | (b[22] << 8) | b[23];
}

int CountFrames(const fs::path& dir) {
  int n = 0;
  for (int k = 0;; ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%06d.png", k);
    if (!fs::exists(dir / name)) return n;
    ++n;
  }
}

// (d) The quick dig itself (scenes/quick_dig.yaml: bed poured, the scoop on the Table 1 path),
// rendered while it runs: the frame at entry (the first one, scoop above the bed) and the first
// frame past 50 mm of rho (mid-trench). Each is far from blank (over 10% of the pixels differ from
// the background: the bed alone covers more) and the two differ in over 2000 pixels (the scoop
// has moved by a third of the box). Then the run is stopped the way SIGTERM stops it.
TEST(FramesTest, QuickDigIsNotBlankAndChanges) {
  sim::Scene scene = sim::LoadScene(kSourceDir + "/scenes/quick_dig.yaml");
  FrameOptions options;
  options.dir = (TempDir() / "dig").string();
  options.settings.camera.width = 480;
  options.settings.camera.height = 270;
  options.camera_preset = "trench_oblique";
  options.threads = 1;
  FrameSequence frames(options);
  Image entry, mid;
  bool have_entry = false, have_mid = false;
  sim::RunOptions run;
  run.output = (TempDir() / "quick_dig.h5").string();
  run.quiet = true;
  run.threads = 2;
  run.frame_every = 0.05;
  run.on_frame = [&](const sim::WorldView& view) {
    if (have_mid) return;
    frames.Add(view);
    if (!have_entry) {
      entry = frames.renderer().image();  // a copy: the renderer reuses its image
      have_entry = true;
    } else if (view.pass == 1 && view.rho > 0.05) {
      mid = frames.renderer().image();
      have_mid = true;
      std::raise(SIGTERM);  // the run closes its output and returns 130
    }
  };
  EXPECT_EQ(sim::RunScene(scene, run), 130);
  sim::ClearStopRequest();
  ASSERT_TRUE(have_entry);
  ASSERT_TRUE(have_mid);
  const Rgba8 background = frames.options().settings.background;
  int not_background_entry = 0, not_background_mid = 0, differing = 0;
  for (int y = 0; y < mid.height(); ++y) {
    for (int x = 0; x < mid.width(); ++x) {
      not_background_entry += entry.At(x, y) != background;
      not_background_mid += mid.At(x, y) != background;
      differing += mid.At(x, y) != entry.At(x, y);
    }
  }
  EXPECT_GT(not_background_entry, mid.width() * mid.height() / 10);
  EXPECT_GT(not_background_mid, mid.width() * mid.height() / 10);
  EXPECT_GT(differing, 2000);
}

// The `render:` block: a preset, an explicit camera, and bad values reported on one line with
// file, line and key.
TEST(FramesTest, SceneRenderBlock) {
  const auto write = [](const std::string& name, const std::string& render_block) {
    const fs::path path = TempDir() / name;
    std::ofstream(path) << "materials: " << kSourceDir << "/scenes/materials.yaml\n"
                        << "gravity: [0, 0, -1.3]\n"
                        << "box: {min: [0, 0, 0], max: [0.03, 0.03, 0.06], wall_material: wall}\n"
                        << "bed: {material: snow, radius: 1.75e-3, count: 100}\n"
                        << render_block;
    return path.string();
  };
  const sim::Scene preset = sim::LoadScene(write(
      "preset.yaml", "render: {camera: top, color_by: depth, size: [320, 200], every: 0.01}\n"));
  EXPECT_EQ(preset.render.camera_preset, "top");
  EXPECT_EQ(preset.render.color_by, "depth");
  EXPECT_EQ(preset.render.width, 320);
  EXPECT_EQ(preset.render.height, 200);
  EXPECT_EQ(preset.render.every, 0.01);
  const FrameOptions options = FrameOptionsFromSpec(preset.render);
  EXPECT_EQ(options.settings.color_by, ColorField::kDepth);
  EXPECT_EQ(options.camera_preset, "top");

  const sim::Scene explicit_camera = sim::LoadScene(write(
      "explicit.yaml", "render:\n  camera: {position: [1, 2, 3], target: [0, 0, 0], fov: 50}\n"));
  const FrameOptions e = FrameOptionsFromSpec(explicit_camera.render);
  EXPECT_TRUE(e.camera_preset.empty());
  EXPECT_EQ(e.settings.camera.position.y, 2);
  EXPECT_EQ(e.settings.camera.fov_y_deg, 50);
  EXPECT_EQ(e.settings.camera.width, 1280);  // default size

  const struct {
    const char* block;
    const char* message;
  } bad[] = {
      {"render: {camera: sideways}\n", ":5: render.camera: expected a preset (trench_side|"},
      {"render: {color_by: colour}\n", ":5: render.color_by: expected one of speed, depth"},
      {"render: {size: [10, 720]}\n", ":5: render.size: expected [width, height] in pixels"},
      {"render:\n  camera: {position: [1, 1, 1], target: [1, 1, 1]}\n",
       ":6: render.camera.target: expected a point other than render.camera.position"},
      {"render: {every: -1}\n", ":5: render.every: expected a number >= 0"},
      {"render: {zoom: 2}\n", ":5: render.zoom: expected one of the keys camera, color_by"},
  };
  for (const auto& c : bad) {
    try {
      sim::LoadScene(write("bad.yaml", c.block));
      ADD_FAILURE() << "accepted: " << c.block;
    } catch (const sim::InputError& error) {
      EXPECT_NE(std::string(error.what()).find(c.message), std::string::npos)
          << error.what() << "\nexpected to contain: " << c.message;
    }
  }
}

// The CLI: `scoopsim run --frames` writes a frame at t0 and every --every seconds, and
// `scoopsim render` writes one frame per snapshot of the run's file, sized by the run's scene,
// replacing the frames an earlier sequence left in the folder. 200 spheres, 0.003 s run at dt
// = 6.4e-6 s with a frame every 1e-3 s: frames at 0, 1, 2, 3 ms (the last step ends at or just past
// 3 ms) = 4; snapshots every 200 steps (1.3 ms) plus t0 = 3.
TEST(FramesTest, CliRunAndRenderWriteFrames) {
  const fs::path scene = TempDir() / "cli.yaml";
  std::ofstream(scene) << "materials: " << kSourceDir << "/scenes/materials.yaml\n"
                       << R"(gravity: [0, 0, -1.3]
time_step: {rayleigh_fraction: 0.2}
box: {min: [0, 0, 0], max: [0.03, 0.03, 0.06], wall_material: wall}
bed:
  material: snow
  radius: 1.75e-3
  count: 200
  settle: {kinetic_energy: 1.0, max_time: 1.0}
duration: 0.003
output: {interval: 1.0e-3, snapshot_every: 200}
render: {camera: trench_side, size: [320, 180]}
)";
  const fs::path out = TempDir() / "cli.h5";
  const fs::path live = TempDir() / "live";
  ASSERT_EQ(Scoopsim("run " + scene.string() + " -o " + out.string() + " --threads 1 --quiet " +
                     "--frames " + live.string() + " --every 1e-3"),
            0);
  EXPECT_EQ(CountFrames(live), 4);

  // A frame left by an earlier, longer sequence goes; other files stay.
  const fs::path saved = TempDir() / "saved";
  fs::create_directories(saved);
  std::ofstream(saved / "frame_000007.png") << "stale";
  std::ofstream(saved / "notes.txt") << "keep";
  const fs::path log = TempDir() / "render.log";
  ASSERT_EQ(Scoopsim("render " + out.string() + " --frames " + saved.string() +
                         " --threads 1 --quiet --color-by depth --camera top --video",
                     log.string()),
            0);
  EXPECT_EQ(CountFrames(saved), 3);
  // The size comes from the run's own scene (render.size), as for the live frames.
  int width = 0, height = 0;
  PngSize(saved / "frame_000000.png", &width, &height);
  EXPECT_EQ(width, 320);
  EXPECT_EQ(height, 180);
  PngSize(live / "frame_000000.png", &width, &height);
  EXPECT_EQ(width, 320);
  EXPECT_EQ(height, 180);
  EXPECT_FALSE(fs::exists(saved / "frame_000007.png"));
  EXPECT_TRUE(fs::exists(saved / "notes.txt"));
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // --video either made the MP4 or said that ffmpeg is missing.
  EXPECT_TRUE(text.find("ffmpeg is not installed") != std::string::npos ||
              fs::exists(saved.string() + ".mp4"))
      << text;

  // Forces are not in snapshots: asking for them is bad input (status 2) with a message.
  EXPECT_EQ(Scoopsim("render " + out.string() + " --frames " + (TempDir() / "f").string() +
                     " --quiet --color-by force"),
            2);
}

}  // namespace
}  // namespace render

namespace render {
namespace {

// Frames from a saved dig draw the scoop: a run file with one snapshot, /scoop/pose and the
// root attribute scoop_mesh renders differently from the same file without the attribute (the
// scoop covers part of the bed), and identically to itself.
TEST(FramesTest, SavedDigDrawsTheScoop) {
  auto write_run = [](const std::string& path, bool with_mesh) {
    sim::H5Output out(path, "box: {min: [0, 0, 0], max: [0.2, 0.1, 0.1], wall_material: wall}\n",
                      "test");
    dem::Particles p;
    for (int i = 0; i < 40; ++i)
      for (int j = 0; j < 20; ++j) {
        p.id.push_back(static_cast<int64_t>(p.id.size()));
        p.x.push_back({0.0025 + 0.005 * i, 0.0025 + 0.005 * j, 0.0025});
        p.v.push_back({});
        p.w.push_back({});
        p.radius.push_back(0.0025);
        p.material.push_back(0);
      }
    out.WriteSnapshot(0.5, p);
    const double t = 0.5, pass = 1, rho = 0.01;
    const double pose[7] = {0.08, 0.05, 0.08, 0.0, 1.0, 0.0, 0.0};  // level scoop above the bed
    out.AppendRow("/scoop/time", &t, 1);
    out.AppendRow("/scoop/pass", &pass, 1);
    out.AppendRow("/scoop/rho", &rho, 1);
    out.AppendRow("/scoop/pose", pose, 7);
    if (with_mesh) out.SetAttribute("scoop_mesh", kSourceDir + "/assets/scoop.stl");
    out.Close();
  };
  auto render_run = [](const std::string& h5, const std::string& dir) {
    FrameOptions options;
    options.dir = (TempDir() / dir).string();
    options.settings.camera.width = 320;
    options.settings.camera.height = 180;
    options.camera_preset = "trench_oblique";
    options.threads = 1;
    FrameSequence frames(options);
    EXPECT_EQ(RenderSavedRun(h5, &frames, true), 1);
    return frames.renderer().image();
  };
  write_run((TempDir() / "with.h5").string(), true);
  write_run((TempDir() / "without.h5").string(), false);
  const Image with = render_run((TempDir() / "with.h5").string(), "with");
  const Image again = render_run((TempDir() / "with.h5").string(), "again");
  const Image without = render_run((TempDir() / "without.h5").string(), "without");
  int differing = 0, same = 0;
  for (int y = 0; y < with.height(); ++y)
    for (int x = 0; x < with.width(); ++x) {
      differing += with.At(x, y) != without.At(x, y);
      same += with.At(x, y) == again.At(x, y);
    }
  EXPECT_GT(differing, 500);  // the scoop, ~0.13 x 0.08 m seen from ~0.4 m, covers thousands
  EXPECT_EQ(same, with.width() * with.height());
}

}  // namespace
}  // namespace render

namespace render {
namespace {

// One big sphere of speed `speed` in the middle of a 0.2 x 0.1 x 0.1 m box.
dem::Particles OneSphere(double speed) {
  dem::Particles p;
  p.id.push_back(0);
  p.x.push_back({0.1, 0.05, 0.03});
  p.v.push_back({speed, 0, 0});
  p.w.push_back({});
  p.radius.push_back(0.03);
  p.material.push_back(0);
  return p;
}

FrameOptions FlatOptions(const std::string& dir) {
  FrameOptions options;
  options.dir = (TempDir() / dir).string();
  options.settings.camera.width = 160;
  options.settings.camera.height = 120;
  options.settings.shading = false;
  options.settings.overlays = false;
  options.settings.scenery = false;
  options.camera_preset = "top";
  options.threads = 1;
  return options;
}

std::string FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A sequence keeps one colour range: a sphere at 0.2 m/s, then 1.5 m/s (beyond the range), then
// 0.2 m/s again, in the range [0, 1]: the first and last frames are the same image, the centre
// pixel viridis(0.2) (unlit, within 1); the middle one shows viridis(1) there. Setting the range
// once frames are written is refused.
TEST(FramesTest, SequenceKeepsOneColourRange) {
  FrameOptions options = FlatOptions("fixed_range");
  options.settings.range_min = 0;
  options.settings.range_max = 1;
  FrameSequence frames(options);
  std::vector<Image> images;
  for (double speed : {0.2, 1.5, 0.2}) {
    const dem::Particles p = OneSphere(speed);
    sim::WorldView view;
    view.particles = &p;
    view.box_max = {0.2, 0.1, 0.1};
    frames.Add(view);
    images.push_back(frames.renderer().image());
  }
  const Rgba8 first = images[0].At(80, 60), middle = images[1].At(80, 60);
  const Rgb want = Viridis(0.2), top = Viridis(1.0);
  EXPECT_NEAR(first.r, 255 * want.r, 1);
  EXPECT_NEAR(first.g, 255 * want.g, 1);
  EXPECT_NEAR(first.b, 255 * want.b, 1);
  EXPECT_NEAR(middle.g, 255 * top.g, 1);
  int differing = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) differing += images[0].At(x, y) != images[2].At(x, y);
  EXPECT_EQ(differing, 0);
  EXPECT_THROW(frames.SetRange(0, 2), std::logic_error);
}

// A saved run's frames share the whole run's colour range: three snapshots of one sphere at 0.2,
// 1.0 and 0.2 m/s render with the range [0, 1] (the largest snapshot's 99th percentile, read
// before the first frame), so the first and last PNG files are byte for byte the same; given a
// range (--color-range), the frames use it.
TEST(FramesTest, SavedRunFramesShareTheWholeRunsRange) {
  const std::string h5 = (TempDir() / "three_speeds.h5").string();
  {
    sim::H5Output out(h5, "box: {min: [0, 0, 0], max: [0.2, 0.1, 0.1], wall_material: wall}\n",
                      "test");
    for (double speed : {0.2, 1.0, 0.2}) out.WriteSnapshot(0.1, OneSphere(speed));
    out.Close();
  }
  FrameSequence frames(FlatOptions("saved_range"));
  ASSERT_EQ(RenderSavedRun(h5, &frames, true), 3);
  EXPECT_EQ(frames.options().settings.range_min, 0);
  EXPECT_NEAR(frames.options().settings.range_max, 1.0, 1e-6);  // stored as a float field
  EXPECT_EQ(FileBytes(frames.FramePath(0)), FileBytes(frames.FramePath(2)));
  EXPECT_NE(FileBytes(frames.FramePath(0)), FileBytes(frames.FramePath(1)));

  FrameOptions given = FlatOptions("saved_given");
  given.settings.range_max = 4;
  given.range_given = true;
  FrameSequence fixed(given);
  RenderSavedRun(h5, &fixed, true);
  EXPECT_EQ(fixed.options().settings.range_max, 4);
}

// A saved run's frames draw the meshes stored with each snapshot (here an "arm" link, a 4 cm box
// over the sphere), in the arm's colour, without any mesh file.
TEST(FramesTest, SavedRunDrawsTheSnapshotsMeshes) {
  const std::string h5 = (TempDir() / "with_meshes.h5").string();
  const dem::TriangleMesh box = BoxMesh({-0.02, -0.02, -0.02}, {0.02, 0.02, 0.02});
  {
    sim::H5Output out(h5, "box: {min: [0, 0, 0], max: [0.2, 0.1, 0.1], wall_material: wall}\n",
                      "test");
    dem::Pose above;
    above.position = {0.1, 0.05, 0.08};
    out.WriteSnapshot(0.1, OneSphere(0.2), {{&box, above, sim::MeshRole::kArmLink}});
    out.Close();
  }
  FrameSequence frames(FlatOptions("saved_meshes"));
  ASSERT_EQ(RenderSavedRun(h5, &frames, true), 1);
  const Rgba8 c = frames.renderer().image().At(80, 60);
  EXPECT_NEAR(c.r, 0.90 * 255, 1);
  EXPECT_NEAR(c.g, 0.55 * 255, 1);
  EXPECT_NEAR(c.b, 0.20 * 255, 1);
}

// `scoopsim bench render` draws the last snapshot of the file it is given (a bed or a run),
// copied side by side up to --particles: a run whose last snapshot is one sphere (r 3 cm, in a
// 0.2 x 0.1 m box), asked for 3, draws three copies 0.2 m apart (none hides another), and its
// one JSON line says particles 3 and drawn 3. Without --bed it is refused.
TEST(FramesTest, BenchRenderDrawsTheGivenBedCopiedSideBySide) {
  const std::string h5 = (TempDir() / "bench_bed.h5").string();
  {
    sim::H5Output out(h5, "box: {min: [0, 0, 0], max: [0.2, 0.1, 0.1], wall_material: wall}\n",
                      "test");
    out.WriteSnapshot(0.1, OneSphere(0.2));
    out.WriteSnapshot(0.2, OneSphere(0.5));
    out.Close();
  }
  const std::string json = (TempDir() / "bench.json").string();
  const std::string cmd = std::string(SCOOPSIM_BINARY) + " bench render --bed " + h5 +
                          " --particles 3 --frames 2 --threads 1 >" + json + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << scoopsim_test::ReadText(json);
  const std::string line = scoopsim_test::ReadText(json);
  EXPECT_NE(line.find("{\"bench\":\"render\",\"particles\":3,\"frames\":2,"), std::string::npos)
      << line;
  EXPECT_NE(line.find("\"drawn\":3,"), std::string::npos) << line;
  EXPECT_NE(Scoopsim("bench render --frames 1"), 0);
}

// A running world's range comes from its scene (color_map.h): for scenes/arm/nominal_snow.yaml
// (box 0.15 m high, pushes at 0.05 m/s, a 5 deg/s rotation through 0 deg, r 8 mm snow) speed
// [0, 0.05] (the push; the rotation's rate times the farthest scoop vertex is slower), depth
// [0, 0.15], material [0, materials - 1], force [0, m |g| 0.15 / (2 r)].
TEST(FramesTest, SceneColourRangeFollowsTheScene) {
  const sim::Scene scene = sim::LoadScene(kSourceDir + "/scenes/arm/nominal_snow.yaml");
  double lo = -1, hi = -1;
  SceneColorRange(scene, ColorField::kSpeed, &lo, &hi);
  EXPECT_EQ(lo, 0);
  EXPECT_DOUBLE_EQ(hi, 0.05);
  SceneColorRange(scene, ColorField::kDepth, &lo, &hi);
  EXPECT_DOUBLE_EQ(hi, 0.15);
  SceneColorRange(scene, ColorField::kMaterial, &lo, &hi);
  EXPECT_EQ(hi, scene.materials.size() - 1);
  SceneColorRange(scene, ColorField::kForce, &lo, &hi);
  const double r = 8e-3, m = scene.materials[scene.materials.Find("snow")].density * 4.0 / 3.0 *
                             3.14159265358979 * r * r * r;
  EXPECT_NEAR(hi, m * 1.3 * 0.15 / (2 * r), 1e-12 * hi);
}

// --color-range other than LO,HI with LO < HI (reversed, one number, not numbers, a third value)
// is bad input: exit 2 and one line naming the option.
TEST(FramesTest, ColorRangeOptionIsChecked) {
  const std::string h5 = (TempDir() / "range_cli.h5").string();
  {
    sim::H5Output out(h5, "box: {min: [0, 0, 0], max: [0.2, 0.1, 0.1], wall_material: wall}\n",
                      "test");
    out.WriteSnapshot(0.1, OneSphere(0.2));
    out.Close();
  }
  const std::string err = (TempDir() / "range_cli.txt").string();
  for (const char* range : {"2,1", "1", "a,b", "0,1,2", "0,"}) {
    EXPECT_EQ(Scoopsim("render " + h5 + " --frames " + (TempDir() / "range_cli").string() +
                           " --color-range " + range + " --quiet",
                       err),
              2)
        << range;
    const std::string text = FileBytes(err);
    EXPECT_NE(text.find("--color-range: expected LO,HI"), std::string::npos) << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  }
}

}  // namespace
}  // namespace render

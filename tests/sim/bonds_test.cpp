// The sim/ side of breakable bonds (issue 44): the bed.bonds keys, the strength laws with depth,
// the bonds made when a settled bed is loaded, the time step they force, their place in bed files
// and run outputs, and the per-particle broken count the frames colour by.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "dem/bond.h"
#include "sim/files/bed_io.h"
#include "sim/files/saved_run.h"
#include "sim/input/scene.h"
#include "sim/loop/bed.h"
#include "sim/loop/preflight.h"
#include "sim/loop/world.h"
#include "tests/cli_util.h"

namespace sim {
namespace {

namespace fs = std::filesystem;
using scoopsim_test::ReadText;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("bonds");
  return dir;
}

// A plain scene of 8 mm snow spheres with bonds. Lines: 10 bonds, 11 gap, 12 modulus, 13
// tensile_strength, 14 shear_strength, then `extra` (lines of the bonds block), then `tail`.
std::string SceneText(const std::string& extra = "", const std::string& tail = "",
                      const std::string& modulus = "1.0e6") {
  return "materials: " + std::string(SCOOPSIM_SOURCE_DIR) + "/scenes/materials.yaml\n" +  // 1
         "gravity: [0, 0, -1.3]\n"                                                        // 2
         "time_step: {rayleigh_fraction: 0.25}\n"                                         // 3
         "neighbor: {skin: 4.0e-3}\n"                                                     // 4
         "box: {min: [0, 0, 0], max: [0.2, 0.2, 0.2], wall_material: wall}\n"             // 5
         "bed:\n"                                                                         // 6
         "  material: snow\n"                                                             // 7
         "  radius: 8.0e-3\n"                                                             // 8
         "  count: 100\n"                                                                 // 9
         "  bonds:\n"                                                                     // 10
         "    gap: 1.0e-3\n"                                                              // 11
         "    modulus: " +
         modulus +
         "\n"                                                             // 12
         "    tensile_strength: 1.0e4\n"                                  // 13
         "    shear_strength: {cohesion: 2.0e4, friction_angle: 30}\n" +  // 14
         extra +
         tail;
}

std::string Write(const std::string& name, const std::string& text) {
  const fs::path path = TempDir() / name;
  std::ofstream(path) << text;
  return path.string();
}

// The message LoadScene throws for `text` ("" when it loads).
std::string LoadError(const std::string& name, const std::string& text) {
  const std::string path = Write(name, text);
  try {
    LoadScene(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Defaults (the scene's comment cites them: Potyondy and Cundall 2004, PFC's linear parallel
// bond) where a key is left out, and the values as given (angle in rad): exact.
TEST(BondsTest, KeysAndDefaults) {
  const Scene scene = LoadScene(Write("defaults.yaml", SceneText()));
  const BondSpec& b = scene.bed.bonds;
  ASSERT_TRUE(b.enabled);
  EXPECT_EQ(b.gap, 1.0e-3);
  EXPECT_EQ(b.params.radius_multiplier, 1.0);
  EXPECT_EQ(b.params.stiffness_ratio, 2.5);
  EXPECT_EQ(b.params.modulus, 1.0e6);
  EXPECT_EQ(b.params.tensile_strength, 1.0e4);
  EXPECT_EQ(b.params.cohesion, 2.0e4);
  EXPECT_EQ(b.params.friction_angle, 30 * M_PI / 180);
  EXPECT_EQ(b.params.damping_ratio, 0.0);
  EXPECT_EQ(b.strength_vs_depth.law, StrengthVsDepth::Law::kConstant);
  // No bed.bonds: an unbonded bed.
  const std::string plain = SceneText();
  const Scene unbonded = LoadScene(Write("unbonded.yaml", plain.substr(0, plain.find("  bonds:"))));
  EXPECT_FALSE(unbonded.bed.bonds.enabled);
  EXPECT_EQ(unbonded.bond_time_step, 0.0);
  EXPECT_EQ(unbonded.time_step, unbonded.contact_time_step);
}

// .inf is a strength that never breaks (the near-solid extreme) for tensile_strength and the
// cohesion alone; anywhere else it is refused as any non-finite number.
TEST(BondsTest, InfinityOnlyForTheStrengths) {
  std::string text = SceneText();
  text.replace(text.find("tensile_strength: 1.0e4"), 23, "tensile_strength: .inf");
  text.replace(text.find("cohesion: 2.0e4"), 15, "cohesion: .inf");
  const Scene scene = LoadScene(Write("inf.yaml", text));
  EXPECT_TRUE(std::isinf(scene.bed.bonds.params.tensile_strength));
  EXPECT_TRUE(std::isinf(scene.bed.bonds.params.cohesion));
  const std::string path = (TempDir() / "inf_modulus.yaml").string();
  EXPECT_EQ(LoadError("inf_modulus.yaml", SceneText("", "", ".inf")),
            path + ":12: bed.bonds.modulus: expected a number > 0 (Pa), got .inf");
  const std::string gap = (TempDir() / "inf_gap.yaml").string();
  std::string g = SceneText();
  g.replace(g.find("gap: 1.0e-3"), 11, "gap: .inf");
  EXPECT_EQ(LoadError("inf_gap.yaml", g),
            gap +
                ":11: bed.bonds.gap: expected a number in [0, 0.008] (m; bed's largest "
                "radius), got .inf");
}

// Bad values: one line naming file, line, key and what was expected (a representative few of
// each key).
TEST(BondsTest, BadValuesAreOneLine) {
  struct Case {
    std::string extra, expected;  // the bonds block's extra lines; the message after "PATH:"
  };
  const Case cases[] = {
      {"    radius_multiplier: 1.5\n",
       "15: bed.bonds.radius_multiplier: expected a number in (0, 1] (bond radius / smaller "
       "sphere's radius), got 1.5"},
      {"    stiffness_ratio: 0\n",
       "15: bed.bonds.stiffness_ratio: expected a number > 0 (k_n / k_s), got 0"},
      {"    damping_ratio: -0.1\n",
       "15: bed.bonds.damping_ratio: expected a number in [0, 1] (of critical), got -0.1"},
      {"    stiffnes_ratio: 2\n",
       "15: bed.bonds.stiffnes_ratio: expected one of the keys gap, radius_multiplier, modulus, "
       "stiffness_ratio, tensile_strength, shear_strength, damping_ratio, strength_vs_depth, got "
       "an unknown key 'stiffnes_ratio'"},
      {"    strength_vs_depth: linear\n",
       "15: bed.bonds.strength_vs_depth: expected constant, {law: linear, slope: 1/m}, {law: "
       "exponential, length: m} or {law: table, points: [[depth m, factor], ...]}, got linear"},
      {"    strength_vs_depth: {law: cubic}\n",
       "15: bed.bonds.strength_vs_depth.law: expected constant, linear, exponential or table, got "
       "cubic"},
      {"    strength_vs_depth: {law: exponential, length: 0}\n",
       "15: bed.bonds.strength_vs_depth.length: expected a number != 0 (m): f = exp(depth / "
       "length), < 0 weakens, got 0"},
      {"    strength_vs_depth: {law: linear}\n",
       "15: bed.bonds.strength_vs_depth.slope: expected a number (1/m): f = max(0, 1 + slope x "
       "depth), got nothing (key missing)"},
      {"    strength_vs_depth: {law: table, points: [[0, 1], [0, 2]]}\n",
       "15: bed.bonds.strength_vs_depth.points: expected a list of [depth, factor] pairs, depths "
       ">= 0 (m) strictly ascending, factors >= 0, got [0, 2] (depth not above the previous "
       "point's)"},
      {"    strength_vs_depth: {law: table, points: [[0, -1]]}\n",
       "15: bed.bonds.strength_vs_depth.points: expected a list of [depth, factor] pairs, depths "
       ">= 0 (m) strictly ascending, factors >= 0, got [0, -1]"},
  };
  int k = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.extra);
    const std::string name = "bad" + std::to_string(k++) + ".yaml";
    EXPECT_EQ(LoadError(name, SceneText(c.extra)), (TempDir() / name).string() + ":" + c.expected);
  }
  // The strengths and the shear block's own keys.
  const auto replaced = [](const std::string& from, const std::string& to) {
    std::string text = SceneText();
    return text.replace(text.find(from), from.size(), to);
  };
  EXPECT_EQ(
      LoadError("bad_tensile.yaml", replaced("tensile_strength: 1.0e4", "tensile_strength: -5")),
      (TempDir() / "bad_tensile.yaml").string() +
          ":13: bed.bonds.tensile_strength: expected a number > 0 (Pa), or .inf for a bond "
          "that never breaks, got -5");
  EXPECT_EQ(LoadError("bad_friction.yaml", replaced("friction_angle: 30", "friction_angle: 90")),
            (TempDir() / "bad_friction.yaml").string() +
                ":14: bed.bonds.shear_strength.friction_angle: expected a number in [0, 90) (deg), "
                "got 90");
  std::string m = SceneText();
  m.erase(m.find("    modulus:"), m.find("    tensile_strength") - m.find("    modulus:"));
  EXPECT_EQ(LoadError("no_modulus.yaml", m),
            (TempDir() / "no_modulus.yaml").string() +
                ":11: bed.bonds.modulus: expected a number > 0 (Pa), got nothing (key missing)");
  // The CLI: exit 2 and that one line.
  const std::string path = Write("cli_bad.yaml", SceneText("    radius_multiplier: 0\n"));
  const std::string log = (TempDir() / "cli_bad.log").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim("check " + path, log), 2);
  EXPECT_EQ(ReadText(log), "scoopsim: " + path +
                               ":15: bed.bonds.radius_multiplier: expected a number in (0, 1] "
                               "(bond radius / smaller sphere's radius), got 0\n");
}

// Each law against its formula at a few depths (d < 0 taken as 0), to 1e-12.
TEST(BondsTest, StrengthLawsFollowTheirFormulas) {
  StrengthVsDepth constant;
  StrengthVsDepth linear;
  linear.law = StrengthVsDepth::Law::kLinear;
  linear.slope = -4.0;  // 1/m: f = 0 from 0.25 m down
  StrengthVsDepth exponential;
  exponential.law = StrengthVsDepth::Law::kExponential;
  exponential.length = 0.05;
  StrengthVsDepth table;
  table.law = StrengthVsDepth::Law::kTable;
  table.depth = {0.01, 0.03, 0.1};
  table.factor = {0.5, 2.0, 3.0};
  for (double d : {-0.02, 0.0, 0.005, 0.01, 0.02, 0.07, 0.1, 0.3}) {
    SCOPED_TRACE(d);
    const double z = std::max(d, 0.0);
    EXPECT_EQ(BondStrengthFactor(constant, d), 1.0);
    EXPECT_NEAR(BondStrengthFactor(linear, d), std::max(0.0, 1 - 4.0 * z), 1e-12);
    EXPECT_NEAR(BondStrengthFactor(exponential, d), std::exp(z / 0.05), 1e-12);
    // Held beyond the ends, linear between: hand-computed.
    const double expected = z <= 0.01   ? 0.5
                            : z <= 0.03 ? 0.5 + (z - 0.01) / 0.02 * 1.5
                            : z <= 0.1  ? 2.0 + (z - 0.03) / 0.07 * 1.0
                                        : 3.0;
    EXPECT_NEAR(BondStrengthFactor(table, d), expected, 1e-12);
  }
}

// A hand-built bed: pairs of touching spheres at known heights. Each bond's strengths are the
// scene's times f(depth of its contact point below the given surface), to 1e-12 relative; an
// infinite strength stays infinite; the pair where f = 0 (at the surface) gets no bond.
TEST(BondsTest, BondStrengthsFollowTheDepthLaw) {
  const std::string extra =
      "    strength_vs_depth: {law: table, points: [[0.0, 0.0], [0.1, 2.0]]}\n";
  std::string text = SceneText(extra);
  text.replace(text.find("cohesion: 2.0e4"), 15, "cohesion: .inf");
  const Scene scene = LoadScene(Write("depth.yaml", text));
  World world(scene, 1);
  dem::System& system = world.mutable_system();
  const int snow = scene.materials.Find("snow");
  const double r = 0.008, surface = 0.15;
  // Pair k side by side (contact point at the centres' height z_k), 0.05 m apart in x.
  const double z[] = {0.15, 0.12, 0.09, 0.06, 0.01};
  for (int k = 0; k < 5; ++k) {
    system.AddParticle({0.02 + 0.04 * k, 0.05, z[k]}, {}, {}, r, snow);
    system.AddParticle({0.02 + 0.04 * k, 0.05 + 2 * r, z[k]}, {}, {}, r, snow);
  }
  const std::vector<dem::Bond> bonds = MakeBedBonds(system, scene.bed.bonds, surface);
  ASSERT_EQ(bonds.size(), 4u);  // none for pair 0, at the surface
  for (int k = 1; k < 5; ++k) {
    SCOPED_TRACE(k);
    const double f = std::min(2.0, 20.0 * (surface - z[k]));  // the table's formula
    const dem::Bond& bond = bonds[k - 1];
    EXPECT_EQ(bond.a, 2 * k);
    EXPECT_EQ(bond.b, 2 * k + 1);
    EXPECT_NEAR(bond.tensile_strength, 1.0e4 * f, 1e-12 * 1.0e4 * 2);
    EXPECT_TRUE(std::isinf(bond.cohesion));
  }
}

// The bonds made on load: as many as an O(N^2) brute force counts pairs whose surfaces are
// closer than the gap, the same pairs, and a bed that holds bonds keeps them as saved (a saved
// bonded bed loads with every field equal, intact or broken).
TEST(BondsTest, BondsMadeOnLoadMatchABruteForcePairCount) {
  const Scene scene = LoadScene(Write("load.yaml", SceneText()));
  const std::string bed = (TempDir() / "load_bed.h5").string();
  {
    World maker(scene, 1);
    dem::System& system = maker.mutable_system();
    const int snow = scene.materials.Find("snow");
    // A jittered lattice: pitch 2r + 0.5 mm, each centre moved by up to +-0.6 mm (a hash of its
    // index), so gaps fall on both sides of 1 mm.
    int n = 0;
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 5; ++i, ++n) {
          const double u = std::sin(12.9898 * n) * 43758.5453;
          const double jitter = 1.2e-3 * (u - std::floor(u)) - 0.6e-3;
          const double pitch = 0.0165;
          system.AddParticle({0.03 + pitch * i + jitter, 0.03 + pitch * j - 0.5 * jitter,
                              0.009 + pitch * k + 0.3 * jitter},
                             {}, {}, 0.008, snow);
        }
    SaveBed(bed, system, scene.yaml_text);
  }
  World world(scene, 1);
  world.LoadBed(bed);
  const dem::Particles& p = world.system().particles();
  std::vector<std::pair<int64_t, int64_t>> brute;
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = 0; j < p.size(); ++j) {
      if (p.id[i] >= p.id[j]) continue;
      const double gap = dem::Norm(p.x[j] - p.x[i]) - p.radius[i] - p.radius[j];
      if (gap < scene.bed.bonds.gap) brute.emplace_back(p.id[i], p.id[j]);
    }
  std::sort(brute.begin(), brute.end());
  const std::vector<dem::Bond>& bonds = world.system().bonds();
  ASSERT_EQ(bonds.size(), brute.size());
  EXPECT_GT(brute.size(), 50u);  // the jitter leaves both kinds of pair
  for (size_t k = 0; k < bonds.size(); ++k) {
    EXPECT_EQ(bonds[k].a, brute[k].first);
    EXPECT_EQ(bonds[k].b, brute[k].second);
  }

  // Saved with its bonds (one marked broken, with a state), loaded as saved.
  std::vector<dem::Bond> saved = bonds;
  dem::System s(scene.materials, MakeSystemConfig(scene));
  LoadBed(bed, &s);  // sim::LoadBed: the unbonded bed, its ids as saved
  saved[3].intact = false;
  saved[5].fn = 1.25;
  saved[5].fs = {0.5, -0.25, 0.125};
  saved[5].mb = {1e-3, 2e-3, -3e-3};
  saved[5].mt = 4e-4;
  saved[5].normal = {0, 1, 0};
  saved[7].tensile_strength = std::numeric_limits<double>::infinity();
  s.AddBonds(saved);
  const std::string bonded = (TempDir() / "bonded_bed.h5").string();
  SaveBed(bonded, s, scene.yaml_text);
  World loaded(scene, 1);
  loaded.LoadBed(bonded);  // holds bonds: none made
  const std::vector<dem::Bond>& back = loaded.system().bonds();
  ASSERT_EQ(back.size(), saved.size());
  EXPECT_EQ(loaded.system().intact_bond_count(), static_cast<int64_t>(saved.size()) - 1);
  for (size_t k = 0; k < saved.size(); ++k) {
    SCOPED_TRACE(k);
    const dem::Bond &x = saved[k], &y = back[k];
    EXPECT_EQ(x.a, y.a);
    EXPECT_EQ(x.b, y.b);
    EXPECT_EQ(x.intact, y.intact);
    EXPECT_EQ(x.radius, y.radius);
    EXPECT_EQ(x.kn, y.kn);
    EXPECT_EQ(x.ks, y.ks);
    EXPECT_EQ(x.tensile_strength, y.tensile_strength);
    EXPECT_EQ(x.cohesion, y.cohesion);
    EXPECT_EQ(x.tan_friction, y.tan_friction);
    EXPECT_EQ(x.damping_ratio, y.damping_ratio);
    EXPECT_EQ(x.fn, y.fn);
    EXPECT_EQ(x.mt, y.mt);
    EXPECT_EQ(x.fs.x, y.fs.x);
    EXPECT_EQ(x.fs.z, y.fs.z);
    EXPECT_EQ(x.mb.y, y.mb.y);
    EXPECT_EQ(x.normal.y, y.normal.y);
  }
}

// The step: min(rayleigh_fraction t_R, dem::BondCriticalStep(smallest radius, its density,
// params)), the rule named; to 1e-12 against each formula. A soft bond leaves the contact's
// step; a stiff one rules, and `check` reports it with its cost when 10x or more smaller.
TEST(BondsTest, TimeStepRule) {
  const Scene soft = LoadScene(Write("soft.yaml", SceneText("", "", "1.0e3")));
  const dem::Material& snow = soft.materials[soft.materials.Find("snow")];
  const double contact = 0.25 * dem::RayleighTimeStep(0.008, snow);
  EXPECT_NEAR(soft.contact_time_step, contact, 1e-12 * contact);
  EXPECT_NEAR(soft.bond_time_step,
              dem::BondCriticalStep(0.008, snow.density, soft.bed.bonds.params),
              1e-12 * soft.bond_time_step);
  ASSERT_GT(soft.bond_time_step, contact);
  EXPECT_EQ(soft.time_step, soft.contact_time_step);
  EXPECT_STREQ(TimeStepRule(soft), "contact");

  Scene stiff = LoadScene(Write("stiff.yaml", SceneText("", "duration: 0.1\n", "1.0e12")));
  const double bond = dem::BondCriticalStep(0.008, snow.density, stiff.bed.bonds.params);
  ASSERT_LT(bond * 10, contact);
  EXPECT_NEAR(stiff.time_step, bond, 1e-12 * bond);
  EXPECT_STREQ(TimeStepRule(stiff), "bond");
  EXPECT_EQ(TimeStepLine(stiff).find("time step "), 0u);
  EXPECT_NE(TimeStepLine(stiff).find("set by the bonds"), std::string::npos);
  const RunForecast f = Preflight(&stiff, Work::kRun);
  EXPECT_STREQ(f.time_step_rule, "bond");
  EXPECT_NE(f.bond_note.find(":12: bed.bonds: the bonds' critical step"), std::string::npos)
      << f.bond_note;
  EXPECT_NE(f.bond_note.find(" unbonded"), std::string::npos) << f.bond_note;
  Scene soft_copy = soft;
  EXPECT_TRUE(Preflight(&soft_copy, Work::kRun).bond_note.empty());
}

// BrokenBondCounts against a hand count: ids in any order, ids of no record 0, records of ids
// not in the list skipped.
TEST(BondsTest, BrokenBondCountsCountEachEnd) {
  const std::vector<int64_t> ids = {7, 3, 5, 11};
  const std::vector<int64_t> a = {3, 3, 5, 2};
  const std::vector<int64_t> b = {5, 7, 7, 3};
  const std::vector<float> c = BrokenBondCounts(ids, a, b);
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c[0], 2.0f);  // 7: (3,7), (5,7)
  EXPECT_EQ(c[1], 3.0f);  // 3: (3,5), (3,7), (2,3)
  EXPECT_EQ(c[2], 2.0f);  // 5
  EXPECT_EQ(c[3], 0.0f);  // 11
}

// A scene of weak bonds (tensile strength 50 Pa) on a saved lattice of 6 x 6 x 3 touching 8 mm
// spheres whose top layer starts moving up at 0.5 m/s; returns the scene's path.
std::string BreakingScene(const std::string& name) {
  const std::string bed = (TempDir() / (name + "_bed.h5")).string();
  std::string text =
      SceneText("", "  file: " + bed + "\nduration: 100\noutput: {interval: 1.0e-3}\n");
  text.replace(text.find("tensile_strength: 1.0e4"), 23, "tensile_strength: 50");
  const std::string scene_path = Write(name + ".yaml", text);
  const Scene scene = LoadScene(scene_path);
  World maker(scene, 1);
  dem::System& system = maker.mutable_system();
  const int snow = scene.materials.Find("snow");
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i)
        system.AddParticle({0.05 + 0.016 * i, 0.05 + 0.016 * j, 0.008 + 0.016 * k},
                           {0, 0, k == 2 ? 0.5 : 0.0}, {}, 0.008, snow);
  SaveBed(bed, system, scene.yaml_text);
  return scene_path;
}

// The colour field broken_bonds: the per-particle counts a saved run yields at a frame's time
// (sim::BrokenBondCounts of the /bonds/broken/ records up to it, as `scoopsim render` draws them)
// equal the live frame's (from the system's own bonds), particle by particle, at every frame.
TEST(BondsTest, BrokenCountsOfASavedRunEqualTheLiveFrames) {
  const Scene scene = LoadScene(BreakingScene("frames"));
  const std::string out = (TempDir() / "frames.h5").string();
  struct Frame {
    double time;
    std::vector<int64_t> ids;
    std::vector<float> counts;
  };
  std::vector<Frame> frames;
  {
    World world(scene, 1);
    world.OpenOutput(out);
    world.LoadBed(scene.bed.file);
    RunControl control;
    control.quiet = true;
    control.stop_after = 0.02;
    control.frame_every = 2e-3;
    control.on_frame = [&](const WorldView& v) {
      frames.push_back({v.time, v.particles->id, v.broken_bonds});
    };
    ASSERT_EQ(world.Run(control).exit_status, 0);
  }
  const BondSeries s = SavedRun(out).Bonds();
  ASSERT_GT(frames.size(), 5u);
  ASSERT_GT(s.broken_time.size(), 0u);
  float most = 0;
  for (const Frame& f : frames) {
    SCOPED_TRACE(f.time);
    const int k = SampleAt(s.broken_time, f.time) + 1;
    const std::vector<int64_t> a(s.broken_a.begin(), s.broken_a.begin() + k);
    const std::vector<int64_t> b(s.broken_b.begin(), s.broken_b.begin() + k);
    EXPECT_EQ(BrokenBondCounts(f.ids, a, b), f.counts);
    for (float c : f.counts) most = std::max(most, c);
  }
  EXPECT_GE(most, 1.0f);
}

// A bonded run stopped by SIGTERM: exit 130, and its /bonds/ series and broken-bond records read
// back through SavedRun: the intact count starts at the bonds made and only falls, each record
// names a made bond, and the counts left plus the records are the bonds made. The top layer of
// a bonded lattice starts moving up at 0.5 m/s: its weak bonds to the layer below break.
TEST(BondsTest, BondedRunOutputsSurviveSigterm) {
  const std::string scene_path = BreakingScene("run");
  const std::string out = (TempDir() / "run.h5").string();
  const std::string log = (TempDir() / "run.log").string();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + std::string(SCOOPSIM_BINARY) + " run " + scene_path + " -o " +
                            out + " --threads 1 2>" + log;
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  for (int k = 0; k < 60000 && !fs::exists(out); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ::kill(pid, SIGTERM);
  ASSERT_EQ(scoopsim_test::Wait(pid), 130) << ReadText(log);
  const std::string text_log = ReadText(log);
  EXPECT_NE(text_log.find("scoopsim: bonds: "), std::string::npos) << text_log;

  const SavedRun run(out);
  EXPECT_EQ(run.RootAttribute("time_step_rule"), "contact");
  const BondSeries s = run.Bonds();
  ASSERT_GT(s.time.size(), 2u) << text_log;
  ASSERT_EQ(s.intact.size(), s.time.size());
  // The bonds the bed got: every touching lattice pair (gap 0 < 1 mm): 3 layers of 6 x 6.
  const double made = 3 * (2 * 6 * 5) + 2 * 36;
  EXPECT_LE(s.intact.front(), made);
  for (size_t k = 1; k < s.intact.size(); ++k) EXPECT_LE(s.intact[k], s.intact[k - 1]);
  ASSERT_GT(s.broken_time.size(), 0u) << "the top layer broke no bond";
  ASSERT_EQ(s.broken_a.size(), s.broken_time.size());
  ASSERT_EQ(s.broken_position.size(), s.broken_time.size());
  ASSERT_EQ(s.broken_mode.size(), s.broken_time.size());
  ASSERT_EQ(s.broken_stress.size(), s.broken_time.size());
  for (size_t k = 0; k < s.broken_time.size(); ++k) {
    EXPECT_LT(s.broken_a[k], s.broken_b[k]);
    EXPECT_TRUE(s.broken_mode[k] == 1 || s.broken_mode[k] == 2);
    EXPECT_GT(s.broken_stress[k], 0.0);
    if (k > 0) {
      EXPECT_GE(s.broken_time[k], s.broken_time[k - 1]);
    }
  }
  // Rows and records flush together: the breaks up to the last row's time account for its
  // count.
  const int last = SampleAt(s.broken_time, s.time.back()) + 1;
  EXPECT_EQ(s.intact.back() + last, made);
}

}  // namespace
}  // namespace sim

// Angles in scenes (issue 40, sim/input/yaml_input.h): every angle key takes a bare number in degrees
// (deg/s for a rate) as before, or a number with its unit ("90 deg", "1.5708 rad", "30 deg/s",
// "0.5 rad/s"); a bare number that looks like radians (not whole, |v| <= 2 pi) is taken as degrees
// with one warning line naming file, line and key; an unknown unit is refused with one line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "sim/input/scene.h"
#include "tests/cli_util.h"

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;

std::string Write(const std::string& name, const std::string& text) {
  static const std::filesystem::path dir = scoopsim_test::ProcessTempDir("scene_units");
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

// A dig scene with the angle keys of the trajectory; `pitch`, `heading`, `rate`, `angle` as
// written. Line 8 holds initial_pitch, line 11 the rotate move.
std::string Scene(const std::string& pitch, const std::string& heading, const std::string& rate,
                  const std::string& angle) {
  return "materials: " + kSourceDir + "/scenes/materials.yaml\n" +               // 1
         "gravity: [0, 0, -1.3]\n"                                               // 2
         "box: {min: [0, 0, 0], max: [0.37, 0.17, 0.2], wall_material: wall}\n"  // 3
         "bed: {material: snow, radius: 8.0e-3, count: 1450}\n"                  // 4
         "dig:\n"                                                                // 5
         "  scoop: {mesh: " +
         kSourceDir + "/assets/scoop.stl, material: aluminium}\n" +  // 6
         "  trajectory:\n"                                           // 7
         "    initial_pitch: " +
         pitch + "\n" +                                              // 8
         "    heading: " + heading + "\n" +                          // 9
         "    preset: none\n    start: [0.13, 0.085]\n    moves:\n"  // 10-12
         "      - {rotate: [0, -1, 0], rate: " +
         rate + ", angle: " + angle + "}\n";  // 13
}

// The same angles in degrees, in radians and in both, give the same scene (radians converted
// with 180/pi: 1e-12 relative), with no warning; whole degrees never warn.
TEST(SceneUnitsTest, DegreesAndRadiansWithTheirUnitsAgree) {
  const sim::Scene bare = LoadScene(Write("bare.yaml", Scene("90", "0", "30", "45")));
  const sim::Scene deg =
      LoadScene(Write("deg.yaml", Scene("90 deg", "0 deg", "30 deg/s", "45 deg")));
  const sim::Scene rad =
      LoadScene(Write("rad.yaml", Scene("1.5707963267948966 rad", "0 rad",
                                        "0.5235987755982988 rad/s", "0.7853981633974483 rad")));
  for (const sim::Scene* s : {&bare, &deg, &rad}) {
    EXPECT_TRUE(s->warnings.empty()) << s->warnings.front();
    const TrajectorySpec& t = s->dig.trajectory;
    EXPECT_NEAR(t.initial_pitch, kPi / 2, 1e-12);
    EXPECT_EQ(s->dig.heading, 0.0);
    ASSERT_EQ(t.moves.size(), 1u);
    EXPECT_NEAR(t.moves[0].speed, kPi / 6, 1e-12);
    EXPECT_NEAR(t.moves[0].amount, kPi / 4, 1e-12);
  }
}

// initial_pitch: 1.57 (a ROS user's pi/2) is 1.57 degrees, as before, with one warning at its
// line; 7.5 (above 2 pi) and 1.57 rad do not warn.
TEST(SceneUnitsTest, BareAngleThatLooksLikeRadiansWarns) {
  const std::string path = Write("looks_rad.yaml", Scene("1.57", "0", "30", "45"));
  const sim::Scene s = LoadScene(path);
  EXPECT_NEAR(s.dig.trajectory.initial_pitch, 1.57 * kPi / 180, 1e-15);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], path +
                               ":8: dig.trajectory.initial_pitch: 1.57 is taken as deg; if "
                               "radians were meant, write '1.57 rad' (or '1.57 deg' to keep "
                               "degrees)");
  EXPECT_TRUE(LoadScene(Write("big.yaml", Scene("7.5", "0", "30", "45"))).warnings.empty());
  EXPECT_TRUE(LoadScene(Write("unit.yaml", Scene("1.57 rad", "0", "30", "45"))).warnings.empty());
  // A rate too: 0.5 (rad/s?) taken as deg/s, with its warning.
  const sim::Scene r = LoadScene(Write("rate.yaml", Scene("90", "0", "0.5", "45")));
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find(":13: dig.trajectory.moves[0].rate: 0.5 is taken as deg/s"),
            std::string::npos)
      << r.warnings[0];
}

// A warning about a value a --set gave names the --set, as an error about it does (it named
// "FILE:100001:", the line the second override's node carries, before).
TEST(SceneUnitsTest, WarningAboutASetValueNamesTheSet) {
  const std::string path = Write("set_rad.yaml", Scene("90", "0", "30", "45"));
  const sim::Scene s =
      sim::LoadScene(path, {"dig.trajectory.heading=3", "dig.trajectory.initial_pitch=1.57"});
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0],
            "--set dig.trajectory.initial_pitch=1.57: dig.trajectory.initial_pitch: 1.57 is taken "
            "as deg; if radians were meant, write '1.57 rad' (or '1.57 deg' to keep degrees)");
}

// A unit other than deg or rad (deg/s, rad/s for a rate), or a value outside the key's range once
// converted, is one InputError at the key's line.
TEST(SceneUnitsTest, UnknownUnitIsRefusedWithOneLine) {
  const std::string path = Write("degrees.yaml", Scene("90 degrees", "0", "30", "45"));
  try {
    LoadScene(path);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              path +
                  ":8: dig.trajectory.initial_pitch: expected a number in [-180, 180] (deg), or "
                  "with a unit (90 deg, 1.5708 rad), got 90 degrees");
  }
  const std::string big = Write("big_rad.yaml", Scene("4 rad", "0", "30", "45"));  // 229 deg
  EXPECT_THROW(LoadScene(big), InputError);
  const std::string rate = Write("rate_unit.yaml", Scene("90", "0", "30 deg", "45"));
  EXPECT_THROW(LoadScene(rate), InputError);
}

// arm.initial, a list of joint angles: each item may carry its unit.
TEST(SceneUnitsTest, ArmInitialItemsTakeUnits) {
  std::ifstream in(kSourceDir + "/scenes/arm/nominal_snow.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text = std::regex_replace(text, std::regex("  urdf: ../../assets/lander_arm.urdf\n"),
                            "  urdf: ../../assets/lander_arm.urdf\n"
                            "  initial: [0, 1.5707963267948966 rad, -90 deg, 0, 0, 90]\n");
  const sim::Scene s = LoadSceneText(kSourceDir + "/scenes/arm/units.yaml", text);
  ASSERT_EQ(s.arm.initial.size(), 6u);
  EXPECT_NEAR(s.arm.initial[1], kPi / 2, 1e-12);
  EXPECT_NEAR(s.arm.initial[2], -kPi / 2, 1e-12);
  EXPECT_NEAR(s.arm.initial[5], kPi / 2, 1e-12);
  EXPECT_TRUE(s.warnings.empty());
}

}  // namespace
}  // namespace sim

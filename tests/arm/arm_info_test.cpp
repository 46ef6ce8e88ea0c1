// `scoopsim arm info URDF` end to end (tools/arm_info.cpp): what it prints for the lander's arm,
// and exit status 2 with one line for a bad URDF.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "tests/cli_util.h"

namespace {

std::string Read(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// The six joints with their types, the moving mass (7 links + the 0.5 kg grinder = 30.2759 kg)
// and the gravity torques of the four named poses; exit 0.
TEST(ArmInfoTest, PrintsTheLanderArm) {
  const auto dir = scoopsim_test::ProcessTempDir("arm_info");
  const std::string out = (dir / "out.txt").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim(std::string("arm info ") + ARM_TEST_URDF + " >" + out), 0);
  const std::string text = Read(out);
  for (const char* s :
       {"j_shou_yaw     revolute", "j_scoop_yaw    continuous", "6 joints", "moving 30.2759 kg",
        "l_hand + l_grinder", "zero", "stowed", "unstowed", "digging", "g = 1.3 m/s^2"}) {
    EXPECT_NE(text.find(s), std::string::npos) << s << "\n" << text;
  }
}

// The lander's own arm with its grinder and tool frames (tests/arm/data/lander_own_arm.urdf):
// exit 0, one line per merge, the grinder held, and the torques with 6 significant digits: the
// zero pose's j_prox_pitch 12.2734 N m and j_dist_pitch 1.24286 N m (GravityTorques, checked
// against an independent moment sum in kinematics_test.cpp), which "%.3f" showed as 12.273 and
// 1.243.
TEST(ArmInfoTest, PrintsTheLanderOwnArmWithItsMerges) {
  const auto dir = scoopsim_test::ProcessTempDir("arm_info_own");
  const std::string out = (dir / "out.txt").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim(std::string("arm info ") + ARM_OWN_URDF + " >" + out), 0);
  const std::string text = Read(out);
  for (const char* s :
       {"merged: l_grinder (0.5 kg, held joint j_grinder) into l_hand: mass and inertia added\n",
        "merged: l_grinder_tip (0 kg, fixed joint j_grinder_tip) into l_hand: a frame (mass and "
        "inertia dropped)\n",
        "merged: l_hand_tool (no <inertial>, fixed joint j_hand_tool) into l_hand: a frame (mass "
        "and inertia dropped)\n",
        "merged: l_scoop_tip (0.001 kg, fixed joint l_scoop_tip_joint) into l_scoop: a frame "
        "(mass and inertia dropped)\n",
        "held at zero (off the chain): j_grinder", "moving 30.2759 kg", "6 significant digits",
        " 12.2734 ", " 1.24286 "}) {
    EXPECT_NE(text.find(s), std::string::npos) << s << "\n" << text;
  }
  size_t lines = 0;
  for (size_t at = 0; (at = text.find("merged: ", at)) != std::string::npos; ++at) ++lines;
  EXPECT_EQ(lines, 4u);
}

TEST(ArmInfoTest, BadUrdfExitsTwoWithOneLine) {
  const auto dir = scoopsim_test::ProcessTempDir("arm_info_bad");
  const std::string err = (dir / "err.txt").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim("arm info " + (dir / "missing.urdf").string(), err), 2);
  const std::string text = Read(err);
  EXPECT_EQ(text, "scoopsim: " + (dir / "missing.urdf").string() +
                      ": URDF file: expected a readable file, got No such file or directory\n");
}

}  // namespace

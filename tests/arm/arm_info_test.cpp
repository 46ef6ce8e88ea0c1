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

TEST(ArmInfoTest, BadUrdfExitsTwoWithOneLine) {
  const auto dir = scoopsim_test::ProcessTempDir("arm_info_bad");
  const std::string err = (dir / "err.txt").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim("arm info " + (dir / "missing.urdf").string(), err), 2);
  const std::string text = Read(err);
  EXPECT_EQ(text, "scoopsim: " + (dir / "missing.urdf").string() +
                      ": URDF file: expected a readable file, got No such file or directory\n");
}

}  // namespace

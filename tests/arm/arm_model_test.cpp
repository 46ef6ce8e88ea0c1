// Tests of arm/arm_model.cpp: the lander's URDF read into an ArmModel, and one line naming the
// file, the element and the expectation for each kind of bad input.
#include "arm/arm_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "arm/internal_urdf_text.h"
#include "tests/cli_util.h"

namespace arm {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

const std::string& LanderUrdf() {
  static const std::string text = ReadFile(ARM_TEST_URDF);
  return text;
}

// Replaces the first occurrence of `from` (which must exist) in the lander's URDF.
std::string Edited(const std::string& from, const std::string& to) {
  std::string text = LanderUrdf();
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Writes `text` to a temporary .urdf and returns its path.
std::string WriteTemp(const std::string& name, const std::string& text) {
  static const std::filesystem::path dir = scoopsim_test::ProcessTempDir("arm");
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

// 1-based line of the first line containing `needle`.
int LineContaining(const std::string& text, const std::string& needle) {
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.find(needle) != std::string::npos) return n;
  }
  return 0;
}

// Loads `text` from a temporary file NAME and expects ArmModelError's one line to be
// "PATH:LINE: " + message, LINE the first line of `text` containing `line_of`; with
// whole = false the message need only start so (the rest carries computed numbers).
void ExpectLoadError(const std::string& name, const std::string& text, const std::string& line_of,
                     const std::string& message, bool whole = true) {
  const std::string path = WriteTemp(name, text);
  std::string got;
  try {
    LoadArmModel(path);
  } catch (const ArmModelError& e) {
    got = e.what();
  }
  const std::string expected =
      path + ":" + std::to_string(LineContaining(text, line_of)) + ": " + message;
  if (whole) {
    EXPECT_EQ(got, expected);
  } else {
    EXPECT_EQ(got.rfind(expected, 0), 0u) << got;
  }
}

TEST(ArmModelTest, ReadsTheLanderArm) {
  const ArmModel m = LoadArmModel(ARM_TEST_URDF);
  ASSERT_EQ(m.dof(), 6);
  const char* names[] = {"j_shou_yaw",   "j_shou_pitch", "j_prox_pitch",
                         "j_dist_pitch", "j_hand_yaw",   "j_scoop_yaw"};
  const double effort[] = {70.9, 101.0, 73.0, 25.7, 25.7, 20.0};
  const double friction[] = {2.6, 4.6, 2.7, 0.3, 0.3, 0.5};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(m.joints[i].name, names[i]);
    EXPECT_EQ(m.joints[i].type, i < 2 ? JointType::kRevolute : JointType::kContinuous);
    EXPECT_EQ(m.joints[i].has_position_limits, i < 2);
    EXPECT_DOUBLE_EQ(m.joints[i].effort, effort[i]);
    EXPECT_DOUBLE_EQ(m.joints[i].damping, 50);
    EXPECT_DOUBLE_EQ(m.joints[i].friction, friction[i]);
    EXPECT_GT(m.joints[i].line, 0);
  }
  EXPECT_DOUBLE_EQ(m.joints[0].lower, -1.56);
  EXPECT_DOUBLE_EQ(m.joints[1].upper, 2.2);
  EXPECT_DOUBLE_EQ(m.joints[0].velocity, 0.15);
  EXPECT_EQ(m.bodies[6].link, "l_scoop");
  // The grinder (0.5 kg) is merged into l_hand; l_scoop_tip is a massless frame of l_scoop.
  EXPECT_NEAR(m.bodies[5].inertial.mass, 6.56759 + 0.5, 1e-12);
  int body = -1;
  Eigen::Isometry3d tip;
  ASSERT_TRUE(m.FindLink("l_scoop_tip", &body, &tip));
  EXPECT_EQ(body, 6);
  EXPECT_LT((tip.translation() - Eigen::Vector3d(0.1, 0, 0.08)).norm(), 1e-15);
  EXPECT_NEAR(m.bodies[6].inertial.mass, 0.30936, 1e-15);
  // Moving mass: the seven link masses and the grinder.
  EXPECT_NEAR(m.MovingMass(), 7.0292 + 3.98552 + 7.67831 + 4.20589 + 6.56759 + 0.5 + 0.30936,
              1e-12);
  // The scoop's mesh, resolved next to the URDF.
  bool mesh = false;
  for (const Shape& s : m.bodies[6].shapes) {
    if (s.kind == Shape::Kind::kMesh && s.collision) {
      mesh = true;
      EXPECT_TRUE(std::filesystem::exists(s.mesh_path)) << s.mesh_path;
      EXPECT_EQ(std::filesystem::path(s.mesh_path).filename(), "scoop.stl");
    }
  }
  EXPECT_TRUE(mesh);
}

// The lander's own arm (tests/arm/data/lander_own_arm.urdf): loaded as is. The grinder (0.5 kg,
// on the revolute j_grinder held at zero) is merged into l_hand with its mass; the lander's dummy
// l_scoop_tip (0.001 kg, inertia 1 1 1 kg m^2), the zero-mass l_grinder_tip and l_hand_tool (no
// <inertial>) are frames: they keep their place and add nothing, so l_scoop's inertial is the
// scoop's own exactly (with the tip's 1 kg m^2 it would be ~1000x larger). Every merge is listed.
TEST(ArmModelTest, LanderOwnArmMergesItsFramesAndGrinder) {
  const ArmModel m = LoadArmModel(ARM_OWN_URDF);
  ASSERT_EQ(m.dof(), 6);
  EXPECT_EQ(m.held_joints, std::vector<std::string>{"j_grinder"});
  EXPECT_EQ(m.bodies[6].inertial.mass, 0.30936);
  EXPECT_NEAR(m.bodies[6].inertial.inertia(0, 0), 0.001031, 1e-15);
  EXPECT_NEAR(m.bodies[5].inertial.mass, 6.56759 + 0.5, 1e-12);
  struct Expected {
    const char* link;
    const char* body_link;
    const char* joint;
    const char* type;
    bool frame;
    double mass;
  };
  const Expected expected[] = {
      {"l_grinder", "l_hand", "j_grinder", "held", false, 0.5},
      {"l_grinder_tip", "l_hand", "j_grinder_tip", "fixed", true, 0},
      {"l_hand_tool", "l_hand", "j_hand_tool", "fixed", true, 0},
      {"l_scoop_tip", "l_scoop", "l_scoop_tip_joint", "fixed", true, 0.001}};
  ASSERT_EQ(m.merges.size(), 4u);
  for (size_t k = 0; k < 4; ++k) {
    const MergedLink& got = m.merges[k];
    EXPECT_EQ(got.link, expected[k].link);
    EXPECT_EQ(got.body_link, expected[k].body_link) << got.link;
    EXPECT_EQ(got.joint, expected[k].joint) << got.link;
    EXPECT_EQ(got.joint_type, expected[k].type) << got.link;
    EXPECT_EQ(got.frame, expected[k].frame) << got.link;
    EXPECT_EQ(got.mass, expected[k].mass) << got.link;
  }
  // The grinder's tip in l_hand: j_grinder's origin (Rz(-120 deg)) then (0.16, 0, 0).
  int body = -1;
  Eigen::Isometry3d tip;
  ASSERT_TRUE(m.FindLink("l_grinder_tip", &body, &tip));
  EXPECT_EQ(body, 5);
  const double yaw = -2.0943951;
  const Eigen::Vector3d want(-0.075 + 0.16 * std::cos(yaw), -0.129903811 + 0.16 * std::sin(yaw), 0);
  EXPECT_LT((tip.translation() - want).norm(), 1e-12);
}

// A link that a chain joint moves cannot be a frame: a zero mass is refused as before, a
// near-zero one (1e-12 kg, at most kFrameMass) names the link and the rule.
TEST(ArmModelTest, MasslessLinkOnAMovingJointIsRefused) {
  ExpectLoadError("zero_mass.urdf", Edited("<mass value=\"0.30936\"/>", "<mass value=\"0\"/>"),
                  "<link name=\"l_scoop\">",
                  "link 'l_scoop' <mass>: expected a mass > 0 kg, got 0");
  ExpectLoadError("tiny_mass.urdf", Edited("<mass value=\"0.30936\"/>", "<mass value=\"1e-12\"/>"),
                  "<link name=\"l_scoop\">",
                  "link 'l_scoop' <mass>: expected a mass > 0.001 kg on a link a chain joint "
                  "moves (a lighter link is a frame, allowed on fixed joints only), got 1e-12");
}

// The fixed l_scoop_tip of the shipped URDF, given the lander's 1e-12 kg: a frame, as without an
// <inertial>; the same at 1 g (kFrameMass); at 2 g it is merged with its mass.
TEST(ArmModelTest, FrameMassBoundOnAFixedJoint) {
  const std::string no_inertial = "<link name=\"l_scoop_tip\"/>";
  const auto with_mass = [&](const char* mass) {
    return Edited(no_inertial, std::string("<link name=\"l_scoop_tip\"><inertial><mass value=\"") +
                                   mass +
                                   "\"/><inertia ixx=\"1e-9\" ixy=\"0\" ixz=\"0\" "
                                   "iyy=\"1e-9\" iyz=\"0\" izz=\"1e-9\"/></inertial></link>");
  };
  for (const char* mass : {"1e-12", "0.001"}) {
    const ArmModel m = ParseArmModel(with_mass(mass), "tip.urdf");
    EXPECT_EQ(m.bodies[6].inertial.mass, 0.30936) << mass;
    ASSERT_EQ(m.merges.size(), 2u);
    EXPECT_TRUE(m.merges[1].frame) << mass;
  }
  const ArmModel heavy = ParseArmModel(with_mass("0.002"), "tip.urdf");
  EXPECT_NEAR(heavy.bodies[6].inertial.mass, 0.30936 + 0.002, 1e-15);
  EXPECT_FALSE(heavy.merges[1].frame);
}

TEST(ArmModelTest, MissingFileNamesThePath) {
  try {
    LoadArmModel("/nonexistent/arm.urdf");
    FAIL();
  } catch (const ArmModelError& e) {
    EXPECT_EQ(std::string(e.what()),
              "/nonexistent/arm.urdf: URDF file: expected a readable file, got No such file or "
              "directory");
  }
}

TEST(ArmModelTest, NotXml) {
  const std::string path = WriteTemp("not_xml.urdf", "solid scoop\n  facet normal 0 0 1\n");
  try {
    LoadArmModel(path);
    FAIL();
  } catch (const ArmModelError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(
        msg.rfind(path + ": <robot>: expected a URDF (XML with one <robot> element), got: ", 0), 0u)
        << msg;
  }
}

// urdfdom's structural errors carry no line: the element its message names is found in the file.
TEST(ArmModelTest, JointToAMissingLinkNamesTheJointsLine) {
  ExpectLoadError("missing_child.urdf",
                  Edited("<child link=\"l_shou\"/>", "<child link=\"l_sho\"/>"),
                  "<joint name=\"j_shou_yaw\"",
                  "joint 'j_shou_yaw': expected an element urdfdom can build into a URDF model, "
                  "got: Failed to build tree: child link [l_sho] of joint [j_shou_yaw] not found");
}

TEST(ArmModelTest, MalformedAxisNamesTheJointsLine) {
  ExpectLoadError("short_axis.urdf", Edited("<axis xyz=\"0 0 -1\"/>", "<axis xyz=\"0 -1\"/>"),
                  "<joint name=\"j_shou_yaw\"",
                  "joint 'j_shou_yaw': expected an element urdfdom can build into a URDF model, "
                  "got: Malformed axis element for joint [j_shou_yaw]",
                  false);
}

TEST(ArmModelTest, DuplicateLinkNamesItsFirstLine) {
  ExpectLoadError("duplicate_link.urdf", Edited("<link name=\"l_shou\">", "<link name=\"l_prox\">"),
                  "<link name=\"l_prox\">",
                  "link 'l_prox': expected an element urdfdom can build into a URDF model, got: "
                  "link 'l_prox' is not unique.");
}

TEST(ArmModelTest, LinkWithoutInertialOnTheChain) {
  const std::string inertial =
      "    <inertial>\n      <origin xyz=\"0.16225 0 -0.10446\" rpy=\"0 0 0\"/>\n"
      "      <mass value=\"3.98552\"/>\n      <inertia ixx=\"0.010948\" ixy=\"0\" "
      "ixz=\"-0.016432\" iyy=\"0.140544\" iyz=\"0\" izz=\"0.141292\"/>\n    </inertial>\n";
  ExpectLoadError("no_inertial.urdf", Edited(inertial, ""), "<link name=\"l_prox\">",
                  "link 'l_prox': expected an <inertial> on every link a chain joint moves "
                  "(base_link -> l_scoop), got none");
}

TEST(ArmModelTest, UnsupportedJointType) {
  ExpectLoadError("prismatic.urdf",
                  Edited("name=\"j_prox_pitch\" type=\"continuous\"",
                         "name=\"j_prox_pitch\" type=\"prismatic\""),
                  "name=\"j_prox_pitch\"",
                  "joint 'j_prox_pitch' type: expected revolute, continuous or fixed on the chain "
                  "base_link -> l_scoop, got prismatic");
}

TEST(ArmModelTest, NoScoopLink) {
  std::string text = LanderUrdf();
  for (size_t at; (at = text.find("\"l_scoop\"")) != std::string::npos;) {
    text.replace(at, 9, "\"l_bucket\"");
  }
  ExpectLoadError("no_scoop.urdf", text, "<robot name=",
                  "<robot name=\"lander_arm\">: expected a link named 'l_scoop' (the scoop, the "
                  "chain's tip), got none");
}

TEST(ArmModelTest, NegativeMass) {
  ExpectLoadError(
      "negative_mass.urdf", Edited("<mass value=\"7.67831\"/>", "<mass value=\"-7.67831\"/>"),
      "<link name=\"l_dist\">", "link 'l_dist' <mass>: expected a mass > 0 kg, got -7.67831");
}

// Defect: urdfdom reads a value it cannot parse as 0, so <mass value="abc"/> was reported as
// "got 0". The value is now reported as written.
TEST(ArmModelTest, MassThatIsNotANumber) {
  ExpectLoadError("mass_abc.urdf", Edited("<mass value=\"7.67831\"/>", "<mass value=\"abc\"/>"),
                  "<link name=\"l_dist\">",
                  "link 'l_dist' <mass value>: expected a number, got 'abc'");
}

TEST(ArmModelTest, InertiaNotPositiveDefinite) {
  ExpectLoadError("bad_inertia.urdf", Edited("ixx=\"0.013575\"", "ixx=\"-0.013575\""),
                  "<link name=\"l_wrist\">",
                  "link 'l_wrist' <inertia>: expected a positive-definite inertia, got principal "
                  "moments ",
                  false);
}

TEST(ArmModelTest, InertiaBreakingTheTriangleInequality) {
  // Izz > Ixx + Iyy: no real body has it.
  ExpectLoadError("triangle.urdf", Edited("izz=\"0.021682\"", "izz=\"0.08\""),
                  "<link name=\"l_hand\">",
                  "link 'l_hand' <inertia>: expected principal moments obeying the triangle "
                  "inequality (I1 + I2 >= I3), got ",
                  false);
}

TEST(ArmModelTest, EffortLimitNotPositive) {
  // j_hand_yaw's limit (j_dist_pitch's reads the same): the one before <link name="l_hand">.
  const std::string text = Edited(
      "effort=\"25.7\" velocity=\"0.2\"/>\n    <dynamics damping=\"50\" "
      "friction=\"0.3\"/>\n  </joint>\n\n  <link name=\"l_hand\">",
      "effort=\"0\" velocity=\"0.2\"/>\n    <dynamics damping=\"50\" "
      "friction=\"0.3\"/>\n  </joint>\n\n  <link name=\"l_hand\">");
  ExpectLoadError("effort.urdf", text, "name=\"j_hand_yaw\"",
                  "joint 'j_hand_yaw' <limit>: expected effort (the torque limit) > 0 N m, got 0");
}

TEST(ArmModelTest, NegativeDamping) {
  ExpectLoadError("damping.urdf",
                  Edited("damping=\"50\" friction=\"2.6\"", "damping=\"-1\" friction=\"2.6\""),
                  "name=\"j_shou_yaw\"",
                  "joint 'j_shou_yaw' <dynamics>: expected damping >= 0 and friction >= 0, got "
                  "damping -1 friction 2.6");
}

// Defect: a joint's parent set to a link below it (j_dist_pitch hung from l_grinder) made a loop
// cut off from the root, which urdfdom accepts; walking up from the scoop never ended and grew
// memory until std::bad_alloc. The loop is refused, its first joint in the file named.
TEST(ArmModelTest, JointLoopNamesTheJoint) {
  ExpectLoadError("loop.urdf", Edited("<parent link=\"l_dist\"/>", "<parent link=\"l_grinder\"/>"),
                  "<joint name=\"j_dist_pitch\"",
                  "joint 'j_dist_pitch' <parent>: expected the links to form a tree (no link its "
                  "own ancestor), got a loop through joints j_dist_pitch, j_hand_yaw, j_grinder");
}

// Defect: a link that is the child of two joints was taken silently (urdfdom keeps one of them,
// by name). The second joint in the file is named.
TEST(ArmModelTest, LinkWithTwoParentsNamesTheSecondJoint) {
  const std::string extra =
      "  <joint name=\"j_extra\" type=\"fixed\">\n    <parent link=\"l_shou\"/>\n"
      "    <child link=\"l_grinder\"/>\n  </joint>\n</robot>";
  ExpectLoadError("two_parents.urdf", Edited("</robot>", extra), "<joint name=\"j_extra\"",
                  "joint 'j_extra' <child>: expected a link with one parent joint (the links a "
                  "tree), got link 'l_grinder', already the child of joint 'j_grinder'");
}

// The lander's URDF with ~8 MB of comment before its first link; the comment opens a tag it never
// closes ("<link xxx...", as a commented-out element would).
std::string HugeUrdf(const std::string& text) {
  const size_t at = text.find("<link name=\"base_link\">");
  std::string comment = "<!-- <link ";
  for (int k = 0; k < 100000; ++k) comment += std::string(79, 'x') + "\n";
  return text.substr(0, at) + comment + " -->\n" + text.substr(at);
}

// Defect: each message's line was found by a regex search over the whole text, once per element
// looked up (a 64 MB URDF took 52 s, 200 MB did not end in 300 s), and the regex recursed once a
// character through a long tag (SIGSEGV on the URDF above). The index reads the text once, by
// construction: it answers with the text gone, and the comment's tag is not an element.
TEST(ArmModelTest, UrdfIndexReadsTheTextOnce) {
  std::string text = HugeUrdf(LanderUrdf());
  ASSERT_GT(text.size(), 8000000u);
  const int joint_line = LineContaining(text, "<joint name=\"j_hand_yaw\"");
  const size_t link_at = text.find("<link name=\"l_hand\">");
  const size_t link_end = text.find("</link>", link_at) + 7;
  const UrdfIndex index(text);
  text.assign(text.size(), '?');  // the index keeps no reference to the text
  EXPECT_EQ(index.Line("joint", "j_hand_yaw"), joint_line);
  EXPECT_EQ(index.Span("link", "l_hand"), std::make_pair(link_at, link_end));
  EXPECT_EQ(index.Line("link", "base_link"),
            LineContaining(HugeUrdf(LanderUrdf()), "<link name=\"base_link\""));
  EXPECT_EQ(index.Line("joint", "j_none"), 0);
  EXPECT_EQ(index.Span("link", "xxx").first, std::string::npos);
}

// The attributes as written, read from one element's text: the first <child> with the attribute,
// a '>' inside a quoted value kept, a commented-out element skipped, nothing past `end`.
TEST(ArmModelTest, AttributeInReadsOneElement) {
  const std::string text =
      "<link name=\"a\"><!-- <mass value=\"old\"/> --><mass/><mass value='1>2'/></link>"
      "<link name=\"b\"><mass value=\"3\"/></link>";
  const UrdfIndex index(text);
  const auto [a0, a1] = index.Span("link", "a");
  EXPECT_EQ(AttributeIn(text, a0, a1, "mass", "value"), "1>2");
  EXPECT_EQ(AttributeIn(text, a0, a1, "inertia", "ixx"), "");
  const auto [b0, b1] = index.Span("link", "b");
  EXPECT_EQ(AttributeIn(text, b0, b1, "mass", "value"), "3");
  EXPECT_EQ(b1, text.size());
}

// The same URDF end to end, a joint after the comment made bad: the message names its line, as
// for a small file; and a URDF over the size cap is refused with the cap in the message.
TEST(ArmModelTest, HugeUrdfNamesTheLineAndTheCap) {
  const std::string text =
      HugeUrdf(Edited("effort=\"25.7\" velocity=\"0.2\"/>\n    <dynamics damping=\"50\" "
                      "friction=\"0.3\"/>\n  </joint>\n\n  <link name=\"l_hand\">",
                      "effort=\"0\" velocity=\"0.2\"/>\n    <dynamics damping=\"50\" "
                      "friction=\"0.3\"/>\n  </joint>\n\n  <link name=\"l_hand\">"));
  ExpectLoadError("huge.urdf", text, "name=\"j_hand_yaw\"",
                  "joint 'j_hand_yaw' <limit>: expected effort (the torque limit) > 0 N m, got 0");
  ASSERT_NO_THROW(ParseArmModel(HugeUrdf(LanderUrdf()), "huge"));
  try {
    ParseArmModel(std::string(65 << 20, ' '), "too_big.urdf");
    ADD_FAILURE() << "a URDF over the cap was read";
  } catch (const ArmModelError& e) {
    EXPECT_EQ(std::string(e.what()),
              "too_big.urdf: URDF text: expected at most 64 MiB of URDF, got 65 MiB");
  }
}

}  // namespace
}  // namespace arm

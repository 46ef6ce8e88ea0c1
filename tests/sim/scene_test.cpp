// Tests sim/input/scene.cpp: the shipped scenes load with the time step of paper eq. 4, every malformed
// scene is refused with one line naming file, line, key and expectation, and the CLI turns such an
// error into exit status 2 and one line on stderr.
#include "sim/input/scene.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

#include "dem/mesh.h"
#include "sim/input/mesh_io.h"
#include "sim/input/trajectory.h"
#include "tests/cli_util.h"

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;

// Paper eq. 4 (Rayleigh time step), written out: t_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766).
double RayleighClosedForm(double radius, double density, double shear_modulus, double poisson) {
  return kPi * radius * std::sqrt(density / shear_modulus) / (0.1631 * poisson + 0.8766);
}

std::filesystem::path TempDir() {
  static const std::filesystem::path dir = scoopsim_test::ProcessTempDir("scene_test");
  return dir;
}

std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = (TempDir() / name).string();
  std::ofstream(path) << text;
  return path;
}

// ---------------------------------------------------------------------------------------------
// (a) Shipped scenes and materials.

// A materials file with snow and a wall; `wall_pair` spells the snow-wall pair ("[snow, wall]"
// or "[wall, snow]": either order must serve both).
void WriteSnowWallMaterials(const std::string& name, const std::string& wall_pair) {
  WriteFile(name, std::string(R"(materials:
  snow: {density: 300, shear_modulus: 1.0e7, poisson: 0.36}
  wall: {density: 7850, shear_modulus: 7.9e10, poisson: 0.3}
interactions:
  - {pair: [snow, snow], restitution: 0.88, friction: 0.58, rolling_friction: 0.05}
  - {pair: )") + wall_pair +
                      R"(, restitution: 0.7, friction: 0.58, rolling_friction: 0.05}
)");
}

TEST(SceneTest, ShippedScenesLoadWithRayleighTimeStep) {
  struct Expected {
    const char* file;
    int64_t count;
    double fraction;
  };
  // Snow (Table 6): rho 300 kg/m^3, G 1e7 Pa, nu 0.36; every shipped scene uses r = 1.75 mm.
  const Expected cases[] = {
      {"settle_small.yaml", 2000, 0.2},
      {"default.yaml", 8000, 0.2},
      {"bench_settle.yaml", 50000, 0.2},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    const Scene scene = LoadScene(kSourceDir + "/scenes/" + c.file);
    EXPECT_EQ(scene.bed.material, "snow");
    EXPECT_EQ(scene.bed.count, c.count);
    EXPECT_EQ(scene.bed.radius_min, 1.75e-3);
    EXPECT_EQ(scene.bed.radius_max, 1.75e-3);
    EXPECT_EQ(scene.rayleigh_fraction, c.fraction);
    const double expected = c.fraction * RayleighClosedForm(1.75e-3, 300.0, 1.0e7, 0.36);
    EXPECT_NEAR(scene.time_step, expected, 1e-12 * expected);
    // t_R = 3.2e-5 s for 3.5 mm snow spheres: a sanity check of the closed form itself.
    EXPECT_NEAR(expected / c.fraction, 3.2e-5, 0.05e-5);
    EXPECT_EQ(scene.gravity.z, -1.3);
    EXPECT_EQ(scene.wall_material, "wall");
    EXPECT_GT(scene.skin, 0.0);
    EXPECT_FALSE(scene.yaml_text.empty());
    EXPECT_EQ(scene.path, kSourceDir + "/scenes/" + c.file);
    EXPECT_EQ(scene.materials_path, kSourceDir + "/scenes/materials.yaml");
  }
}

TEST(SceneTest, BenchSettleSceneMatchesTheBenchmarkSpec) {
  const Scene scene = LoadScene(kSourceDir + "/scenes/bench_settle.yaml");
  EXPECT_EQ(scene.bed.count, 50000);
  EXPECT_EQ(scene.skin, 0.875e-3);
  EXPECT_NEAR(scene.box_max.x - scene.box_min.x, 0.2, 1e-15);
  EXPECT_NEAR(scene.box_max.y - scene.box_min.y, 0.1, 1e-15);
}

TEST(SceneTest, DefaultsApplyWhenOptionalKeysAreLeftOut) {
  WriteSnowWallMaterials("defaults_mats.yaml", "[wall, snow]");
  const std::string path = WriteFile("defaults.yaml", R"(materials: defaults_mats.yaml
gravity: [0, 0, -9.81]
box: {min: [0, 0, 0], max: [0.05, 0.05, 0.08], wall_material: wall}
bed: {material: snow, radius: [1.0e-3, 2.0e-3], count: 100}
)");
  const Scene scene = LoadScene(path);
  EXPECT_EQ(scene.rayleigh_fraction, 0.2);
  EXPECT_EQ(scene.bed.radius_min, 1.0e-3);
  EXPECT_EQ(scene.bed.radius_max, 2.0e-3);
  EXPECT_EQ(scene.skin, 0.25 * 2.0 * 1.0e-3);  // a quarter of the smallest diameter
  EXPECT_EQ(scene.bed.seed, 1u);
  EXPECT_EQ(scene.bed.fill_fraction, 0.35);
  EXPECT_EQ(scene.duration, 0.0);
  EXPECT_EQ(scene.threads, 0);
  EXPECT_TRUE(scene.bed.file.empty());
  // The smallest radius sets the time step.
  const double expected = 0.2 * RayleighClosedForm(1.0e-3, 300.0, 1.0e7, 0.36);
  EXPECT_NEAR(scene.time_step, expected, 1e-12 * expected);
  // The interaction given as [wall, snow] serves both orders.
  const int snow = scene.materials.Find("snow"), wall = scene.materials.Find("wall");
  EXPECT_TRUE(scene.materials.has_interaction(snow, wall));
  EXPECT_EQ(scene.materials.interaction(snow, wall).restitution, 0.7);
}

// A bed of clumps: the template's smallest sphere sets the time step (paper eq. 4), its largest
// the default skin, its bounding radius radius_max; a scene template works like a built-in one;
// WithClumpBed keeps the bed's solid volume.
TEST(SceneTest, ClumpBedTakesItsStepFromTheSmallestSphere) {
  WriteSnowWallMaterials("clumps_mats.yaml", "[snow, wall]");
  const std::string path = WriteFile("clumps.yaml", R"(materials: clumps_mats.yaml
gravity: [0, 0, -1.3]
box: {min: [0, 0, 0], max: [0.05, 0.05, 0.08], wall_material: wall}
bed: {material: snow, clump: tetra12, count: 100}
clump_templates:
  rod: {spheres: [[0, 0, 0, 1.0e-3], [0, 0, 1.5e-3, 0.5e-3]]}
health: {max_overlap: 0.1}
)");
  const Scene scene = LoadScene(path);
  EXPECT_EQ(scene.bed.clump, "tetra12");
  EXPECT_EQ(scene.bed.clump_template.radii.size(), 12u);
  EXPECT_EQ(scene.bed.radius_min, 0.4375e-3);
  EXPECT_NEAR(scene.bed.radius_max, 6.1237e-3 - 3 * 0.4375e-3 + 0.4375e-3, 1e-6);  // to its tip
  EXPECT_EQ(scene.skin, 0.5 * 1.75e-3);
  EXPECT_EQ(scene.max_overlap, 0.1);
  const double expected = 0.2 * RayleighClosedForm(0.4375e-3, 300.0, 1.0e7, 0.36);
  EXPECT_NEAR(scene.time_step, expected, 1e-12 * expected);
  ASSERT_EQ(scene.clump_templates.size(), 1u);
  EXPECT_EQ(scene.clump_templates[0].name, "rod");
  // The same solid volume in clumps of another template: count scales with 1 / volume.
  const Scene rod = WithClumpBed(scene, scene.clump_templates[0]);
  EXPECT_EQ(rod.bed.clump, "rod");
  EXPECT_EQ(rod.bed.radius_min, 0.5e-3);
  EXPECT_NEAR(rod.bed.count * rod.bed.clump_volume, 100 * scene.bed.clump_volume,
              0.5 * rod.bed.clump_volume);
  EXPECT_NEAR(rod.time_step, 0.2 * RayleighClosedForm(0.5e-3, 300.0, 1.0e7, 0.36), 1e-15);
  EXPECT_EQ(rod.skin, 0.5e-3);
}

// The study's ice scenes (tools/make_paper_scenes.py) use the 4-sphere tetrahedron, as the study
// chose, with as many clumps as hold the solid volume of the bed at a solid fraction of 0.59: the
// generator's tetra4 volume agrees with dem::ClumpMassProperties (within 1e-4).
TEST(SceneTest, PaperIceScenesUseTheFourSphereClump) {
  for (const char* file : {"bed_ice.yaml", "lut_ice_b15.yaml", "lut_ice_b3.yaml"}) {
    SCOPED_TRACE(file);
    const Scene scene = LoadScene(kSourceDir + "/scenes/paper/" + file);
    EXPECT_EQ(scene.bed.clump, "tetra4");
    EXPECT_EQ(scene.bed.material, "ice");
    const double solid = 0.59 * 0.62 * 0.22 * 0.15;
    EXPECT_NEAR(scene.bed.count * scene.bed.clump_volume, solid, 1e-4 * solid);
    // 3.5 mm spheres: the step of the snow scenes' spheres of the same size.
    EXPECT_NEAR(scene.time_step, 0.25 * RayleighClosedForm(1.75e-3, 900.0, 1.0e7, 0.36), 1e-15);
  }
  const Scene shape = LoadScene(kSourceDir + "/scenes/paper/shape_study.yaml");
  EXPECT_EQ(shape.bed.clump, "tetra4");
  EXPECT_TRUE(shape.dig.enabled);
}

TEST(SceneTest, BedFileIsResolvedAgainstTheScenesFolder) {
  WriteSnowWallMaterials("bedfile_mats.yaml", "[snow, wall]");
  const std::string path = WriteFile("bedfile.yaml", R"(materials: bedfile_mats.yaml
gravity: [0, 0, -1.3]
box: {min: [0, 0, 0], max: [0.05, 0.05, 0.08], wall_material: wall}
bed: {material: snow, radius: 1.75e-3, count: 100, file: beds/x.h5}
)");
  const Scene scene = LoadScene(path);
  EXPECT_EQ(scene.bed.file, (TempDir() / "beds" / "x.h5").string());
  EXPECT_EQ(scene.materials_path, (TempDir() / "bedfile_mats.yaml").string());
}

TEST(SceneTest, ShippedMaterialsHaveEveryPairThatCanMeet) {
  dem::MaterialTable table;
  LoadMaterials(kSourceDir + "/scenes/materials.yaml", &table);
  struct Expected {
    const char* name;
    double density;
  };
  const Expected particles[] = {{"snow", 300}, {"ice", 900}, {"size_study", 916.7}, {"sand", 2650}};
  const int wall = table.Find("wall");
  const int aluminium = table.Find("aluminium");
  ASSERT_GE(wall, 0);
  ASSERT_GE(aluminium, 0);
  for (const auto& p : particles) {
    SCOPED_TRACE(p.name);
    const int m = table.Find(p.name);
    ASSERT_GE(m, 0);
    EXPECT_EQ(table[m].density, p.density);
    EXPECT_TRUE(table.has_interaction(m, m));
    EXPECT_TRUE(table.has_interaction(m, wall));
    EXPECT_TRUE(table.has_interaction(m, aluminium));
    // Particle-scoop friction 0.58 except sand (the study's scoop values).
    if (std::string(p.name) != "sand") {
      EXPECT_EQ(table.interaction(m, aluminium).friction, 0.58);
      EXPECT_EQ(table.interaction(m, aluminium).rolling_friction, 0.05);
      EXPECT_EQ(table.interaction(m, aluminium).restitution, 0.7);
      EXPECT_EQ(table.interaction(m, m).restitution, 0.88);  // Tables 2 and 6
      EXPECT_EQ(table[m].shear_modulus, 1.0e7);
      EXPECT_EQ(table[m].poisson, 0.36);
    }
  }
  // Aluminium: G = E / (2 (1 + nu)) with E 6.9e10 Pa, nu 0.33 (the study's scoop).
  EXPECT_NEAR(table[aluminium].shear_modulus, 6.9e10 / (2.0 * 1.33), 1e-3 * 2.6e10);
  EXPECT_NEAR(table[aluminium].YoungsModulus(), 6.9e10, 1e-3 * 6.9e10);
}

// The contact law's choices: the shipped file takes the defaults (the study's code: edem rolling,
// standard damping); a file's contact_law sets every pair that names none, a pair's own keys win.
TEST(SceneTest, ContactLawFromTheFileAndFromEachPair) {
  dem::MaterialTable shipped;
  LoadMaterials(kSourceDir + "/scenes/materials.yaml", &shipped);
  const int snow = shipped.Find("snow");
  EXPECT_EQ(shipped.interaction(snow, snow).rolling_model, dem::RollingModel::kEdem);
  EXPECT_EQ(shipped.interaction(snow, snow).damping, dem::DampingLaw::kStandard);
  const std::string path = WriteFile("law_mats.yaml", R"(contact_law: {rolling_model: cdt}
materials:
  snow: {density: 300, shear_modulus: 1.0e7, poisson: 0.36}
  wall: {density: 7850, shear_modulus: 7.9e10, poisson: 0.3}
interactions:
  - {pair: [snow, snow], restitution: 0.88, friction: 0.58, rolling_friction: 0.05}
  - {pair: [snow, wall], restitution: 0.7, friction: 0.58, rolling_friction: 0.05,
     rolling_model: legacy, damping: exact_restitution}
)");
  dem::MaterialTable t;
  LoadMaterials(path, &t);
  EXPECT_EQ(t.interaction(0, 0).rolling_model, dem::RollingModel::kCdt);
  EXPECT_EQ(t.interaction(0, 0).damping, dem::DampingLaw::kStandard);
  EXPECT_EQ(t.interaction(0, 1).rolling_model, dem::RollingModel::kLegacy);
  EXPECT_EQ(t.interaction(1, 0).damping, dem::DampingLaw::kExactRestitution);
}

TEST(SceneTest, MissingSceneFileNamesTheFileAsGiven) {
  try {
    LoadScene("no/such/scene.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "no/such/scene.yaml: cannot open scene file");
  }
}

// ---------------------------------------------------------------------------------------------
// (b) Malformed scenes. Each case edits one line of a valid scene (or its materials file) and
// names substrings its one-line message must contain.

// Line numbers below refer to these texts.
const char* kGoodScene =
    "materials: mats.yaml\n"                                                 // 1
    "gravity: [0, 0, -1.3]\n"                                                // 2
    "time_step: {rayleigh_fraction: 0.2}\n"                                  // 3
    "neighbor: {skin: 0.875e-3}\n"                                           // 4
    "box: {min: [0, 0, 0], max: [0.05, 0.05, 0.08], wall_material: wall}\n"  // 5
    "bed:\n"                                                                 // 6
    "  material: snow\n"                                                     // 7
    "  radius: 1.75e-3\n"                                                    // 8
    "  count: 2000\n"                                                        // 9
    "  seed: 1\n"                                                            // 10
    "duration: 0.01\n";                                                      // 11
const char* kGoodMaterials =
    "materials:\n"                                                                           // 1
    "  snow: {density: 300, shear_modulus: 1.0e7, poisson: 0.36}\n"                          // 2
    "  wall: {density: 7850, shear_modulus: 7.9e10, poisson: 0.3}\n"                         // 3
    "interactions:\n"                                                                        // 4
    "  - {pair: [snow, snow], restitution: 0.88, friction: 0.58, rolling_friction: 0.05}\n"  // 5
    "  - {pair: [snow, wall], restitution: 0.7, friction: 0.58, rolling_friction: 0.05}\n";  // 6

struct BadCase {
  const char* name;        // also the file name: <name>.yaml, materials <name>_mats.yaml
  const char* scene_from;  // text replaced in the scene ("" = none)
  const char* scene_to;
  const char* materials_from;  // text replaced in the materials file ("" = none)
  const char* materials_to;
  std::vector<std::string> expect;  // substrings of the message; "@" stands for the file name
};

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  if (from.empty()) return text;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "test bug: '" << from << "' not in the text";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

const BadCase kBadCases[] = {
    {"unknown_key",
     "  seed: 1",
     "  sead: 1",
     "",
     "",
     {"@.yaml:10: bed.sead: expected one of the keys material, radius, count",
      "got an unknown key 'sead'"}},
    {"unknown_top_key",
     "duration: 0.01",
     "durration: 0.01",
     "",
     "",
     {"@.yaml:11: durration: expected one of the keys", "got an unknown key"}},
    {"wrong_type",
     "count: 2000",
     "count: many",
     "",
     "",
     {"@.yaml:9: bed.count: expected an integer > 0, got many"}},
    {"wrong_type_gravity",
     "gravity: [0, 0, -1.3]",
     "gravity: -1.3",
     "",
     "",
     {"@.yaml:2: gravity: expected a list of 3 numbers [gx, gy, gz] (m/s^2), got -1.3"}},
    {"gravity_two_components",
     "gravity: [0, 0, -1.3]",
     "gravity: [0, -1.3]",
     "",
     "",
     {"@.yaml:2: gravity: expected a list of 3 numbers", "got [0, -1.3]"}},
    {"missing_gravity",
     "gravity: [0, 0, -1.3]\n",
     "",
     "",
     "",
     {"@.yaml:1: gravity: expected a list of 3 numbers", "got nothing (key missing)"}},
    {"missing_count",
     "  count: 2000\n",
     "",
     "",
     "",
     {"@.yaml:7: bed.count: expected an integer > 0, got nothing (key missing)"}},
    {"negative_radius",
     "radius: 1.75e-3",
     "radius: -1.75e-3",
     "",
     "",
     {"@.yaml:8: bed.radius: expected a number >= 1e-6 or a range [rmin, rmax]", "got -1.75e-3"}},
    {"radius_range_reversed",
     "radius: 1.75e-3",
     "radius: [2.0e-3, 1.0e-3]",
     "",
     "",
     {"@.yaml:8: bed.radius: expected", "1e-6 <= rmin <= rmax", "got [2.0e-3, 1.0e-3]",
      "range reversed"}},
    {"negative_count",
     "count: 2000",
     "count: -5",
     "",
     "",
     {"@.yaml:9: bed.count: expected an integer > 0, got -5"}},
    {"bed_does_not_fit",
     "count: 2000",
     "count: 200000",
     "",
     "",
     {"@.yaml:9: bed.count: expected a bed that fits the box: at most 5256 spheres", "got 200000",
      "the settled bed would be 3.04397 m high"}},
    {"box_smaller_than_a_sphere",
     "max: [0.05, 0.05, 0.08]",
     "max: [0.05, 0.002, 0.08]",
     "",
     "",
     {"@.yaml:5: box.max: expected a box at least 0.00400293 m along x, y and z",
      "got a box of 0.05 x 0.002 x 0.08 m"}},
    {"restitution_above_one",
     "",
     "",
     "restitution: 0.88",
     "restitution: 1.3",
     {"@_mats.yaml:5: interactions[0].restitution: expected a number in (0, 1]", "got 1.3",
      "pair [snow, snow]"}},
    {"restitution_zero",
     "",
     "",
     "restitution: 0.88",
     "restitution: 0",
     {"@_mats.yaml:5: interactions[0].restitution: expected a number in (0, 1]", "got 0"}},
    {"negative_friction",
     "",
     "",
     "restitution: 0.7, friction: 0.58",
     "restitution: 0.7, friction: -0.1",
     {"@_mats.yaml:6: interactions[1].friction: expected a number >= 0", "got -0.1",
      "pair [snow, wall]"}},
    {"negative_rolling_friction",
     "",
     "",
     "rolling_friction: 0.05}",
     "rolling_friction: -1}",
     {"@_mats.yaml:5: interactions[0].rolling_friction: expected a number >= 0", "got -1"}},
    {"unknown_rolling_model",
     "",
     "",
     "rolling_friction: 0.05}",
     "rolling_friction: 0.05, rolling_model: epsd}",
     {"@_mats.yaml:5: interactions[0].rolling_model: expected edem, cdt or legacy", "got epsd"}},
    {"unknown_damping_law",
     "",
     "",
     "interactions:",
     "contact_law: {damping: exact}\ninteractions:",
     {"@_mats.yaml:4: contact_law.damping: expected standard or exact_restitution", "got exact"}},
    {"poisson_half",
     "",
     "",
     "poisson: 0.36",
     "poisson: 0.5",
     {"@_mats.yaml:2: materials.snow.poisson: expected a number in [0, 0.5)", "got 0.5"}},
    {"zero_density",
     "",
     "",
     "density: 300",
     "density: 0",
     {"@_mats.yaml:2: materials.snow.density: expected a number in [1, 1e5]", "got 0"}},
    {"negative_shear_modulus",
     "",
     "",
     "shear_modulus: 1.0e7",
     "shear_modulus: -1.0e7",
     {"@_mats.yaml:2: materials.snow.shear_modulus: expected a number > 0", "got -1.0e7"}},
    {"unknown_material_key",
     "",
     "",
     "poisson: 0.36}",
     "poisson: 0.36, colour: white}",
     {"@_mats.yaml:2: materials.snow.colour: expected one of the keys", "unknown key"}},
    {"rayleigh_fraction_too_large",
     "rayleigh_fraction: 0.2",
     "rayleigh_fraction: 0.5",
     "",
     "",
     {"@.yaml:3: time_step.rayleigh_fraction: expected a number in (0, 0.3], got 0.5",
      "time step too large", "0.3 t_R"}},
    {"rayleigh_fraction_zero",
     "rayleigh_fraction: 0.2",
     "rayleigh_fraction: 0",
     "",
     "",
     {"@.yaml:3: time_step.rayleigh_fraction: expected a number in (0, 0.3], got 0"}},
    {"unknown_material",
     "material: snow",
     "material: slush",
     "",
     "",
     {"@.yaml:7: bed.material: expected a material defined in", "(snow, wall)", "got slush"}},
    {"unknown_wall_material",
     "wall_material: wall",
     "wall_material: glass",
     "",
     "",
     {"@.yaml:5: box.wall_material: expected a material defined in", "got glass"}},
    {"yaml_syntax_error",
     "  seed: 1",
     "   seed: 1",
     "",
     "",
     {"@.yaml:10: syntax: expected valid YAML, got a syntax error"}},
    {"yaml_syntax_error_flow",
     "gravity: [0, 0, -1.3]",
     "gravity: [0, 0, -1.3",
     "",
     "",
     {"@.yaml:3: syntax: expected valid YAML", "end of sequence flow not found"}},
    {"box_min_not_below_max",
     "max: [0.05, 0.05, 0.08]",
     "max: [0.05, 0.05, 0]",
     "",
     "",
     {"@.yaml:5: box.max: expected every component greater than box.min's", "got [0.05, 0.05, 0]",
      "z: max 0 <= min 0"}},
    {"missing_interaction_pair",
     "",
     "",
     "  - {pair: [snow, wall], restitution: 0.7, friction: 0.58, rolling_friction: 0.05}\n",
     "",
     {"@.yaml:5: box.wall_material: expected an interaction for the pair [snow, wall]",
      "got none"}},
    {"missing_self_interaction",
     "",
     "",
     "  - {pair: [snow, snow], restitution: 0.88, friction: 0.58, rolling_friction: 0.05}\n",
     "",
     {"@.yaml:7: bed.material: expected an interaction for the pair [snow, snow]"}},
    {"interaction_unknown_material",
     "",
     "",
     "pair: [snow, wall]",
     "pair: [snow, steel]",
     {"@_mats.yaml:6: interactions[1].pair: expected two material names from materials "
      "(snow, wall)",
      "got [snow, steel]"}},
    {"duplicate_pair",
     "",
     "",
     "pair: [snow, wall]",
     "pair: [snow, snow]",
     {"@_mats.yaml:6: interactions[1].pair: expected each pair once, got [snow, snow] again",
      "first at line 5"}},
    {"missing_materials_file",
     "materials: mats.yaml",
     "materials: nope.yaml",
     "",
     "",
     {"@.yaml:1: materials: expected the path of a readable materials file, got nope.yaml",
      "cannot open"}},
    {"second_document",
     "duration: 0.01",
     "duration: 0.01\n---\nduration: 0.02",
     "",
     "",
     {"@.yaml:13: (document 2): expected one YAML document, got a second one after '---'",
      "it would be ignored"}},
    {"second_document_in_materials",
     "",
     "",
     "restitution: 0.7, friction: 0.58, rolling_friction: 0.05}\n",
     "restitution: 0.7, friction: 0.58, rolling_friction: 0.05}\n---\nmaterials: {}\n",
     {"@_mats.yaml:8: (document 2): expected one YAML document"}},
    {"duplicate_key",
     "duration: 0.01",
     "duration: 0.01\nduration: 0.02",
     "",
     "",
     {"@.yaml:12: duration: expected each key once", "first at line 11"}},
    {"negative_skin",
     "skin: 0.875e-3",
     "skin: -1",
     "",
     "",
     {"@.yaml:4: neighbor.skin: expected a number > 0 (m), got -1"}},
    {"fill_fraction_zero",
     "  seed: 1",
     "  seed: 1\n  fill_fraction: 0",
     "",
     "",
     {"@.yaml:11: bed.fill_fraction: expected a number in (0, 0.5]", "got 0"}},
    {"negative_duration",
     "duration: 0.01",
     "duration: -1",
     "",
     "",
     {"@.yaml:11: duration: expected a number >= 0 (s), got -1"}},
    {"unknown_clump_template",
     "  radius: 1.75e-3",
     "  clump: tetra5",
     "",
     "",
     {"@.yaml:8: bed.clump: expected a clump template (tetra1, tetra4, tetra8, tetra12), "
      "got tetra5"}},
    {"clump_and_radius",
     "  seed: 1",
     "  seed: 1\n  clump: tetra4",
     "",
     "",
     {"@.yaml:8: bed.radius: expected no bed.radius with bed.clump", "got 1.75e-3"}},
    {"clump_template_negative_radius",
     "duration: 0.01",
     "duration: 0.01\nclump_templates:\n  rod: {spheres: [[0, 0, 0, 1e-3], [0, 0, 1e-3, -1]]}",
     "",
     "",
     {"@.yaml:13: clump_templates.rod.spheres[1]: expected [x, y, z, r] with r > 0 (m), "
      "got [0, 0, 1e-3, -1]"}},
    {"clump_template_three_numbers",
     "duration: 0.01",
     "duration: 0.01\nclump_templates:\n  rod:\n    spheres:\n      - [0, 0, 1e-3]",
     "",
     "",
     {"@.yaml:15: clump_templates.rod.spheres[0]: expected [x, y, z, r] with r > 0 (m), "
      "got [0, 0, 1e-3]"}},
    {"clump_template_builtin_name",
     "duration: 0.01",
     "duration: 0.01\nclump_templates:\n  tetra4: {spheres: [[0, 0, 0, 1e-3]]}",
     "",
     "",
     {"@.yaml:13: clump_templates.tetra4: expected a name other than the built-in tetra1, "
      "tetra4, tetra8, tetra12, got 'tetra4'"}},
    {"clump_template_unknown_key",
     "duration: 0.01",
     "duration: 0.01\nclump_templates:\n  rod: {spheres: [[0, 0, 0, 1e-3]], scale: 2}",
     "",
     "",
     {"@.yaml:13: clump_templates.rod.scale: expected one of the keys spheres", "unknown key"}},
    {"clump_name_typo",
     "  radius: 1.75e-3",
     "  clump: rood",
     "",
     "",
     {"@.yaml:8: bed.clump: expected a clump template (tetra1, tetra4, tetra8, tetra12)",
      "got rood"}},
    {"max_overlap_zero",
     "duration: 0.01",
     "duration: 0.01\nhealth: {max_overlap: 0}",
     "",
     "",
     {"@.yaml:12: health.max_overlap: expected a number in (0, 0.5]", "got 0"}},
    {"box_not_a_map",
     "box: {min: [0, 0, 0], max: [0.05, 0.05, 0.08], wall_material: wall}",
     "box: 0.05",
     "",
     "",
     {"@.yaml:5: box: expected a map with keys min, max, wall_material, got 0.05"}},
};

// Names the case in gtest's failure output instead of dumping its bytes.
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadSceneTest : public testing::TestWithParam<BadCase> {};

TEST_P(BadSceneTest, IsRefusedWithOneLineNamingFileLineKeyAndExpectation) {
  const BadCase& c = GetParam();
  const std::string name = c.name;
  const std::string mats_name = name + "_mats.yaml";
  WriteFile(mats_name, Replace(kGoodMaterials, c.materials_from, c.materials_to));
  std::string scene_text = Replace(kGoodScene, c.scene_from, c.scene_to);
  const size_t mats_line = scene_text.find("materials: mats.yaml");
  if (mats_line != std::string::npos) {
    scene_text.replace(mats_line, std::string("materials: mats.yaml").size(),
                       "materials: " + mats_name);
  }
  const std::string path = WriteFile(name + ".yaml", scene_text);
  try {
    LoadScene(path);
    FAIL() << "no error for " << name;
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    for (std::string expected : c.expect) {
      const size_t at = expected.find('@');
      if (at != std::string::npos) expected.replace(at, 1, name);
      EXPECT_NE(message.find(expected), std::string::npos)
          << "message: " << message << "\nmissing: " << expected;
    }
    // The file is named exactly as given (the materials file: joined to the scene's folder).
    const bool in_materials = c.expect[0].rfind("@_mats.yaml:", 0) == 0;
    const std::string file = in_materials ? (TempDir() / mats_name).string() : path;
    EXPECT_EQ(message.rfind(file + ":", 0), 0u) << message;
  }
}

INSTANTIATE_TEST_SUITE_P(Malformed, BadSceneTest, testing::ValuesIn(kBadCases),
                         [](const testing::TestParamInfo<BadCase>& info) {
                           return std::string(info.param.name);
                         });

TEST(SceneTest, GoodSceneOfTheMalformedTableLoads) {
  WriteFile("good_mats.yaml", kGoodMaterials);
  const std::string path = WriteFile(
      "good.yaml", Replace(kGoodScene, "materials: mats.yaml", "materials: good_mats.yaml"));
  const Scene scene = LoadScene(path);
  EXPECT_EQ(scene.bed.count, 2000);
}

// ---------------------------------------------------------------------------------------------
// (c) The CLI: bad input -> exit status 2 and one line on stderr.

struct CommandResult {
  int status = -1;     // exit status, or -1 if it did not exit normally
  std::string output;  // stdout and stderr together
};

CommandResult RunCommand(const std::string& arguments) {
  const std::string command = std::string("'") + SCOOPSIM_BINARY + "' " + arguments + " 2>&1";
  CommandResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) result.output.append(buffer, n);
  const int raw = ::pclose(pipe);
  if (raw != -1 && WIFEXITED(raw)) result.status = WEXITSTATUS(raw);
  return result;
}

int CountLines(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n';
  return lines;
}

TEST(CliTest, BadSceneExitsTwoWithOneLine) {
  WriteFile("cli_mats.yaml", kGoodMaterials);
  const std::string scene =
      WriteFile("cli_bad.yaml",
                Replace(Replace(kGoodScene, "materials: mats.yaml", "materials: cli_mats.yaml"),
                        "radius: 1.75e-3", "radius: -1"));
  const std::string out = (TempDir() / "cli_out" / "run.h5").string();
  for (const char* command : {"run", "bed"}) {
    SCOPED_TRACE(command);
    const CommandResult r =
        RunCommand(std::string(command) + " '" + scene + "' -o '" + out + "' --quiet");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_EQ(CountLines(r.output), 1) << r.output;
    EXPECT_EQ(r.output, "scoopsim: " + scene +
                            ":8: bed.radius: expected a number >= 1e-6 or a range "
                            "[rmin, rmax] with 1e-6 <= rmin <= rmax (m), got -1\n");
  }
}

// --set KEY=VALUE overrides a scene key before the scene is checked: the value is read as the
// scene's own (bed.count, a nested key, a key the file leaves out, a list item), the scene's text
// keeps the overrides as trailing `# scoopsim --set` lines (what the output stores, and what a
// reader of that text applies again), the lines of the file's own keys are unchanged, and a bad key
// or value gives the scene's one-line error with `--set KEY=VALUE` for the file and line.
TEST(SceneSetTest, OverridesAreCheckedAsTheSceneIs) {
  WriteFile("set_mats.yaml", kGoodMaterials);
  const std::string good = Replace(kGoodScene, "materials: mats.yaml", "materials: set_mats.yaml");
  const std::string path = WriteFile("set_good.yaml", good);
  const std::vector<std::string> sets = {"bed.count=123", "time_step.rayleigh_fraction=0.1",
                                         "render.camera=top", "box.max.2=0.09"};
  const Scene scene = LoadScene(path, sets);
  EXPECT_EQ(scene.bed.count, 123);
  EXPECT_EQ(scene.rayleigh_fraction, 0.1);
  EXPECT_EQ(scene.render.camera_preset, "top");
  EXPECT_EQ(scene.box_max.z, 0.09);
  EXPECT_EQ(scene.box_max.y, 0.05);
  EXPECT_EQ(scene.yaml_text, good +
                                 "# scoopsim --set bed.count=123\n"
                                 "# scoopsim --set time_step.rayleigh_fraction=0.1\n"
                                 "# scoopsim --set render.camera=top\n"
                                 "# scoopsim --set box.max.2=0.09\n");
  const Scene again = LoadSceneText(path, scene.yaml_text);
  EXPECT_EQ(again.bed.count, 123);
  EXPECT_EQ(again.box_max.z, 0.09);
  EXPECT_EQ(LoadScene(path).bed.count, 2000);  // the file itself is unchanged

  auto error_of = [&](const std::string& scene_path, const std::vector<std::string>& s) {
    try {
      LoadScene(scene_path, s);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(loaded)");
  };
  // A bad value, a bad key, a key under a value that is not a map, a malformed override.
  EXPECT_EQ(error_of(path, {"bed.count=5", "bed.radius=-1"}),
            "--set bed.radius=-1: bed.radius: expected a number >= 1e-6 or a range [rmin, rmax] "
            "with 1e-6 <= rmin <= rmax (m), got -1");
  EXPECT_EQ(error_of(path, {"bed.cout=5"})
                .rfind("--set bed.cout=5: bed.cout: expected one of the "
                       "keys material, radius, count",
                       0),
            0u)
      << error_of(path, {"bed.cout=5"});
  EXPECT_EQ(error_of(path, {"bed.count.x=5"}).rfind("--set bed.count.x=5: bed.count: expected", 0),
            0u)
      << error_of(path, {"bed.count.x=5"});
  EXPECT_EQ(error_of(path, {"bed.count"}),
            "--set: expected KEY=VALUE with KEY a dotted scene key (dig.bite_depth), got "
            "'bed.count'");
  // An error in the file itself keeps its file and line whatever is set.
  const std::string bad = WriteFile("set_bad.yaml", Replace(good, "count: 2000", "count: -3"));
  EXPECT_EQ(error_of(bad, {"bed.seed=2", "duration: 0.02"}).rfind("--set: expected KEY=VALUE", 0),
            0u);
  EXPECT_EQ(error_of(bad, {"bed.seed=2"}).rfind(bad + ":9: bed.count: expected", 0), 0u)
      << error_of(bad, {"bed.seed=2"});
}

// The command line's --set on check, run and bed: a good key changes the scene (check's forecast
// counts the particles set), a bad key or value exits 2 with one line naming the --set.
TEST(CliTest, SetOverridesASceneKeyOrExitsTwoNamingIt) {
  WriteFile("cli_set_mats.yaml", kGoodMaterials);
  const std::string scene = WriteFile(
      "cli_set.yaml", Replace(kGoodScene, "materials: mats.yaml", "materials: cli_set_mats.yaml"));
  const CommandResult good = RunCommand("check '" + scene + "' --set bed.count=1500");
  EXPECT_EQ(good.status, 0) << good.output;
  EXPECT_NE(good.output.find(": ok: 1500 particles"), std::string::npos) << good.output;
  const CommandResult two =
      RunCommand("check '" + scene + "' --set bed.count=1500 --set bed.count=1700");
  EXPECT_NE(two.output.find(": ok: 1700 particles"), std::string::npos) << two.output;
  const std::string out = (TempDir() / "cli_set_out" / "run.h5").string();
  for (const char* command : {"check", "run", "bed"}) {
    SCOPED_TRACE(command);
    const std::string tail = std::string(command) == "check" ? "" : " -o '" + out + "' --quiet";
    const CommandResult key =
        RunCommand(std::string(command) + " '" + scene + "' --set bed.cout=1500" + tail);
    EXPECT_EQ(key.status, 2) << key.output;
    EXPECT_EQ(CountLines(key.output), 1) << key.output;
    EXPECT_EQ(
        key.output.rfind("scoopsim: --set bed.cout=1500: bed.cout: expected one of the keys", 0),
        0u)
        << key.output;
    const CommandResult value =
        RunCommand(std::string(command) + " '" + scene + "' --set bed.radius=-1" + tail);
    EXPECT_EQ(value.status, 2) << value.output;
    EXPECT_EQ(value.output,
              "scoopsim: --set bed.radius=-1: bed.radius: expected a number >= 1e-6 or a range "
              "[rmin, rmax] with 1e-6 <= rmin <= rmax (m), got -1\n");
  }
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(CliTest, MissingSceneExitsTwoWithOneLine) {
  const CommandResult r = RunCommand("run no/such/scene.yaml -o /dev/null --quiet");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.output, "scoopsim: no/such/scene.yaml: cannot open scene file\n");
}

TEST(CliTest, HelpAndVersionExitZero) {
  const CommandResult help = RunCommand("--help");
  EXPECT_EQ(help.status, 0) << help.output;
  EXPECT_NE(help.output.find("bed"), std::string::npos) << help.output;
  EXPECT_NE(help.output.find("run"), std::string::npos) << help.output;
  EXPECT_NE(help.output.find("bench"), std::string::npos) << help.output;
  const CommandResult run_help = RunCommand("run --help");
  EXPECT_EQ(run_help.status, 0) << run_help.output;
  EXPECT_NE(run_help.output.find("--threads"), std::string::npos) << run_help.output;
  const CommandResult version = RunCommand("--version");
  EXPECT_EQ(version.status, 0) << version.output;
  EXPECT_NE(version.output.find(SCOOPSIM_VERSION), std::string::npos) << version.output;
}

TEST(CliTest, CommandLineErrorsExitTwo) {
  EXPECT_EQ(RunCommand("").status, 2);                   // no subcommand
  EXPECT_EQ(RunCommand("dig scenes/x.yaml").status, 2);  // unknown subcommand
  EXPECT_EQ(RunCommand("run").status, 2);                // missing SCENE
  EXPECT_EQ(RunCommand("run x.yaml --threads -3").status, 2);
  EXPECT_EQ(RunCommand("bench settle --particles 0").status, 2);
  EXPECT_EQ(RunCommand("bench settle --bogus").status, 2);
}

// ---------------------------------------------------------------------------------------------
// (d) The dig block is validated whole at load: its mesh (read, triangles, finite vertices, closed
// when a density is given), the scoop's density and every key of the trajectory, `moves:` items
// included. Each error is an InputError that carries file, line and key as data.

// The trajectory's moves of DigScene, lines 10-15.
const std::string kMoves =
    "    moves:\n"                                                                           // 10
    "      - {translate: [0, 0, -1], speed: 0.14, distance: 0.028, start: 1.8}\n"            // 11
    "      - {rotate: [0, -1, 0], rate: 90, angle: 90}\n"                                    // 12
    "      - {translate: [1, 0, 0], speed: 0.3, duration: 0.1}\n"                            // 13
    "      - {hold: 0.25}\n"                                                                 // 14
    "      - {rotate: [0, 0, 1], rate: 45, angle: 30, about: [0.05, 0, 0.02], start: 4}\n";  // 15

// A dig scene naming `mesh`; line numbers in the cases below refer to it.
std::string DigScene(const std::string& mesh) {
  return "materials: " + kSourceDir + "/scenes/materials.yaml\n" +               // 1
         "gravity: [0, 0, -1.3]\n"                                               // 2
         "box: {min: [0, 0, 0], max: [0.37, 0.17, 0.2], wall_material: wall}\n"  // 3
         "bed: {material: snow, radius: 8.0e-3, count: 1450}\n"                  // 4
         "dig:\n"                                                                // 5
         "  scoop: {mesh: " +
         mesh + ", material: aluminium}\n" +  // 6
         "  trajectory:\n"                    // 7
         "    preset: table1\n"               // 8
         "    start: [0.13, 0.085]\n" +       // 9
         kMoves;                              // 10-15
}

const std::string kScoopStl = kSourceDir + "/assets/scoop.stl";

// Small mesh files a scene may name: garbage bytes (400 of them: no binary STL's 84 + 50 n), an
// OBJ without a triangle, one with a NaN vertex, one open triangle.
std::string MeshFile(const std::string& name) {
  const std::string path = (TempDir() / name).string();
  std::ofstream f(path, std::ios::binary);
  if (name == "garbage.stl") {
    for (int i = 0; i < 400; ++i) f.put(static_cast<char>((i * 37 + 11) % 256));
  } else if (name == "lines.obj") {
    f << "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n";
  } else if (name == "nan.obj") {
    f << "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  } else if (name == "triangle.obj") {
    f << "v 0 0 0\nv 0.01 0 0\nv 0 0.01 0\nf 1 2 3\n";
  }
  return path;
}

TEST(DigLoadTest, MovesListLoadsAsWritten) {
  const Scene scene = LoadScene(WriteFile("moves_good.yaml", DigScene(kScoopStl)));
  const TrajectorySpec& t = scene.dig.trajectory;
  EXPECT_DOUBLE_EQ(t.initial_pitch, 0.5 * kPi);  // the preset's, kept with moves:
  ASSERT_EQ(t.moves.size(), 5u);
  const double deg = kPi / 180;
  const Move expected[] = {Translate("", {0, 0, -1}, 0.14, 0.028, 1.8),
                           Rotate("", {0, -1, 0}, 90 * deg, 90 * deg),
                           Translate("", {1, 0, 0}, 0.3, 0.3 * 0.1), Hold("", 0.25),
                           RotateAbout("", {0, 0, 1}, 45 * deg, 30 * deg, {0.05, 0, 0.02}, 4.0)};
  for (size_t i = 0; i < t.moves.size(); ++i) {
    SCOPED_TRACE(i);
    const Move& m = t.moves[i];
    const Move& e = expected[i];
    EXPECT_EQ(m.name, "moves[" + std::to_string(i) + "]");
    EXPECT_EQ(m.kind, e.kind);
    EXPECT_EQ(m.axis.x, e.axis.x);
    EXPECT_EQ(m.axis.y, e.axis.y);
    EXPECT_EQ(m.axis.z, e.axis.z);
    EXPECT_NEAR(m.speed, e.speed, 1e-15);
    EXPECT_NEAR(m.amount, e.amount, 1e-15);
    EXPECT_EQ(m.start, e.start);
    EXPECT_EQ(m.about_pivot, e.about_pivot);
    EXPECT_EQ(m.point.x, e.point.x);
    EXPECT_EQ(m.point.z, e.point.z);
  }
  // Ends after the yaw that starts at 4 s: 30 deg at 45 deg/s.
  EXPECT_NEAR(Trajectory(t).end_time(), 4.0 + 30.0 / 45.0, 1e-12);
}

// The mesh is read at load (and kept), and a density gives the mass and CoM there.
TEST(DigLoadTest, MeshAndMassPropertiesAreMadeAtLoad) {
  std::string text = DigScene(kScoopStl);
  const Scene given = LoadScene(WriteFile("mesh_given.yaml", text));
  EXPECT_EQ(given.dig.scoop.geometry.triangles.size(), 84u);
  EXPECT_EQ(given.dig.scoop.geometry.material, given.materials.Find("aluminium"));
  EXPECT_EQ(given.dig.scoop.mass, 0.30936);  // the default, as no density is given
  text.replace(text.find("material: aluminium}"), 20, "material: aluminium, density: 2700}");
  const Scene dense = LoadScene(WriteFile("mesh_density.yaml", text));
  const dem::MassProperties mp = dem::ComputeMassProperties(LoadMesh(kScoopStl), 2700);
  EXPECT_EQ(dense.dig.scoop.density, 2700);
  EXPECT_EQ(dense.dig.scoop.mass, mp.mass);
  EXPECT_EQ(dense.dig.scoop.com.x, mp.center_of_mass.x);
  EXPECT_EQ(dense.dig.scoop.com.y, mp.center_of_mass.y);
  EXPECT_EQ(dense.dig.scoop.com.z, mp.center_of_mass.z);
}

struct DigCase {
  const char* name;
  std::string from, to;  // edit of DigScene(MESH); MESH = the mesh below
  std::string mesh;      // path of the mesh the scene names
  int line;
  std::string key;
  std::string expect;  // a substring of what()
};

std::vector<DigCase> DigCases() {
  const std::string stl = kScoopStl;
  return {
      {"missing_mesh", "", "", (TempDir() / "no_such_scoop.stl").string(), 6, "dig.scoop.mesh",
       "no file"},
      {"garbage_mesh", "", "", MeshFile("garbage.stl"), 6, "dig.scoop.mesh", "assimp"},
      {"mesh_without_triangles", "", "", MeshFile("lines.obj"), 6, "dig.scoop.mesh", "no triangle"},
      {"mesh_nan_vertex", "", "", MeshFile("nan.obj"), 6, "dig.scoop.mesh",
       "expected a mesh whose vertices have finite coordinates"},
      {"open_mesh_with_density", "material: aluminium}", "material: aluminium, density: 2700}",
       MeshFile("triangle.obj"), 6, "dig.scoop.density", "expected a closed dig.scoop.mesh"},
      {"negative_density", "material: aluminium}", "material: aluminium, density: -5}", stl, 6,
       "dig.scoop.density", "expected a number > 0 (kg/m^3), got -5"},
      {"zero_density", "material: aluminium}", "material: aluminium, density: 0}", stl, 6,
       "dig.scoop.density", "got 0"},
      {"unknown_trajectory_key", "    preset: table1", "    preset: table1\n    pivto: [0, 0, 0]",
       stl, 9, "dig.trajectory.pivto", "an unknown key 'pivto'"},
      {"zero_rate", "rate: 90", "rate: 0", stl, 12, "dig.trajectory.moves[1].rate",
       "dig.trajectory.moves[1].rate: expected a number > 0 (deg/s), got 0"},
      {"negative_rate", "rate: 90", "rate: -90", stl, 12, "dig.trajectory.moves[1].rate",
       "got -90"},
      {"zero_speed", "speed: 0.3", "speed: 0", stl, 13, "dig.trajectory.moves[2].speed",
       "expected a number > 0 (m/s), got 0"},
      {"negative_hold", "{hold: 0.25}", "{hold: -1}", stl, 14, "dig.trajectory.moves[3].hold",
       "expected a number >= 0 (s), got -1"},
      {"zero_axis", "rotate: [0, 0, 1]", "rotate: [0, 0, 0]", stl, 15,
       "dig.trajectory.moves[4].rotate", "not all 0"},
      {"infinite_direction", "translate: [1, 0, 0]", "translate: [.inf, 0, 0]", stl, 13,
       "dig.trajectory.moves[2].translate", "got [.inf, 0, 0]"},
      {"nan_about", "about: [0.05, 0, 0.02]", "about: [0.05, .nan, 0.02]", stl, 15,
       "dig.trajectory.moves[4].about", "expected a list of 3 numbers"},
      {"negative_start", "start: 1.8", "start: -1", stl, 11, "dig.trajectory.moves[0].start",
       "got -1"},
      {"overlapping_start", "start: 4}", "start: 2.5}", stl, 15, "dig.trajectory.moves[4].start",
       "expected a time >= 3.35 s (the end of moves[3]; moves run in order without "
       "overlapping), got 2.5"},
      {"distance_and_duration", "duration: 0.1}", "duration: 0.1, distance: 0.03}", stl, 13,
       "dig.trajectory.moves[2].duration", "expected either distance (m) or duration (s)"},
      {"unknown_move_key", "{hold: 0.25}", "{hold: 0.25, sped: 1}", stl, 14,
       "dig.trajectory.moves[3].sped", "expected one of the keys hold, start"},
      {"two_kinds", "{hold: 0.25}", "{hold: 0.25, translate: [1, 0, 0]}", stl, 14,
       "dig.trajectory.moves[3]", "got more than one (translate, hold)"},
      {"no_kind", "{hold: 0.25}", "{start: 3.5}", stl, 14, "dig.trajectory.moves[3]",
       "expected a map with one of translate"},
      {"moves_and_segment", "    start: [0.13, 0.085]",
       "    start: [0.13, 0.085]\n    linear: {speed: 0.1}", stl, 10, "dig.trajectory.linear",
       "got both linear and moves"},
      {"duration_beside_dig", "dig:\n", "duration: 1.0\ndig:\n", stl, 5, "duration",
       "expected no duration in a scene with a dig"},
      {"empty_moves", kMoves, "    moves: []\n", stl, 10, "dig.trajectory.moves",
       "a non-empty list of moves"},
  };
}

TEST(DigLoadTest, MalformedDigBlockIsRefusedAtLoadWithItsKey) {
  for (const DigCase& c : DigCases()) {
    SCOPED_TRACE(c.name);
    std::string text = DigScene(c.mesh);
    if (!c.from.empty()) {
      const size_t at = text.find(c.from);
      ASSERT_NE(at, std::string::npos) << "test bug: '" << c.from << "' not in the scene";
      text.replace(at, c.from.size(), c.to);
    }
    const std::string path = WriteFile(std::string(c.name) + ".yaml", text);
    try {
      LoadScene(path);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.line(), c.line) << m;
      EXPECT_EQ(e.key(), c.key) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      EXPECT_EQ(m.rfind(path + ":" + std::to_string(c.line) + ": " + c.key + ": expected ", 0), 0u)
          << m;
      EXPECT_NE(m.find(c.expect), std::string::npos) << m;
    }
  }
}

// The CLI refuses such a scene before it makes or loads a bed: exit status 2, the one line and
// nothing else (no bed or progress line), no output file, and at once (a bed of 1450 particles
// takes far longer to pour).
TEST(CliTest, BadDigBlockExitsTwoBeforeAnyParticle) {
  const std::vector<DigCase> cases = DigCases();
  for (const DigCase& c : cases) {
    const std::string name = c.name;
    if (name != "garbage_mesh" && name != "zero_rate" && name != "negative_density") continue;
    SCOPED_TRACE(name);
    std::string text = DigScene(c.mesh);
    if (!c.from.empty()) text.replace(text.find(c.from), c.from.size(), c.to);
    const std::string scene = WriteFile("cli_" + name + ".yaml", text);
    const std::string out = (TempDir() / ("cli_" + name) / "run.h5").string();
    const auto t0 = std::chrono::steady_clock::now();
    const CommandResult r = RunCommand("run '" + scene + "' -o '" + out + "'");
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_EQ(CountLines(r.output), 1) << r.output;
    EXPECT_EQ(
        r.output.rfind(
            "scoopsim: " + scene + ":" + std::to_string(c.line) + ": " + c.key + ": expected ", 0),
        0u)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_LT(seconds, 10.0);
  }
}

// scenes/lift_dig.yaml: tiny_dig's path (Table 1 with its shorter linear push, 0.05 m, and the
// second rotation from 3.2 s) written out as a moves list, then a vertical lift of 0.06 m at
// 0.1 m/s once the blade is up.
TEST(DigLoadTest, LiftDigIsTable1ThenALift) {
  const Scene lift = LoadScene(kSourceDir + "/scenes/lift_dig.yaml");
  const Scene tiny = LoadScene(kSourceDir + "/scenes/tiny_dig.yaml");
  TrajectorySpec expected = Table1Preset();
  ASSERT_EQ(expected.moves[2].name, "linear");
  expected.moves[2].amount = 0.05;  // tiny_dig's overrides: the box is 0.37 m long
  ASSERT_EQ(expected.moves[3].name, "rotation2");
  expected.moves[3].start = 3.2;
  expected.moves.push_back(Translate("lift", {0, 0, 1}, 0.1, 0.06));
  const TrajectorySpec& t = lift.dig.trajectory;
  EXPECT_EQ(t.initial_pitch, expected.initial_pitch);
  EXPECT_EQ(lift.dig.heading, tiny.dig.heading);
  EXPECT_EQ(t.pivot_start.x, tiny.dig.trajectory.pivot_start.x);
  EXPECT_EQ(t.pivot_start.y, tiny.dig.trajectory.pivot_start.y);
  ASSERT_EQ(t.moves.size(), expected.moves.size());
  for (size_t i = 0; i < t.moves.size(); ++i) {
    SCOPED_TRACE(expected.moves[i].name);
    const Move& m = t.moves[i];
    const Move& e = expected.moves[i];
    EXPECT_EQ(m.kind, e.kind);
    EXPECT_EQ(m.axis.x, e.axis.x);
    EXPECT_EQ(m.axis.y, e.axis.y);
    EXPECT_EQ(m.axis.z, e.axis.z);
    EXPECT_EQ(m.speed, e.speed);  // deg -> rad as the preset computes it: exactly equal
    EXPECT_EQ(m.amount, e.amount);
    EXPECT_EQ(m.start, e.start);
    EXPECT_EQ(m.about_pivot, e.about_pivot);
    if (i < tiny.dig.trajectory.moves.size()) {
      EXPECT_EQ(m.speed, tiny.dig.trajectory.moves[i].speed);
      EXPECT_EQ(m.amount, tiny.dig.trajectory.moves[i].amount);
      EXPECT_EQ(m.start, tiny.dig.trajectory.moves[i].start);
    }
  }
  // The lift runs from the end of the tilt (4.2 s) to 4.8 s and raises the pivot 0.06 m.
  const Trajectory path(t);
  EXPECT_NEAR(path.end_time(), 4.8, 1e-12);
  EXPECT_NEAR(path.At(4.8).pivot.z - path.At(4.2).pivot.z, 0.06, 1e-12);
}

}  // namespace
}  // namespace sim

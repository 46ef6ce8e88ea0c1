// Scenes: YAML files in SI units, validated in full at load. Every error names the file, the line,
// the key and what was expected: "scenes/x.yaml:12: bed.radius: expected a number > 0, got -1".
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "dem/bond.h"
#include "dem/clump.h"
#include "dem/material.h"
#include "dem/mesh.h"
#include "dem/system.h"
#include "dem/vec3.h"
#include "sim/input/input_error.h"
#include "sim/input/trajectory.h"

namespace arm {
struct ArmModel;  // arm/arm_model.h: sim keeps it behind a pointer (no Eigen in this header)
}

namespace sim {

// How a bond's strengths (tensile_strength and the shear strength's cohesion; not its friction
// angle, not its stiffness) grow or fall with the depth d [m] of its contact point below the
// bed's free surface (key bed.bonds.strength_vs_depth): f(d) multiplies them
// (BondStrengthFactor). d < 0 (a point above
// the measured surface, a grain standing proud) is taken as 0.
struct StrengthVsDepth {
  enum class Law { kConstant, kLinear, kExponential, kTable };
  Law law = Law::kConstant;    // constant: f = 1
  double slope = 0;            // linear: f = max(0, 1 + slope d) [1/m]; f = 0: no bond
  double length = 0;           // exponential: f = exp(d / length) [m], length != 0 (< 0 weakens)
  std::vector<double> depth;   // table: points (depth [m] ascending, f >= 0), linear between,
  std::vector<double> factor;  //   held beyond the ends
};

// Breakable bonds made between the bed's spheres when a settled bed is loaded (key bed.bonds;
// dem/bond.h, the parallel bond of Potyondy and Cundall 2004). Absent: an unbonded bed.
struct BondSpec {
  bool enabled = false;
  double gap = 0;          // spheres whose surfaces are closer than this are bonded [m]
  dem::BondParams params;  // strengths before the depth factor; SI (friction angle in rad)
  StrengthVsDepth strength_vs_depth;
};

// f(d) of `law` at depth `depth` [m] below the bed's surface (d < 0 taken as 0) [-].
double BondStrengthFactor(const StrengthVsDepth& law, double depth);

// How the bed is made (fill + settle) or where a saved one is loaded from.
struct BedSpec {
  std::string material;               // particle material name (key bed.material)
  double radius_min = 0;              // [m] radii are uniform in [radius_min, radius_max]
  double radius_max = 0;              // [m] (bed.radius: r sets both; bed.radius: [a, b] a range);
                                      // clumps: their smallest sphere and their bounding radius
  int64_t count = 0;                  // number of particles (spheres, or clumps with bed.clump)
  std::string clump;                  // bed.clump: a template name; the bed is made of these rigid
                                      // clumps (dem/clump.h) instead of spheres; "" = spheres
  dem::ClumpTemplate clump_template;  // that template (built in, or from clump_templates)
  double clump_volume = 0;            // [m^3] of one clump (the union of its spheres)
  uint64_t seed = 1;                  // insertion RNG seed
  double fill_fraction = 0.35;        // solid fraction of the random insertion layers [-]
  double settle_ke = 1e-9;            // settled when mean kinetic energy per particle < this [J]
  double settle_max_time = 5.0;       // give up settling after this simulated time [s]
  std::string file;                   // saved bed to load instead of making one (path as written,
                                      // resolved against the scene's folder); "" = make one
  double settled_height = 0;          // [m] derived: height of the bed once settled, estimated
                                      // at a solid fraction of 0.59 (LoadScene's box check)
  BondSpec bonds;                     // bed.bonds: bonds made when the settled bed is loaded
};

struct OutputSpec {
  double interval = 1e-3;       // time between rows of the time series [s]
  int64_t snapshot_every = 0;   // particle snapshot every N steps; 0 = none
  double flush_seconds = 10.0;  // wall-clock flush period [s]
};

// The scoop: a triangle mesh in the l_scoop frame, its mass properties and the cavity that holds
// the collected sample.
struct ScoopSpec {
  std::string mesh;            // mesh file (any format assimp reads), resolved against the scene
  double scale = 1.0;          // mesh units -> m
  dem::TriangleMesh geometry;  // that file as LoadScene read it (sim::LoadMesh at `scale`): SI,
                               // l_scoop frame, name "scoop", material = material_index
  std::string material;        // scoop material (key dig.scoop.material)
  int material_index = -1;
  // The particles' rolling-friction couples count in the scoop's torque (as EDEM's option; off
  // by default, as EDEM's default). Key dig.scoop.rolling_torque.
  bool rolling_torque = false;
  double mass = 0.30936;                   // [kg] (FACTS.md section 2, l_scoop)
  dem::Vec3 com{0.001315, 0.0, 0.045328};  // centre of mass in l_scoop [m]
  double density = 0;  // > 0: `mass` and `com` were computed by LoadScene from the (closed)
                       // mesh at this density [kg/m^3] (dem::ComputeMassProperties); 0: as given
  // Box of the l_scoop frame whose particles count as collected at the end of a pass [m]:
  // between the back plate, the blade, the side plates, the lid and the bottom (FACTS.md 3).
  dem::Vec3 cavity_min{-0.031, -0.0399, 0.0015};
  dem::Vec3 cavity_max{0.094, 0.0399, 0.0755};
};

// A dig of `passes` passes; pass p cuts to p * bite_depth below the original surface (the
// lowest point of the level scoop during the linear segment).
struct DigSpec {
  bool enabled = false;
  ScoopSpec scoop;
  std::string preset = "none";  // trajectory preset the keys below override: table1, table4, none
  TrajectorySpec trajectory;    // pivot_start.z is set per pass at run time
  double heading = 0;           // trench direction: rotation about world z from +x [rad]
  int passes = 1;
  double bite_depth = 0.015;   // [m]
  double surface = 0;          // world z of the original surface [m] (when surface_given)
  bool surface_given = false;  // else measured from the settled bed
  double interval = 1e-3;      // time between rows of /scoop/ [s]
  bool start_buried = false;   // place the tool at its start pose in the bed (particles it
                               // overlaps removed) instead of lowering it from clear of the bed
};
// Frames (key `render:`, optional): camera, colouring and size of the OSMesa frames written by
// `scoopsim run --frames DIR`. Plain data: sim knows nothing of render/, which reads this.
struct RenderSpec {
  std::string camera_preset = "trench_oblique";  // one of kRenderCameraPresets; "" = explicit
  dem::Vec3 camera_position, camera_target;      // explicit camera [m] (camera: {position, ...})
  double fov_deg = 35;                           // vertical field of view [deg], in (0, 180)
  std::string color_by = "speed";                // speed | depth | material | force |
                                                 // broken_bonds
  int width = 1280, height = 720;                // [px], each in [16, 4096]
  double every = 0;  // [s] between frames; 0: 0.05 s in a dig, else output.interval
};
// Camera presets a scene may name (render/camera.cpp frames each; a render test checks both
// lists agree).
inline const char* const kRenderCameraPresets[] = {"trench_side", "trench_oblique", "top", "arm",
                                                   "scoop"};

// A fixed rigid sphere in the bed (key `obstacles:`, a buried boulder). The particles meet it as
// a fixed triangle mesh (World::StartDig takes out the particles it overlaps); a scoop held by the
// arm meets it as a rigid sphere (sim/loop/arm_driver.h); a kinematic scoop passes through it.
struct ObstacleSpec {
  dem::Vec3 center;      // [m], world
  double radius = 0;     // [m]
  std::string material;  // DEM material of its surface (default: box.wall_material)
  int material_index = -1;
  double stiffness = 2e6;  // scoop-sphere contact stiffness [N/m] (linear penalty)
};

// When the arm (Bullet) and the DEM exchange pose and wrench (docs/arm.md, "The arm in the
// loop"). kBulletFirst: Bullet steps first with the wrench of the last DEM step, so the DEM gets
// the pose at the end of its coming step. kDemFirst: the DEM steps first with the pose Bullet
// had at the start of the step (a one-step lag), then Bullet steps with that step's wrench.
enum class CouplingTiming { kBulletFirst, kDemFirst };
// What the arm does on a fault (torque, position and force/torque limits): arm::Reaction.
enum class ArmReaction { kContinue, kStop, kRetract };

// The arm that holds the scoop (key `arm:`; sim/loop/arm_driver.h). Angles in rad, SI units.
struct ArmSpec {
  bool enabled = false;
  std::string urdf;                            // resolved against the scene's folder
  std::shared_ptr<const arm::ArmModel> model;  // the URDF as LoadScene read it (its efforts)
  // base_link in the DEM world: given (base.position, base.yaw), or placed at the first pass so
  // that the base-frame point (reach x, reach y, -base_height) lies under the path's start pivot
  // on the bed's surface, base yaw = the dig's heading (the lander's ground plane is 0.172 m
  // below base_link, FACTS.md section 2).
  bool base_given = false;
  dem::Vec3 base_position;
  double base_yaw = 0;
  double reach_x = 1.55, reach_y = 0.175;    // [m], base frame
  double base_height = 0.172;                // [m]
  std::vector<double> initial;               // IK seed for the path's first pose (dof entries)
  std::vector<std::array<double, 3>> gains;  // p, i, d per joint (default: the lander's)
  // Effort-limit factor per joint, in (0, 1] (1: as the URDF): the arm saturates and faults at
  // model effort x derate (arm::Derated), /arm/effort_limit holds the URDF's, /arm/effort_derate
  // this.
  std::vector<double> derate;
  int substeps = 1;  // DEM steps per Bullet step (averaged wrench)
  CouplingTiming timing = CouplingTiming::kBulletFirst;
  // The PID's D term (arm/controller.h): implicit (stable at any step; the default with
  // arm.wrench: table) or explicit (the default coupled to the DEM).
  bool implicit_d = false;
  // The table-driven arm's Bullet step [s] (arm.step); 0: substeps x time_step, as coupled.
  double step = 0;
  double velocity_margin = 0.9;  // the path is slowed until every joint stays below this
                                 // fraction of its velocity limit
  // Fault rules (arm/fault_monitor.h) and the reaction to torque, position and F/T limits.
  double hold_time = 0.1;     // JOINT_TORQUE_LIMIT hold time [s]
  double force_limit = 200;   // [N]
  double torque_limit = 100;  // [N m]
  std::string sensor_joint = "j_dist_pitch";
  double sensor_rate = 200;  // F/T sensor samples per second [1/s]
  ArmReaction reaction = ArmReaction::kStop;
  double stop_hold = 0.25;               // a stopped pass ends this long after the stop [s]
  dem::Vec3 retract_direction{0, 0, 1};  // world, unit
  double retract_distance = 0.05;        // [m]
  double retract_speed = 0.02;           // [m/s]
  // Where the scoop's wrench comes from: the DEM (arm.wrench: dem, the default) or a wrench table
  // (arm.wrench: table, arm.table: TABLE.h5): no bed at all, see sim/loop/table_arm.h.
  bool table_driven = false;
  std::string table;  // the table file, resolved against the scene's folder
};

struct Scene {
  std::string path;       // the scene file as given
  std::string yaml_text;  // its full text (stored as the HDF5 attribute scene_yaml)
  std::string materials_path;
  dem::MaterialTable materials;
  dem::Vec3 gravity{0, 0, -9.81};  // [m/s^2]
  double rayleigh_fraction = 0.2;  // dt / t_R, in (0, 0.3]
  double time_step = 0;            // [s] derived: rayleigh_fraction * t_R(smallest radius), or
                                   // bond_time_step when that is smaller
  double contact_time_step = 0;    // [s] derived: rayleigh_fraction * t_R(smallest radius)
  double bond_time_step = 0;       // [s] derived: dem::BondCriticalStep(smallest radius, its
                                   // density, bed.bonds); 0 without bed.bonds
  double skin = 0;                 // Verlet skin [m]; default 0.25 * smallest diameter (clumps:
                                   // 0.25 * the template's largest sphere diameter)
  bool skin_given = false;         // neighbor.skin was set (else the default above)
  dem::Vec3 box_min, box_max;      // container [m]: floor and four side walls, open top
  std::string wall_material;       // material of the container walls
  BedSpec bed;
  double duration = 0;  // simulated time of `scoopsim run` [s]
  OutputSpec output;
  int threads = 0;  // 0 = all cores (CLI --threads overrides)
  DigSpec dig;
  dem::SleepConfig sleep;     // used while digging (never while settling)
  double max_overlap = 0.05;  // health.max_overlap: overlap / smaller diameter that stops a run
                              // (dem::SystemConfig::max_overlap_fraction)
  std::vector<dem::ClumpTemplate> clump_templates;  // the scene's own (key clump_templates)
  RenderSpec render;
  std::vector<ObstacleSpec> obstacles;  // key obstacles
  ArmSpec arm;                          // key arm
  // Warnings of the load, one line each ("FILE:LINE: KEY: ..."; the CLI prints them): values that
  // are legal but almost surely wrong (zero gravity, a dig surface far above the box, a bare angle
  // that looks like radians: angles are degrees, or "90 deg", "1.5708 rad").
  std::vector<std::string> warnings;
};

// Loads and validates a scene. Throws InputError with one line naming file, line, key, expectation.
// `sets`: the command line's `--set KEY=VALUE` overrides, written into the scene before it is
// checked (and kept in its yaml_text as `# scoopsim --set KEY=VALUE` lines at the end, so the text
// stored with a run holds them); an error about an overridden key names `--set KEY=VALUE` for the
// file and line.
Scene LoadScene(const std::string& path, const std::vector<std::string>& sets = {});
// The same for a scene text that is not (or not yet) a file, such as a sweep's case: `path`
// names it in messages and files named in it are relative to its folder. Applies the overrides
// the text holds.
Scene LoadSceneText(const std::string& path, const std::string& yaml_text);
// `error` reworded to name the override it is about (`--set KEY=VALUE: KEY: expected ...`) when
// its line is one of `sets`' (an error found after LoadScene, sim/loop/preflight.h); else `error`.
InputError NamingSet(const InputError& error, const std::vector<std::string>& sets);

// The 1-based line of the dotted key `key` ("bed.radius", "dig.scoop.scale") in the scene's text,
// or of its nearest parent there; 1 when none. For errors found after LoadScene
// (sim/loop/preflight.h).
int SceneLine(const Scene& scene, const std::string& key);

// A line about the scene's key `key` (a note, not an error): "FILE:LINE: TEXT" at the key's line
// (SceneLine), or "--set KEY=VALUE: TEXT" when an override wrote it.
std::string SceneNote(const Scene& scene, const std::string& key, const std::string& text);

// Refuses a scene with `arm:` for a command that digs kinematically (the scoop follows the dig's
// path exactly: sweeps, the shape, particle-size and Balovnev studies): an InputError at the
// scene's `arm` line naming `command`; an error about an `arm` a --set wrote names the --set.
void RefuseArmScene(const Scene& scene, const std::string& command);

// Refuses (InputError at bed.count) a bed that would not fit the box once settled: bed.count
// spheres or clumps at a solid fraction of ~0.59 must lie below the box's top. LoadScene checks
// it for a bed still to be poured; Preflight for `scoopsim bed` of a scene that names a bed.file
// (a run loads the file, whose own radii and count are checked instead).
void CheckBedFitsTheBox(const Scene& scene);

// Which rule sets the scene's time step: "contact" (rayleigh_fraction x t_R) or "bond"
// (dem::BondCriticalStep, smaller).
const char* TimeStepRule(const Scene& scene);

// The built-in clump templates' names (dem::TetrahedronTemplates), in order.
std::vector<std::string> BuiltinClumpNames();

// `scene` with its bed made of clumps of `t` (the shape study): bed.clump and the quantities
// derived from the bed (radii, time step, default skin) as LoadScene derives them, and bed.count
// set so that the bed holds the same solid volume as the scene's (so it settles to the same
// height); bed.file is cleared.
Scene WithClumpBed(const Scene& scene, const dem::ClumpTemplate& t);

// What the scene text stored in a saved run (sim/files/saved_run.h) says about the world it ran in,
// for a reader that rebuilds views of it. A whole LoadScene is not possible there: the materials
// file and the bed are named relative to a folder that may be gone.
struct StoredScene {
  bool has_box = false;            // the text has box.min and box.max
  dem::Vec3 box_min, box_max;      // container [m]
  bool has_gravity = false;        // the text has gravity
  dem::Vec3 gravity{0, 0, -9.81};  // [m/s^2]
  RenderSpec render;               // the `render:` block; defaults when it has none
};

// Parses `box`, `gravity` and `render` of a stored scene text, each checked as LoadScene checks
// it; other keys are not read. `name` stands for the file in messages ("out.h5:scene_yaml").
// Throws InputError like LoadScene.
StoredScene ParseStoredScene(const std::string& yaml_text, const std::string& name);

// What the scene text stored in a dig's output made before 2026-12-06 says about the wrench table's
// cell it fills (sim/files/wrench_table.h; later outputs of a sweep carry the validated Scene's
// values as attributes). Read with LoadScene's checks and defaults of these keys.
struct StoredDig {
  std::string material;                   // bed.material
  double radius_min = 0, radius_max = 0;  // [m] bed.radius (0 with bed.clump)
  std::string clump;                      // bed.clump, "" = spheres
  double bite_depth = 0;                  // [m] dig.bite_depth, DigSpec's default when not given
};
// Throws InputError (named `name`) for a text without bed.material or a dig, or with a bad value.
StoredDig ParseStoredDig(const std::string& yaml_text, const std::string& name);

// Loads a materials file into `table` (materials and their pair interactions). Throws InputError.
void LoadMaterials(const std::string& path, dem::MaterialTable* table);

}  // namespace sim

// Scene and materials loading (yaml-cpp). Every value is checked here, once, so the rest of the
// program can trust a Scene. Each error is one line:
//   FILE:LINE: KEY: expected WHAT, got WHAT-WAS-THERE
// LINE is 1-based (yaml-cpp marks are 0-based); KEY is the dotted path of the offending value;
// FILE is the path exactly as the user gave it (materials files: joined to the scene's folder).
#include "sim/input/scene.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "arm/arm_model.h"
#include "arm/controller.h"
#include "dem/mesh.h"
#include "sim/input/mesh_io.h"
#include "sim/input/yaml_input.h"

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxRayleighFraction = 0.3;  // DEM practice: dt in 0.2..0.3 t_R (paper eq. 4)
// The arm's Bullet step [s] (arm.substeps x time_step, or arm.step). With the PID's D term
// explicit, below its bound (dt < 2 I / d, ~1.2e-4 s on j_scoop_yaw). Implicit: on a wrench table
// at most the lander's own control step, 400 Hz (the P term stays explicit, stable to dt < 2 /
// omega: several times that on the lander's arm); coupled to the DEM still 1e-4 s, where the
// one-step lag of the wrench against the stiff scoop-bed contact, not the PID, is the bound
// (journal sections 8 and 13: k dt = 7.4e-5 s already gave transients).
constexpr double kMaxArmStepExplicitD = 1e-4;
constexpr double kMaxArmStepImplicitD = 2.5e-3;
// The solid fraction of a settled bed, for the height of a bed still to be poured.
constexpr double kSettledSolidFraction = 0.59;

// A double with 6 significant digits, for messages.
std::string Num(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

// A whole number held in a double, for messages.
std::string Int(double v) {
  // A double past long long's range would overflow the cast (undefined behaviour).
  return std::fabs(v) < 9e18 ? std::to_string(static_cast<long long>(v)) : Num(v);
}

using yaml_input::LineOf;

using yaml_input::Describe;
using yaml_input::ResolveAgainst;

std::string Join(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? sep : "") + items[i];
  return out;
}

// The one place an InputError about a file's content is made.
[[noreturn]] void Fail(const std::string& file, int line, const std::string& key,
                       const std::string& expected, const std::string& got,
                       const std::string& note = "") {
  throw InputError(file, line, key, expected, got, note);
}

std::string InputErrorMessage(const std::string& file, int line, const std::string& key,
                              const std::string& expected, const std::string& got,
                              const std::string& note) {
  std::string message = file;
  if (line > 0) message += ":" + std::to_string(line);
  message += ": ";
  if (!key.empty()) message += key + ": ";
  message += "expected " + expected + ", got " + got;
  if (!note.empty()) message += " (" + note + ")";
  return message;
}

// Reads the whole file; false when it cannot be opened as a regular file.
bool ReadFile(const std::string& path, std::string* text) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream buffer;
  buffer << in.rdbuf();
  *text = buffer.str();
  return true;
}

// Parses a scene or materials file: one document, syntax errors at their line (yaml_input.h).
YAML::Node Parse(const std::string& file, const std::string& text) {
  return yaml_input::ParseDocument(file, text);
}

// A scene's document with the command line's overrides its text holds (`--set`) written in.
YAML::Node ParseScene(const std::string& file, const std::string& text) {
  YAML::Node root = Parse(file, text);
  yaml_input::ApplySets(&root, yaml_input::SetsOf(text));
  return root;
}

// The scene of a text with its overrides, checked (LoadSceneText names the override an error is
// about).
Scene ReadScene(const std::string& path, const std::string& yaml_text);

// A YAML map being read: rejects unknown keys up front and gives typed, range-checked values
// addressed by their dotted path.
class MapReader {
 public:
  // `path` is the dotted path of the map itself ("" for the document root).
  MapReader(const std::string& file, const YAML::Node& node, std::string path,
            std::initializer_list<const char*> allowed)
      : file_(file), node_(node), path_(std::move(path)) {
    for (const char* key : allowed) allowed_.emplace_back(key);
    if (!node_.IsMap()) {
      Fail(file_, LineOf(node_), path_.empty() ? "(top level)" : path_,
           "a map with keys " + Join(allowed_), Describe(node_));
    }
    yaml_input::RefuseDuplicateKeys(file_, node_, path_);
    for (auto it = node_.begin(); it != node_.end(); ++it) {
      const YAML::Node key_node = it->first;
      if (!key_node.IsScalar()) {
        Fail(file_, LineOf(key_node), path_.empty() ? "(top level)" : path_,
             "plain keys (" + Join(allowed_) + ")", "a key that is " + Describe(key_node));
      }
      const std::string key = key_node.Scalar();
      bool known = false;
      for (const auto& a : allowed_) known = known || a == key;
      if (!known) {
        Fail(file_, LineOf(key_node), Key(key), "one of the keys " + Join(allowed_),
             "an unknown key '" + key + "'");
      }
    }
  }

  bool Has(const char* key) const { return static_cast<bool>(node_[key]); }
  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }
  // Dotted path of a key of this map.
  std::string Key(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  // The value of a required key; a missing key is reported at the line of the map.
  YAML::Node Need(const char* key, const std::string& expected) const {
    const YAML::Node value = node_[key];
    if (!value) Fail(file_, LineOf(node_), Key(key), expected, "nothing (key missing)");
    return value;
  }

  // A finite number satisfying `ok`; `expected` says what `ok` accepts ("a number > 0").
  double Number(const char* key, const std::string& expected,
                const std::function<bool(double)>& ok) const {
    return CheckNumber(Need(key, expected), Key(key), expected, ok);
  }
  double Number(const char* key, double fallback, const std::string& expected,
                const std::function<bool(double)>& ok) const {
    return Has(key) ? Number(key, expected, ok) : fallback;
  }

  // An integer satisfying `ok`.
  int64_t Integer(const char* key, const std::string& expected,
                  const std::function<bool(int64_t)>& ok) const {
    const YAML::Node value = Need(key, expected);
    long long v = 0;
    if (!value.IsScalar() || !YAML::convert<long long>::decode(value, v) || !ok(v)) {
      Fail(file_, LineOf(value), Key(key), expected, Describe(value));
    }
    return v;
  }
  int64_t Integer(const char* key, int64_t fallback, const std::string& expected,
                  const std::function<bool(int64_t)>& ok) const {
    return Has(key) ? Integer(key, expected, ok) : fallback;
  }

  // A non-empty string.
  std::string String(const char* key, const std::string& expected) const {
    const YAML::Node value = Need(key, expected);
    if (!value.IsScalar() || value.Scalar().empty()) {
      Fail(file_, LineOf(value), Key(key), expected, Describe(value));
    }
    return value.Scalar();
  }

  // true or false (YAML's spellings of a boolean).
  bool Bool(const char* key, bool fallback) const {
    if (!Has(key)) return fallback;
    const YAML::Node value = node_[key];
    bool v = false;
    if (!value.IsScalar() || !YAML::convert<bool>::decode(value, v)) {
      Fail(file_, LineOf(value), Key(key), "true or false", Describe(value));
    }
    return v;
  }

  // [x, y, z] of finite numbers.
  dem::Vec3 Vector(const char* key, const std::string& expected) const {
    const YAML::Node value = Need(key, expected);
    if (!value.IsSequence() || value.size() != 3) {
      Fail(file_, LineOf(value), Key(key), expected, Describe(value));
    }
    double c[3];
    for (int i = 0; i < 3; ++i) {
      c[i] = CheckNumber(
          value[i], Key(key), expected, [](double) { return true; }, &value);
    }
    return {c[0], c[1], c[2]};
  }

  // [x, y, z] of finite numbers, not all 0: a direction or an axis.
  dem::Vec3 Direction(const char* key, const std::string& expected) const {
    const dem::Vec3 v = Vector(key, expected);
    if (!(dem::Norm(v) > 0))
      Fail(file_, LineOf(node_[key]), Key(key), expected, Describe(node_[key]));
    return v;
  }

  // An angle (`rate`: an angular rate) in degrees (deg/s), for `ok`'s check and the caller's
  // conversion: a bare number as before, or with its unit, "90 deg", "1.5708 rad" ("5 deg/s",
  // "0.1 rad/s"). A bare number that looks like radians is taken as degrees with a warning
  // (yaml_input.h, LooksLikeRadians).
  double Angle(const char* key, const std::string& expected, const std::function<bool(double)>& ok,
               bool rate = false) const {
    return CheckAngle(Need(key, expected), Key(key), expected, ok, rate);
  }
  double Angle(const char* key, double fallback, const std::string& expected,
               const std::function<bool(double)>& ok, bool rate = false) const {
    return Has(key) ? Angle(key, expected, ok, rate) : fallback;
  }
  double CheckAngle(const YAML::Node& value, const std::string& key, const std::string& expected,
                    const std::function<bool(double)>& ok, bool rate,
                    const YAML::Node* whole = nullptr) const {
    double v = 0;
    if (value.IsScalar() && !YAML::convert<double>::decode(value, v)) {
      if (!yaml_input::ParseAngleWithUnit(value.Scalar(), rate, &v) || !ok(v)) {
        Fail(file_, LineOf(value), key,
             expected + (rate ? ", or with a unit (5 deg/s, 0.1 rad/s)"
                              : ", or with a unit (90 deg, 1.5708 rad)"),
             Describe(whole ? *whole : value));
      }
      return v;
    }
    v = CheckNumber(value, key, expected, ok, whole);
    if (yaml_input::LooksLikeRadians(v)) {
      const std::string unit = rate ? "deg/s" : "deg";
      yaml_input::Warn(file_, LineOf(value),
                       key + ": " + value.Scalar() + " is taken as " + unit +
                           "; if radians were meant, write '" + value.Scalar() + " " +
                           (rate ? "rad/s" : "rad") + "' (or '" + value.Scalar() + " " + unit +
                           "' to keep degrees)");
    }
    return v;
  }

  // Checks a scalar number; errors quote `whole` (the enclosing list) when given.
  double CheckNumber(const YAML::Node& value, const std::string& key, const std::string& expected,
                     const std::function<bool(double)>& ok,
                     const YAML::Node* whole = nullptr) const {
    double v = 0;
    if (!value.IsScalar() || !YAML::convert<double>::decode(value, v) || !std::isfinite(v) ||
        !ok(v)) {
      Fail(file_, LineOf(value), key, expected, Describe(whole ? *whole : value));
    }
    return v;
  }

 private:
  std::string file_;
  YAML::Node node_;
  std::string path_;
  std::vector<std::string> allowed_;
};

bool Positive(double v) { return v > 0; }
bool NonNegative(double v) { return v >= 0; }

// Mean sphere volume of radii uniform in [a, b]: (4/3) pi E[r^3], E[r^3] = (b^4 - a^4) / 4(b - a).
double MeanSphereVolume(double a, double b) {
  const double mean_r3 = b > a ? (b * b * b * b - a * a * a * a) / (4.0 * (b - a)) : a * a * a;
  return 4.0 / 3.0 * kPi * mean_r3;
}

// The keys rolling_model and damping of a map, where present, into `out`.
void ParseContactLaw(const MapReader& m, dem::Interaction* out) {
  if (m.Has("rolling_model")) {
    const char* expected = "edem, cdt or legacy (rolling friction model, dem/contact.h)";
    const std::string name = m.String("rolling_model", expected);
    if (!dem::ParseRollingModel(name, &out->rolling_model))
      Fail(m.file(), LineOf(m.node()["rolling_model"]), m.Key("rolling_model"), expected, name);
  }
  if (m.Has("damping")) {
    const char* expected = "standard or exact_restitution (damping law, dem/contact.h)";
    const std::string name = m.String("damping", expected);
    if (!dem::ParseDampingLaw(name, &out->damping))
      Fail(m.file(), LineOf(m.node()["damping"]), m.Key("damping"), expected, name);
  }
}

void ParseMaterials(const std::string& file, const YAML::Node& root, dem::MaterialTable* table) {
  const MapReader top(file, root, "",
                      {"materials", "interactions", "contact_law", "source", "notes"});

  // Materials: name -> {density, shear_modulus, poisson}.
  const YAML::Node materials =
      top.Need("materials", "a map of material name -> {density, shear_modulus, poisson}");
  if (!materials.IsMap() || materials.size() == 0) {
    Fail(file, LineOf(materials), "materials",
         "a non-empty map of material name -> {density, shear_modulus, poisson}",
         Describe(materials));
  }
  std::vector<std::string> names;
  for (auto it = materials.begin(); it != materials.end(); ++it) {
    const YAML::Node name_node = it->first;
    if (!name_node.IsScalar() || name_node.Scalar().empty()) {
      Fail(file, LineOf(name_node), "materials", "material names", Describe(name_node));
    }
    const std::string name = name_node.Scalar();
    const std::string path = "materials." + name;
    if (table->Find(name) >= 0) {
      Fail(file, LineOf(name_node), path, "each material name once", "a second '" + name + "'");
    }
    const MapReader m(file, it->second, path,
                      {"density", "shear_modulus", "poisson", "source", "notes"});
    dem::Material material;
    material.name = name;
    // Solid grains: osmium, the densest element, is 22590 kg/m^3; a density far below 1 makes
    // the time step (paper eq. 4) vanish and the run never end.
    material.density = m.Number("density", "a number in [1, 1e5] (solid density, kg/m^3)",
                                [](double v) { return v >= 1 && v <= 1e5; });
    material.shear_modulus =
        m.Number("shear_modulus", "a number > 0 (shear modulus G, Pa)", Positive);
    material.poisson = m.Number("poisson", "a number in [0, 0.5) (Poisson's ratio)",
                                [](double v) { return v >= 0 && v < 0.5; });
    table->Add(material);
    names.push_back(name);
  }
  const std::string known = Join(names);

  // Interactions: a list of {pair: [a, b], restitution, friction, rolling_friction}.
  const YAML::Node interactions =
      top.Need("interactions", "a list of {pair: [a, b], restitution, friction, rolling_friction}");
  if (!interactions.IsSequence()) {
    Fail(file, LineOf(interactions), "interactions",
         "a list of {pair: [a, b], restitution, friction, rolling_friction}",
         Describe(interactions));
  }
  // contact_law: {rolling_model, damping}, the choices of every pair that names none itself
  // (dem/contact.h); without it, as the study's code (EDEM): edem rolling, standard damping.
  dem::Interaction law;
  if (top.Has("contact_law")) {
    ParseContactLaw(
        MapReader(file, top.node()["contact_law"], "contact_law", {"rolling_model", "damping"}),
        &law);
  }
  std::map<std::pair<int, int>, int> defined;  // pair -> line of its first definition
  for (size_t i = 0; i < interactions.size(); ++i) {
    const std::string path = "interactions[" + std::to_string(i) + "]";
    const MapReader in(file, interactions[i], path,
                       {"pair", "restitution", "friction", "rolling_friction", "rolling_model",
                        "damping", "source", "notes"});
    const std::string pair_expected = "two material names from materials (" + known + ")";
    const YAML::Node pair = in.Need("pair", pair_expected);
    if (!pair.IsSequence() || pair.size() != 2 || !pair[0].IsScalar() || !pair[1].IsScalar()) {
      Fail(file, LineOf(pair), in.Key("pair"), pair_expected, Describe(pair));
    }
    const int a = table->Find(pair[0].Scalar());
    const int b = table->Find(pair[1].Scalar());
    if (a < 0 || b < 0) Fail(file, LineOf(pair), in.Key("pair"), pair_expected, Describe(pair));
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    const auto [where, inserted] = defined.emplace(key, LineOf(pair));
    if (!inserted) {
      Fail(file, LineOf(pair), in.Key("pair"), "each pair once", Describe(pair) + " again",
           "first at line " + std::to_string(where->second));
    }
    const std::string note = "pair " + Describe(pair);
    dem::Interaction interaction;
    const auto number = [&](const char* k, const std::string& expected,
                            const std::function<bool(double)>& ok) {
      const YAML::Node value = in.Need(k, expected);
      double v = 0;
      if (!value.IsScalar() || !YAML::convert<double>::decode(value, v) || !std::isfinite(v) ||
          !ok(v)) {
        Fail(file, LineOf(value), in.Key(k), expected, Describe(value), note);
      }
      return v;
    };
    interaction.restitution =
        number("restitution", "a number in (0, 1] (coefficient of restitution)",
               [](double v) { return v > 0 && v <= 1; });
    interaction.friction = number("friction", "a number >= 0 (static friction)", NonNegative);
    interaction.rolling_friction =
        number("rolling_friction", "a number >= 0 (rolling friction)", NonNegative);
    // The contact law's choices: the pair's own keys, else the file's contact_law.
    interaction.rolling_model = law.rolling_model;
    interaction.damping = law.damping;
    ParseContactLaw(in, &interaction);
    table->SetInteraction(a, b, interaction);
  }
}

constexpr double kDeg = kPi / 180.0;

// The preset's segments, in the order they run (the keys of dig.trajectory that override them).
const char* const kSegments[] = {"approach", "rotation1", "linear", "rotation2"};

// One move of a preset, by its name (approach, rotation1, linear, rotation2): `off` removes it, a
// map overrides its start, speed and amount (adding it when the preset has none).
// `speed_key`/`amount_key` name the keys (speed/distance in m/s and m, rate/angle in deg/s, deg).
void ParseSegment(const std::string& file, const MapReader& parent, const char* key,
                  const char* speed_key, const char* amount_key, double unit, const Move& shape,
                  std::vector<Move>* moves) {
  if (!parent.Has(key)) return;
  auto it =
      std::find_if(moves->begin(), moves->end(), [&](const Move& m) { return m.name == key; });
  const YAML::Node node = parent.node()[key];
  if (node.IsScalar() && node.Scalar() == "off") {
    if (it != moves->end()) moves->erase(it);
    return;
  }
  const MapReader m(file, node, parent.Key(key), {"start", speed_key, amount_key});
  const bool was = it != moves->end();
  Move seg = was ? *it : shape;
  if (!was) seg.start = 0;
  seg.start = m.Number("start", seg.start, "a number >= 0 (s)", NonNegative);
  if (!was && !m.Has(speed_key)) m.Need(speed_key, "a number > 0");
  if (!was && !m.Has(amount_key)) m.Need(amount_key, "a number > 0");
  if (unit != 1.0) {  // rate and angle
    seg.speed = m.Angle(speed_key, seg.speed / unit, "a number > 0", Positive, true) * unit;
    seg.amount = m.Angle(amount_key, seg.amount / unit, "a number > 0", Positive) * unit;
  } else {
    seg.speed = m.Number(speed_key, seg.speed / unit, "a number > 0", Positive) * unit;
    seg.amount = m.Number(amount_key, seg.amount / unit, "a number > 0", Positive) * unit;
  }
  if (was) {
    *it = seg;
  } else {
    // In the order approach, rotation1, linear, rotation2.
    auto rank = [](const std::string& n) {
      return std::find_if(std::begin(kSegments), std::end(kSegments),
                          [&](const char* o) { return n == o; }) -
             std::begin(kSegments);
    };
    auto at = std::find_if(moves->begin(), moves->end(),
                           [&](const Move& x) { return rank(x.name) > rank(key); });
    moves->insert(at, seg);
  }
}

// Where a move of the trajectory was written, for messages: the YAML node (the move's own map,
// or the preset for a segment the scene left alone), its dotted key, and the YAML keys of the
// move's fields where they differ from Move's names (TrajectoryError::field).
struct MoveSource {
  YAML::Node node;
  std::string key;                            // "dig.trajectory.linear", "...moves[2]"
  std::map<std::string, std::string> fields;  // "axis" -> "rotate", "distance" -> "duration"
};

// `moves:` the whole tool path as a list (sim/input/trajectory.h), each item a map with one of
//   translate: [dx, dy, dz], speed (m/s), distance (m) or duration (s)
//   rotate: [ax, ay, az] (world axis, right hand, before the dig's heading turns the whole
//           path), rate (deg/s), angle (deg), about: [x, y, z] (a point of l_scoop, m;
//           default the trajectory's pivot)
//   hold: duration (s)
// and an optional start (s; default when the previous move ends). Values are checked here with
// their keys; their order and overlap by Trajectory, after.
void ParseMoves(const std::string& file, const YAML::Node& node, std::vector<Move>* moves,
                std::vector<MoveSource>* sources) {
  const std::string list_key = "dig.trajectory.moves";
  const std::string kinds = "one of translate: [dx, dy, dz], rotate: [ax, ay, az], hold: s";
  if (!node.IsSequence() || node.size() == 0)
    Fail(file, LineOf(node), list_key, "a non-empty list of moves, each a map with " + kinds,
         Describe(node));
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node item = node[i];
    const std::string name = "moves[" + std::to_string(i) + "]";
    const std::string key = list_key + "[" + std::to_string(i) + "]";
    std::vector<std::string> given;
    if (item.IsMap())
      for (const char* kind : {"translate", "rotate", "hold"})
        if (item[kind]) given.emplace_back(kind);
    if (given.size() != 1) {
      Fail(file, LineOf(item), key, "a map with " + kinds,
           given.empty() ? Describe(item) : "more than one (" + Join(given) + ")");
    }
    const double start_default = Move::kAfterPrevious;
    const std::string start_expected = "a number >= 0 (s; default: when the previous move ends)";
    MoveSource source{item, key, {}};
    if (given[0] == "translate") {
      const MapReader m(file, item, key, {"translate", "speed", "distance", "duration", "start"});
      const std::string dir_expected =
          "a list of 3 numbers [dx, dy, dz], not all 0 (direction of travel, world)";
      const dem::Vec3 direction = m.Direction("translate", dir_expected);
      const double speed = m.Number("speed", "a number > 0 (m/s)", Positive);
      if (m.Has("distance") && m.Has("duration"))
        Fail(file, LineOf(item["duration"]), m.Key("duration"),
             "either distance (m) or duration (s)", "both");
      double distance = 0;
      if (m.Has("duration")) {
        const double duration = m.Number("duration", "a number >= 0 (s)", NonNegative);
        distance = speed * duration;
        if (!std::isfinite(distance))
          Fail(file, LineOf(item["duration"]), m.Key("duration"),
               "a duration whose distance (speed * duration) is finite",
               Describe(item["duration"]));
        source.fields["distance"] = "duration";
      } else {
        distance = m.Number("distance", "a number >= 0 (m), or duration (s)", NonNegative);
      }
      const double start = m.Number("start", start_default, start_expected, NonNegative);
      moves->push_back(Translate(name, direction, speed, distance, start));
      source.fields["direction"] = "translate";
    } else if (given[0] == "rotate") {
      const MapReader m(file, item, key, {"rotate", "rate", "angle", "about", "start"});
      const std::string axis_expected =
          "a list of 3 numbers [ax, ay, az], not all 0 (axis, world, right hand)";
      const dem::Vec3 axis = m.Direction("rotate", axis_expected);
      const double rate = m.Angle("rate", "a number > 0 (deg/s)", Positive, true) * kDeg;
      const double angle = m.Angle("angle", "a number >= 0 (deg)", NonNegative) * kDeg;
      const double start = m.Number("start", start_default, start_expected, NonNegative);
      if (m.Has("about")) {
        const dem::Vec3 point = m.Vector("about", "a list of 3 numbers [x, y, z] (m, l_scoop)");
        moves->push_back(RotateAbout(name, axis, rate, angle, point, start));
      } else {
        moves->push_back(Rotate(name, axis, rate, angle, start));
      }
      source.fields["axis"] = "rotate";
      source.fields["point"] = "about";
    } else {
      const MapReader m(file, item, key, {"hold", "start"});
      const double duration = m.Number("hold", "a number >= 0 (s)", NonNegative);
      const double start = m.Number("start", start_default, start_expected, NonNegative);
      moves->push_back(Hold(name, duration, start));
      source.fields["duration"] = "hold";
    }
    sources->push_back(source);
  }
}

void ParseDig(const std::string& file, const YAML::Node& node, int bed_material, Scene* scene) {
  DigSpec& dig = scene->dig;
  dig.enabled = true;
  const MapReader d(
      file, node, "dig",
      {"scoop", "trajectory", "passes", "bite_depth", "surface", "interval", "start_buried"});
  // Scoop.
  const YAML::Node scoop_node = d.Need("scoop", "a map with keys mesh, material");
  const MapReader sc(
      file, scoop_node, "dig.scoop",
      {"mesh", "scale", "material", "mass", "com", "density", "cavity", "rolling_torque"});
  ScoopSpec& scoop = dig.scoop;
  scoop.mesh = ResolveAgainst(file, sc.String("mesh", "the path of a mesh file (STL, OBJ, ...)"));
  if (!std::filesystem::exists(scoop.mesh)) {
    Fail(file, LineOf(scoop_node["mesh"]), "dig.scoop.mesh", "the path of a readable mesh file",
         scoop_node["mesh"].Scalar(), "no file " + scoop.mesh);
  }
  scoop.scale = sc.Number("scale", 1.0, "a number > 0 (mesh units to m)", Positive);
  // The mesh itself, read once here (sim/input/mesh_io.h): assimp reads it, it has triangles, its
  // vertices are finite. Its errors name the mesh file; here they name the scene's key.
  try {
    scoop.geometry = LoadMesh(scoop.mesh, scoop.scale);
  } catch (const InputError& e) {
    const std::string key = e.key() == "scale" ? "scale" : "mesh";
    const YAML::Node at = scoop_node[key];
    Fail(file, LineOf(at ? at : scoop_node), "dig.scoop." + key, e.expected(), e.got(),
         "mesh file " + scoop.mesh);
  }
  scoop.geometry.name = "scoop";
  scoop.material = sc.String("material", "a material name");
  scoop.material_index = scene->materials.Find(scoop.material);
  if (scoop.material_index < 0) {
    Fail(file, LineOf(scoop_node["material"]), "dig.scoop.material",
         "a material defined in " + scene->materials_path, scoop.material);
  }
  if (!scene->materials.has_interaction(bed_material, scoop.material_index)) {
    Fail(file, LineOf(scoop_node["material"]), "dig.scoop.material",
         "an interaction for the pair [" + scene->bed.material + ", " + scoop.material + "] in " +
             scene->materials_path,
         "none");
  }
  scoop.rolling_torque = sc.Bool("rolling_torque", scoop.rolling_torque);
  scoop.mass = sc.Number("mass", scoop.mass, "a number > 0 (kg)", Positive);
  if (sc.Has("com")) scoop.com = sc.Vector("com", "a list of 3 numbers [x, y, z] (m, l_scoop)");
  scoop.density = sc.Number("density", 0.0, "a number > 0 (kg/m^3)", Positive);
  if (sc.Has("density") && (sc.Has("mass") || sc.Has("com")))
    Fail(file, LineOf(scoop_node["density"]), "dig.scoop.density",
         "either density (mass properties from the mesh) or mass and com", "both");
  scoop.geometry.material = scoop.material_index;
  if (scoop.density > 0) {
    // Mass and CoM of the solid the mesh bounds (dem/mesh.h), which must be closed.
    try {
      const dem::MassProperties mp = dem::ComputeMassProperties(scoop.geometry, scoop.density);
      scoop.mass = mp.mass;
      scoop.com = mp.center_of_mass;
    } catch (const dem::MeshError& e) {
      // dem names its own fields: density; volume (not closed, or inside out); triangles.
      if (e.field() == "volume") {
        Fail(file, LineOf(scoop_node["density"]), "dig.scoop.density",
             "a closed dig.scoop.mesh to take the mass and com from: " + e.expected(),
             "a mesh that encloses " + e.got(),
             "mesh file " + scoop.mesh + "; or give mass and com instead of density");
      }
      const std::string key = e.field() == "density" ? "density" : "mesh";
      Fail(file, LineOf(scoop_node[key]), "dig.scoop." + key, e.expected(), e.got(),
           "mesh file " + scoop.mesh);
    }
  }
  if (sc.Has("cavity")) {
    const MapReader cav(file, scoop_node["cavity"], "dig.scoop.cavity", {"min", "max"});
    scoop.cavity_min = cav.Vector("min", "a list of 3 numbers [x, y, z] (m, l_scoop)");
    scoop.cavity_max = cav.Vector("max", "a list of 3 numbers [x, y, z] (m, l_scoop)");
    for (int i = 0; i < 3; ++i)
      if (!(scoop.cavity_max[i] > scoop.cavity_min[i]))
        Fail(file, LineOf(scoop_node["cavity"]), "dig.scoop.cavity.max",
             "every component greater than min's", Describe(scoop_node["cavity"]["max"]));
  }

  // Trajectory: a preset, then overrides of its segments or a list of moves that replaces them.
  const YAML::Node traj_node = d.Need("trajectory", "a map with keys preset, start, ...");
  const MapReader tr(file, traj_node, "dig.trajectory",
                     {"preset", "start", "heading", "pivot", "initial_pitch", "approach",
                      "rotation1", "linear", "rotation2", "moves"});
  dig.preset = tr.Has("preset") ? tr.String("preset", "table1, table4 or none") : "none";
  if (dig.preset == "table1") {
    dig.trajectory = Table1Preset();
  } else if (dig.preset == "table4") {
    dig.trajectory = Table4Preset();
  } else if (dig.preset == "none") {
    dig.trajectory = TrajectorySpec{};
  } else {
    Fail(file, LineOf(traj_node["preset"]), "dig.trajectory.preset", "table1, table4 or none",
         dig.preset);
  }
  TrajectorySpec& t = dig.trajectory;
  {
    const std::string expected = "a list of 2 numbers [x, y]: pivot position at t = 0 (m)";
    const YAML::Node st = tr.Need("start", expected);
    if (!st.IsSequence() || st.size() != 2)
      Fail(file, LineOf(st), "dig.trajectory.start", expected, Describe(st));
    t.pivot_start.x = tr.CheckNumber(
        st[0], "dig.trajectory.start", expected, [](double) { return true; }, &st);
    t.pivot_start.y = tr.CheckNumber(
        st[1], "dig.trajectory.start", expected, [](double) { return true; }, &st);
  }
  dig.heading = tr.Angle("heading", 0.0, "a number (deg)", [](double) { return true; }) * kDeg;
  if (tr.Has("pivot"))
    t.pivot_offset = tr.Vector("pivot", "a list of 3 numbers [x, y, z] (m, l_scoop)");
  t.initial_pitch =
      tr.Angle("initial_pitch", t.initial_pitch / kDeg, "a number in [-180, 180] (deg)",
               [](double v) { return v >= -180 && v <= 180; }) *
      kDeg;
  std::vector<MoveSource> sources;  // one per move of t.moves
  if (tr.Has("moves")) {
    for (const char* segment : kSegments) {
      if (tr.Has(segment)) {
        Fail(file, LineOf(traj_node[segment]), tr.Key(segment),
             "no segment override with dig.trajectory.moves (the list is the whole path)",
             "both " + std::string(segment) + " and moves");
      }
    }
    t.moves.clear();
    ParseMoves(file, traj_node["moves"], &t.moves, &sources);
  } else {
    const dem::Vec3 pitch_down{0, -1, 0};
    ParseSegment(file, tr, "approach", "speed", "distance", 1.0,
                 Translate("approach", {0, 0, -1}, 1, 0), &t.moves);
    ParseSegment(file, tr, "rotation1", "rate", "angle", kDeg,
                 Rotate("rotation1", pitch_down, 1, 0), &t.moves);
    ParseSegment(file, tr, "linear", "speed", "distance", 1.0, Translate("linear", {1, 0, 0}, 1, 0),
                 &t.moves);
    ParseSegment(file, tr, "rotation2", "rate", "angle", kDeg,
                 Rotate("rotation2", pitch_down, 1, 0), &t.moves);
    // A segment is reported at its own map when the scene wrote one, else at the preset.
    for (const Move& m : t.moves) {
      const YAML::Node own = traj_node[m.name];
      const YAML::Node preset = traj_node["preset"];
      sources.push_back({own ? own : (preset ? preset : traj_node), tr.Key(m.name), {}});
    }
  }
  if (t.moves.empty())
    Fail(file, LineOf(traj_node), "dig.trajectory", "at least one segment (preset or map)", "none");
  // The whole path by Trajectory's own rules (order and overlap of the starts, among others); its
  // error names the move and field, mapped back to the key that wrote it.
  try {
    const Trajectory check(t);
    (void)check;
  } catch (const TrajectoryError& e) {
    if (e.move() < 0) {
      const std::string key = e.field() == "pivot_offset"  ? "pivot"
                              : e.field() == "pivot_start" ? "start"
                                                           : e.field();
      const YAML::Node at = traj_node[key];
      Fail(file, LineOf(at ? at : traj_node), tr.Key(key), e.expected(), e.got());
    }
    const MoveSource& source = sources.at(static_cast<size_t>(e.move()));
    const auto mapped = source.fields.find(e.field());
    const std::string key = mapped != source.fields.end() ? mapped->second : e.field();
    const YAML::Node at = source.node.IsMap() ? source.node[key] : YAML::Node();
    Fail(file, LineOf(at ? at : source.node), source.key + "." + key, e.expected(), e.got());
  }

  dig.passes = static_cast<int>(d.Integer("passes", 1, "an integer in [1, 100]",
                                          [](int64_t v) { return v >= 1 && v <= 100; }));
  dig.bite_depth = d.Number("bite_depth", dig.bite_depth, "a number >= 0 (m)", NonNegative);
  if (d.Has("surface")) {
    const YAML::Node sf = node["surface"];
    if (!(sf.IsScalar() && sf.Scalar() == "auto")) {
      dig.surface = d.Number("surface", "a number (m) or auto", [](double) { return true; });
      dig.surface_given = true;
    }
  }
  dig.interval = d.Number("interval", dig.interval, "a number > 0 (s)", Positive);
  dig.start_buried = d.Bool("start_buried", dig.start_buried);
}

// Obstacles: fixed rigid spheres in the bed (a buried boulder).
void ParseObstacles(const std::string& file, const YAML::Node& node, const std::string& wall,
                    int bed_material, Scene* scene) {
  const std::string expected = "a list of maps with keys sphere, material, stiffness";
  if (!node.IsSequence() || node.size() == 0)
    Fail(file, LineOf(node), "obstacles", expected, Describe(node));
  for (size_t k = 0; k < node.size(); ++k) {
    const std::string key = "obstacles[" + std::to_string(k) + "]";
    const MapReader m(file, node[k], key, {"sphere", "material", "stiffness"});
    const YAML::Node sphere_node = m.Need("sphere", "a map with keys center, radius");
    const MapReader s(file, sphere_node, key + ".sphere", {"center", "radius"});
    ObstacleSpec o;
    o.center = s.Vector("center", "a list of 3 numbers [x, y, z] (m)");
    o.radius = s.Number("radius", "a number > 0 (m)", Positive);
    o.material = m.Has("material") ? m.String("material", "a material name") : wall;
    o.material_index = scene->materials.Find(o.material);
    const YAML::Node at = m.Has("material") ? node[k]["material"] : node[k];
    if (o.material_index < 0)
      Fail(file, LineOf(at), m.Key("material"), "a material defined in " + scene->materials_path,
           o.material);
    if (!scene->materials.has_interaction(bed_material, o.material_index))
      Fail(file, LineOf(at), m.Key("material"),
           "an interaction for the pair [" + scene->bed.material + ", " + o.material + "] in " +
               scene->materials_path,
           "none");
    o.stiffness = m.Number("stiffness", o.stiffness, "a number > 0 (N/m)", Positive);
    scene->obstacles.push_back(o);
  }
}

// The arm block: the URDF (read and checked here, arm::LoadArmModel), where the base stands,
// gains, derating, coupling and fault rules.
void ParseArm(const std::string& file, const YAML::Node& node, Scene* scene) {
  ArmSpec& a = scene->arm;
  a.enabled = true;
  const MapReader m(file, node, "arm",
                    {"urdf", "base", "initial", "gains", "derate", "substeps", "timing", "d_term",
                     "step", "velocity_margin", "faults", "wrench", "table"});
  const std::string urdf_name =
      m.Has("urdf") ? m.String("urdf", "the path of a URDF file") : "../assets/lander_arm.urdf";
  a.urdf = ResolveAgainst(file, urdf_name);
  const YAML::Node urdf_at = m.Has("urdf") ? node["urdf"] : node;
  auto model = std::make_shared<arm::ArmModel>();
  try {
    *model = arm::LoadArmModel(a.urdf);
  } catch (const arm::ArmModelError& e) {
    Fail(file, LineOf(urdf_at), "arm.urdf", "a URDF the arm builder accepts", e.what());
  }
  const int n = model->dof();
  auto joint_of = [&](const YAML::Node& key_node, const std::string& key) {
    const int j = model->JointIndex(key_node.Scalar());
    if (j < 0) {
      std::vector<std::string> names;
      for (const arm::Joint& joint : model->joints) names.push_back(joint.name);
      Fail(file, LineOf(key_node), key, "a joint of the chain (" + Join(names) + ")",
           key_node.Scalar());
    }
    return j;
  };

  if (m.Has("base")) {
    const MapReader b(file, node["base"], "arm.base", {"position", "yaw", "reach", "height"});
    if (b.Has("position") && (b.Has("reach") || b.Has("height")))
      Fail(file, LineOf(node["base"]), "arm.base",
           "either position (and yaw) or reach and height (placed at the dig)", "both");
    if (b.Has("position")) {
      a.base_given = true;
      a.base_position = b.Vector("position", "a list of 3 numbers [x, y, z] (m, world)");
      a.base_yaw = b.Angle("yaw", 0.0, "a number (deg)", [](double) { return true; }) * kDeg;
    } else if (b.Has("yaw")) {
      Fail(file, LineOf(node["base"]["yaw"]), "arm.base.yaw", "yaw only with arm.base.position",
           Describe(node["base"]["yaw"]), "placed at the dig, the base turns with dig.heading");
    }
    if (b.Has("reach")) {
      const YAML::Node r = node["base"]["reach"];
      const std::string expected = "a list of 2 numbers [x, y] (m, base frame)";
      if (!r.IsSequence() || r.size() != 2)
        Fail(file, LineOf(r), "arm.base.reach", expected, Describe(r));
      a.reach_x = b.CheckNumber(
          r[0], "arm.base.reach", expected, [](double) { return true; }, &r);
      a.reach_y = b.CheckNumber(
          r[1], "arm.base.reach", expected, [](double) { return true; }, &r);
    }
    a.base_height = b.Number("height", a.base_height, "a number (m)", [](double) { return true; });
  }

  a.initial = {0, kPi / 2, -kPi / 2, 0, 0, kPi / 2};  // the lander's pre-dig pose, yaw 0
  a.initial.resize(n, 0.0);
  if (m.Has("initial")) {
    const YAML::Node v = node["initial"];
    const std::string expected = "a list of " + std::to_string(n) + " joint angles (deg)";
    if (!v.IsSequence() || static_cast<int>(v.size()) != n)
      Fail(file, LineOf(v), "arm.initial", expected, Describe(v));
    for (int i = 0; i < n; ++i)
      a.initial[i] = m.CheckAngle(
                         v[i], "arm.initial", expected, [](double) { return true; }, false, &v) *
                     kDeg;
  }

  a.gains.clear();
  for (int i = 0; i < n; ++i) {
    const arm::PidGains g = i < 6 ? arm::kLanderGains[i] : arm::PidGains{};
    a.gains.push_back({g.p, g.i, g.d});
  }
  if (m.Has("gains")) {
    const YAML::Node g = node["gains"];
    if (!g.IsMap()) Fail(file, LineOf(g), "arm.gains", "a map joint: [p, i, d]", Describe(g));
    for (auto it = g.begin(); it != g.end(); ++it) {
      const int j = joint_of(it->first, "arm.gains");
      const std::string key = "arm.gains." + it->first.Scalar();
      const std::string expected = "a list of 3 numbers [p, i, d] >= 0";
      const YAML::Node v = it->second;
      if (!v.IsSequence() || v.size() != 3) Fail(file, LineOf(v), key, expected, Describe(v));
      for (int c = 0; c < 3; ++c)
        a.gains[j][c] = m.CheckNumber(v[c], key, expected, NonNegative, &v);
    }
  } else if (n != 6) {
    Fail(file, LineOf(urdf_at), "arm.gains", "gains for an arm that is not the lander's six joints",
         "none", std::to_string(n) + " joints in " + a.urdf);
  }

  a.derate.assign(n, 1.0);
  if (m.Has("derate")) {
    const YAML::Node d = node["derate"];
    if (!d.IsMap())
      Fail(file, LineOf(d), "arm.derate", "a map joint: factor in (0, 1]", Describe(d));
    for (auto it = d.begin(); it != d.end(); ++it) {
      const int j = joint_of(it->first, "arm.derate");
      a.derate[j] = m.CheckNumber(it->second, "arm.derate." + it->first.Scalar(),
                                  "a number in (0, 1] (fraction of the URDF's effort limit)",
                                  [](double v) { return v > 0 && v <= 1; });
    }
  }
  a.model = model;

  a.substeps = static_cast<int>(m.Integer("substeps", 1, "an integer in [1, 100]",
                                          [](int64_t v) { return v >= 1 && v <= 100; }));
  if (m.Has("timing")) {
    const std::string t = m.String("timing", "bullet_first or dem_first");
    if (t == "bullet_first")
      a.timing = CouplingTiming::kBulletFirst;
    else if (t == "dem_first")
      a.timing = CouplingTiming::kDemFirst;
    else
      Fail(file, LineOf(node["timing"]), "arm.timing", "bullet_first or dem_first", t);
  }
  a.step = m.Number("step", 0.0, "a number > 0 (s)", Positive);
  a.velocity_margin = m.Number("velocity_margin", a.velocity_margin, "a number in (0, 1]",
                               [](double v) { return v > 0 && v <= 1; });

  if (m.Has("faults")) {
    const YAML::Node fn = node["faults"];
    const MapReader f(file, fn, "arm.faults",
                      {"hold_time", "force_limit", "torque_limit", "sensor_joint", "sensor_rate",
                       "reaction", "stop_hold", "retract"});
    a.hold_time = f.Number("hold_time", a.hold_time, "a number >= 0 (s)", NonNegative);
    a.force_limit = f.Number("force_limit", a.force_limit, "a number > 0 (N)", Positive);
    a.torque_limit = f.Number("torque_limit", a.torque_limit, "a number > 0 (N m)", Positive);
    if (f.Has("sensor_joint")) {
      joint_of(fn["sensor_joint"], "arm.faults.sensor_joint");
      a.sensor_joint = fn["sensor_joint"].Scalar();
    }
    a.sensor_rate = f.Number("sensor_rate", a.sensor_rate, "a number > 0 (1/s)", Positive);
    if (f.Has("reaction")) {
      const std::string r = f.String("reaction", "continue, stop or retract");
      if (r == "continue")
        a.reaction = ArmReaction::kContinue;
      else if (r == "stop")
        a.reaction = ArmReaction::kStop;
      else if (r == "retract")
        a.reaction = ArmReaction::kRetract;
      else
        Fail(file, LineOf(fn["reaction"]), "arm.faults.reaction", "continue, stop or retract", r);
    }
    a.stop_hold = f.Number("stop_hold", a.stop_hold, "a number >= 0 (s)", NonNegative);
    if (f.Has("retract")) {
      const MapReader r(file, fn["retract"], "arm.faults.retract",
                        {"direction", "distance", "speed"});
      if (r.Has("direction")) {
        a.retract_direction = r.Direction("direction", "a list of 3 numbers, not all 0 (world)");
        a.retract_direction = (1.0 / dem::Norm(a.retract_direction)) * a.retract_direction;
      }
      a.retract_distance = r.Number("distance", a.retract_distance, "a number > 0 (m)", Positive);
      a.retract_speed = r.Number("speed", a.retract_speed, "a number > 0 (m/s)", Positive);
    }
  } else if (model->JointIndex(a.sensor_joint) < 0) {
    a.sensor_joint.clear();  // another arm without the lander's sensor joint: no F/T monitoring
  }
  // The scoop's wrench: the DEM's (default) or a wrench table's (sim/loop/table_arm.h).
  const std::string wrench = m.Has("wrench") ? m.String("wrench", "dem or table") : "dem";
  if (wrench == "table") {
    a.table_driven = true;
    if (!m.Has("table"))
      Fail(file, LineOf(node), "arm.table",
           "the wrench table file (TABLE.h5) with arm.wrench: table", "nothing");
    a.table = ResolveAgainst(file, m.String("table", "the path of a wrench table (TABLE.h5)"));
    if (!std::filesystem::is_regular_file(a.table))
      Fail(file, LineOf(node["table"]), "arm.table",
           "an existing wrench table (scoopsim table build DIR -o TABLE.h5)", a.table);
  } else if (wrench != "dem") {
    Fail(file, LineOf(node["wrench"]), "arm.wrench", "dem or table", wrench);
  } else if (m.Has("table")) {
    Fail(file, LineOf(node["table"]), "arm.table", "a table only with arm.wrench: table",
         m.String("table", "a path"));
  }
  // The PID's D term: implicit on a table (the step it needs), explicit coupled to the DEM
  // unless asked (journal section 13: the boulder's fault timeline moved with it).
  a.implicit_d = a.table_driven;
  if (m.Has("d_term")) {
    const std::string d = m.String("d_term", "implicit or explicit");
    if (d == "implicit" || d == "explicit")
      a.implicit_d = d == "implicit";
    else
      Fail(file, LineOf(node["d_term"]), "arm.d_term", "implicit or explicit", d);
  }
  if (m.Has("step") && !a.table_driven)
    Fail(file, LineOf(node["step"]), "arm.step",
         "a step only with arm.wrench: table (a coupled arm steps every arm.substeps DEM steps)",
         Num(a.step));
}

void ParseSleep(const std::string& file, const YAML::Node& node, dem::SleepConfig* sleep) {
  const MapReader m(file, node, "sleep",
                    {"enabled", "speed", "wake_speed", "wake_distance", "wake_margin",
                     "check_every", "quiet_checks"});
  sleep->enabled = m.Bool("enabled", true);
  sleep->speed = m.Number("speed", sleep->speed, "a number > 0 (m/s)", Positive);
  sleep->wake_speed = m.Number("wake_speed", sleep->wake_speed, "a number > 0 (m/s)", Positive);
  sleep->wake_distance =
      m.Number("wake_distance", sleep->wake_distance, "a number >= 0 (m)", NonNegative);
  sleep->wake_margin =
      m.Number("wake_margin", sleep->wake_margin, "a number >= 0 (m)", NonNegative);
  sleep->check_every = static_cast<int>(m.Integer("check_every", sleep->check_every,
                                                  "an integer in [1, 100000] (steps)",
                                                  [](int64_t v) { return v >= 1 && v <= 100000; }));
  sleep->quiet_checks =
      static_cast<int>(m.Integer("quiet_checks", sleep->quiet_checks, "an integer in [1, 250]",
                                 [](int64_t v) { return v >= 1 && v <= 250; }));
}

// The `render:` block of a scene (frames of `scoopsim run --frames`, `scoopsim render`).
RenderSpec ParseRender(const std::string& path, const YAML::Node& node) {
  const MapReader r(path, node, "render", {"camera", "color_by", "size", "every"});
  RenderSpec spec;
  std::string presets;
  for (const char* name : kRenderCameraPresets)
    presets += (presets.empty() ? "" : "|") + std::string(name);
  if (r.Has("camera")) {
    const YAML::Node camera = node["camera"];
    const std::string expected =
        "a preset (" + presets + ") or a map {position: [x, y, z], target: [x, y, z], fov: deg}";
    if (camera.IsScalar()) {
      bool known = false;
      for (const char* name : kRenderCameraPresets) known = known || camera.Scalar() == name;
      if (!known) Fail(path, LineOf(camera), "render.camera", expected, Describe(camera));
      spec.camera_preset = camera.Scalar();
    } else {
      const MapReader c(path, camera, "render.camera", {"position", "target", "fov"});
      spec.camera_preset.clear();
      spec.camera_position = c.Vector("position", "a list of 3 numbers [x, y, z] (m)");
      spec.camera_target = c.Vector("target", "a list of 3 numbers [x, y, z] (m)");
      spec.fov_deg = c.Angle("fov", spec.fov_deg, "a number in (0, 180) (deg)",
                             [](double v) { return v > 0 && v < 180; });
      if (dem::Norm(spec.camera_target - spec.camera_position) <= 0) {
        Fail(path, LineOf(camera["target"]), "render.camera.target",
             "a point other than render.camera.position", Describe(camera["target"]));
      }
    }
  }
  if (r.Has("color_by")) {
    const YAML::Node f = node["color_by"];
    const std::string expected = "one of speed, depth, material, force, broken_bonds";
    if (!f.IsScalar() ||
        (f.Scalar() != "speed" && f.Scalar() != "depth" && f.Scalar() != "material" &&
         f.Scalar() != "force" && f.Scalar() != "broken_bonds")) {
      Fail(path, LineOf(f), "render.color_by", expected, Describe(f));
    }
    spec.color_by = f.Scalar();
  }
  if (r.Has("size")) {
    const YAML::Node size = node["size"];
    const std::string expected = "[width, height] in pixels, each an integer in [16, 4096]";
    int wh[2] = {0, 0};
    for (int i = 0; i < 2 && size.IsSequence() && size.size() == 2; ++i) {
      long long v = 0;
      if (size[i].IsScalar() && YAML::convert<long long>::decode(size[i], v) && v >= 16 &&
          v <= 4096) {
        wh[i] = static_cast<int>(v);
      }
    }
    if (wh[0] == 0 || wh[1] == 0) Fail(path, LineOf(size), "render.size", expected, Describe(size));
    spec.width = wh[0];
    spec.height = wh[1];
  }
  spec.every = r.Number("every", spec.every,
                        "a number >= 0 (s; 0: 0.05 in a dig, else output.interval)", NonNegative);
  return spec;
}

// `clump_templates:` a map of name -> {spheres: [[x, y, z, r], ...]} (m, template frame).
std::vector<dem::ClumpTemplate> ParseClumpTemplates(const std::string& file,
                                                    const YAML::Node& node) {
  const std::string expected = "a map of template name -> {spheres: [[x, y, z, r], ...]} (m)";
  if (!node.IsMap() || node.size() == 0)
    Fail(file, LineOf(node), "clump_templates", "a non-empty " + expected, Describe(node));
  std::vector<dem::ClumpTemplate> out;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const YAML::Node name_node = it->first;
    const std::string name = name_node.IsScalar() ? name_node.Scalar() : "";
    if (name.empty())
      Fail(file, LineOf(name_node), "clump_templates", expected, Describe(name_node));
    const std::string path = "clump_templates." + name;
    if (dem::FindBuiltinTemplate(name) != nullptr) {
      Fail(file, LineOf(name_node), path,
           "a name other than the built-in " + Join(BuiltinClumpNames()), "'" + name + "'");
    }
    for (const dem::ClumpTemplate& t : out)
      if (t.name == name)
        Fail(file, LineOf(name_node), path, "each template name once", "a second '" + name + "'");
    const MapReader m(file, it->second, path, {"spheres", "notes"});
    const std::string sphere_expected =
        "a list of spheres [x, y, z, r]: centre in the template frame and radius r > 0 (m)";
    const YAML::Node spheres = m.Need("spheres", sphere_expected);
    if (!spheres.IsSequence() || spheres.size() == 0)
      Fail(file, LineOf(spheres), path + ".spheres", sphere_expected, Describe(spheres));
    dem::ClumpTemplate t;
    t.name = name;
    for (size_t k = 0; k < spheres.size(); ++k) {
      const YAML::Node sp = spheres[k];
      const std::string key = path + ".spheres[" + std::to_string(k) + "]";
      const std::string one = "[x, y, z, r] with r > 0 (m)";
      if (!sp.IsSequence() || sp.size() != 4) Fail(file, LineOf(sp), key, one, Describe(sp));
      double c[4];
      for (int i = 0; i < 4; ++i)
        c[i] = m.CheckNumber(
            sp[i], key, one, [i](double v) { return i < 3 || v > 0; }, &sp);
      t.centers.push_back({c[0], c[1], c[2]});
      t.radii.push_back(c[3]);
    }
    out.push_back(t);
  }
  return out;
}

// Breakable bonds (key bed.bonds; dem/bond.h). Defaults where a key is left out are those of the
// reference's parallel bond: radius_multiplier 1 and stiffness_ratio 2.5 (Potyondy and Cundall
// 2004, the parallel-bond parameters of their Lac du Bonnet granite model: lambda = 1,
// k_n/k_s = 2.5), gap 0 and friction_angle 0 (PFC's linear parallel bond "with inactive
// dashpots and a reference gap of zero corresponds with the parallel-bond model of
// [Potyondy2004]", its friction angle pb_fa defaulting to 0: Itasca, PFC 9 manual, "Linear
// Parallel Bond Model"), damping_ratio 0 (the reference's undamped bond), strength_vs_depth
// constant. The modulus and the two strengths have no default: they are the material.
// `.inf` is accepted for tensile_strength and cohesion alone (bonds that never break).
void ParseBonds(const std::string& file, const YAML::Node& node, BedSpec* bed) {
  const MapReader m(file, node, "bed.bonds",
                    {"gap", "radius_multiplier", "modulus", "stiffness_ratio", "tensile_strength",
                     "shear_strength", "damping_ratio", "strength_vs_depth"});
  BondSpec& b = bed->bonds;
  b.enabled = true;
  dem::BondParams& p = b.params;
  p.stiffness_ratio = 2.5;
  // A strength: a number > 0 [Pa], or .inf (never breaks).
  const auto strength = [&](const MapReader& map, const char* key) {
    const std::string expected = "a number > 0 (Pa), or .inf for a bond that never breaks";
    const YAML::Node v = map.Need(key, expected);
    double x = 0;
    if (v.IsScalar() && YAML::convert<double>::decode(v, x) && std::isinf(x) && x > 0) return x;
    return map.CheckNumber(v, map.Key(key), expected, Positive);
  };
  // The gap is at most the bed's largest radius: bonds join neighbours, not spheres a grain apart.
  b.gap = m.Number("gap", 0.0,
                   "a number in [0, " + Num(bed->radius_max) + "] (m; bed's largest radius)",
                   [&](double v) { return v >= 0 && v <= bed->radius_max; });
  p.radius_multiplier = m.Number("radius_multiplier", 1.0,
                                 "a number in (0, 1] (bond radius / smaller sphere's radius)",
                                 [](double v) { return v > 0 && v <= 1; });
  p.modulus = m.Number("modulus", "a number > 0 (Pa)", Positive);
  p.stiffness_ratio =
      m.Number("stiffness_ratio", p.stiffness_ratio, "a number > 0 (k_n / k_s)", Positive);
  p.tensile_strength = strength(m, "tensile_strength");
  const YAML::Node shear_node =
      m.Need("shear_strength", "a map with keys cohesion (Pa), friction_angle (deg)");
  const MapReader shear(file, shear_node, "bed.bonds.shear_strength",
                        {"cohesion", "friction_angle"});
  p.cohesion = strength(shear, "cohesion");
  p.friction_angle = shear.Angle("friction_angle", 0.0, "a number in [0, 90) (deg)", [](double v) {
    return v >= 0 && v < 90;
  }) * kDeg;
  p.damping_ratio = m.Number("damping_ratio", 0.0, "a number in [0, 1] (of critical)",
                             [](double v) { return v >= 0 && v <= 1; });
  if (!m.Has("strength_vs_depth")) return;
  // constant, or {law: linear, slope}, {law: exponential, length}, {law: table, points}.
  const YAML::Node law_node = node["strength_vs_depth"];
  const std::string key = "bed.bonds.strength_vs_depth";
  const std::string expected =
      "constant, {law: linear, slope: 1/m}, {law: exponential, length: m} or {law: table, "
      "points: [[depth m, factor], ...]}";
  StrengthVsDepth& law = b.strength_vs_depth;
  if (law_node.IsScalar()) {
    if (law_node.Scalar() != "constant")
      Fail(file, LineOf(law_node), key, expected, Describe(law_node));
    return;
  }
  if (!law_node.IsMap() || !law_node["law"] || !law_node["law"].IsScalar())
    Fail(file, LineOf(law_node), key, expected, Describe(law_node));
  const std::string name = law_node["law"].Scalar();
  if (name == "constant") {
    MapReader(file, law_node, key, {"law"});
  } else if (name == "linear") {
    const MapReader l(file, law_node, key, {"law", "slope"});
    law.law = StrengthVsDepth::Law::kLinear;
    law.slope = l.Number("slope", "a number (1/m): f = max(0, 1 + slope x depth)",
                         [](double) { return true; });
  } else if (name == "exponential") {
    const MapReader l(file, law_node, key, {"law", "length"});
    law.law = StrengthVsDepth::Law::kExponential;
    law.length = l.Number("length", "a number != 0 (m): f = exp(depth / length), < 0 weakens",
                          [](double v) { return v != 0; });
  } else if (name == "table") {
    const MapReader l(file, law_node, key, {"law", "points"});
    law.law = StrengthVsDepth::Law::kTable;
    const std::string points_expected =
        "a list of [depth, factor] pairs, depths >= 0 (m) strictly ascending, factors >= 0";
    const YAML::Node points = l.Need("points", points_expected);
    if (!points.IsSequence() || points.size() == 0)
      Fail(file, LineOf(points), l.Key("points"), points_expected, Describe(points));
    for (size_t i = 0; i < points.size(); ++i) {
      const YAML::Node pt = points[i];
      if (!pt.IsSequence() || pt.size() != 2)
        Fail(file, LineOf(pt), l.Key("points"), points_expected, Describe(pt));
      const double d = l.CheckNumber(pt[0], l.Key("points"), points_expected, NonNegative, &pt);
      const double f = l.CheckNumber(pt[1], l.Key("points"), points_expected, NonNegative, &pt);
      if (!law.depth.empty() && !(d > law.depth.back()))
        Fail(file, LineOf(pt), l.Key("points"), points_expected, Describe(pt),
             "depth not above the previous point's");
      law.depth.push_back(d);
      law.factor.push_back(f);
    }
  } else {
    Fail(file, LineOf(law_node["law"]), key + ".law", "constant, linear, exponential or table",
         Describe(law_node["law"]));
  }
}

// The time step (paper eq. 4: a fraction of the Rayleigh time of the smallest sphere, a clump's
// smallest sphere included) and the default skin, from the bed.
void DeriveFromBed(Scene* scene) {
  const BedSpec& bed = scene->bed;
  if (!scene->skin_given) {
    double largest = bed.radius_min;
    for (double r : bed.clump_template.radii) largest = std::max(largest, r);
    scene->skin = 0.5 * (bed.clump.empty() ? bed.radius_min : largest);
  }
  const dem::Material& material = scene->materials[scene->materials.Find(bed.material)];
  scene->contact_time_step =
      scene->rayleigh_fraction * dem::RayleighTimeStep(bed.radius_min, material);
  scene->time_step = scene->contact_time_step;
  // Bonds (issue 44): their springs' critical step at the smallest sphere, when smaller.
  scene->bond_time_step = 0;
  if (bed.bonds.enabled) {
    scene->bond_time_step =
        dem::BondCriticalStep(bed.radius_min, material.density, bed.bonds.params);
    scene->time_step = std::min(scene->time_step, scene->bond_time_step);
  }
}

// Sets the bed's clump template and the radii it implies (smallest sphere, bounding radius).
void SetBedClump(BedSpec* bed, const dem::ClumpTemplate& t) {
  const dem::ClumpShape shape = dem::MakeClumpShape(t);
  bed->clump = t.name;
  bed->clump_template = t;
  bed->clump_volume = shape.volume;
  bed->radius_min = shape.min_radius;
  bed->radius_max = shape.bounding_radius;
}

}  // namespace

InputError::InputError(std::string file, int line, std::string key, std::string expected,
                       std::string got, std::string note)
    : std::runtime_error(InputErrorMessage(file, line, key, expected, got, note)),
      file_(std::move(file)),
      line_(line),
      key_(std::move(key)),
      expected_(std::move(expected)),
      got_(std::move(got)),
      note_(std::move(note)) {}

int SceneLine(const Scene& scene, const std::string& key) {
  YAML::Node node;
  try {
    node = ParseScene(scene.path, scene.yaml_text);
  } catch (const std::exception&) {
    return 1;
  }
  int line = 1;
  for (size_t begin = 0; begin <= key.size() && node.IsMap();) {
    const size_t dot = std::min(key.find('.', begin), key.size());
    // "moves[4]": item 4 of the list `moves`.
    std::string name = key.substr(begin, dot - begin);
    long item = -1;
    const size_t bracket = name.find('[');
    if (bracket != std::string::npos) {
      item = std::strtol(name.c_str() + bracket + 1, nullptr, 10);
      name.resize(bracket);
    }
    YAML::Node child = node[name];
    if (child && item >= 0) {
      if (!child.IsSequence() || static_cast<size_t>(item) >= child.size()) break;
      child.reset(child[static_cast<size_t>(item)]);
    }
    if (!child) break;
    line = LineOf(child);
    node.reset(child);
    begin = dot + 1;
  }
  return line;
}

std::string SceneNote(const Scene& scene, const std::string& key, const std::string& text) {
  const std::string line = scene.path + ":" + std::to_string(SceneLine(scene, key)) + ": " + text;
  return yaml_input::WarningNamingSet(line, scene.path, yaml_input::SetsOf(scene.yaml_text));
}

void RefuseArmScene(const Scene& scene, const std::string& command) {
  if (!scene.arm.enabled) return;
  // At the key's own line (SceneLine gives its value's: the line under it for a block map). The
  // text was read as this scene: it parses.
  int line = 1;
  const YAML::Node root = ParseScene(scene.path, scene.yaml_text);
  for (auto it = root.begin(); it != root.end(); ++it)
    if (it->first.IsScalar() && it->first.Scalar() == "arm") line = LineOf(it->first);
  const InputError error(scene.path, line, "arm",
                         "a scene without an arm (" + command +
                             " digs kinematically: the scoop follows the dig's path exactly)",
                         "an arm", "run a scene with an arm with `scoopsim run`");
  throw NamingSet(error, yaml_input::SetsOf(scene.yaml_text));
}

double BondStrengthFactor(const StrengthVsDepth& law, double depth) {
  const double d = std::max(depth, 0.0);
  switch (law.law) {
    case StrengthVsDepth::Law::kConstant:
      return 1.0;
    case StrengthVsDepth::Law::kLinear:
      return std::max(0.0, 1.0 + law.slope * d);
    case StrengthVsDepth::Law::kExponential:
      return std::exp(d / law.length);
    case StrengthVsDepth::Law::kTable: {
      // Linear between the points, held beyond the ends.
      const std::vector<double>& x = law.depth;
      const std::vector<double>& y = law.factor;
      if (x.empty()) return 1.0;
      if (d <= x.front()) return y.front();
      if (d >= x.back()) return y.back();
      const size_t k = static_cast<size_t>(std::upper_bound(x.begin(), x.end(), d) - x.begin());
      const double u = (d - x[k - 1]) / (x[k] - x[k - 1]);
      return y[k - 1] + u * (y[k] - y[k - 1]);
    }
  }
  return 1.0;
}

const char* TimeStepRule(const Scene& scene) {
  return scene.bond_time_step > 0 && scene.bond_time_step < scene.contact_time_step ? "bond"
                                                                                    : "contact";
}

std::vector<std::string> BuiltinClumpNames() {
  std::vector<std::string> names;
  for (const dem::ClumpTemplate& t : dem::TetrahedronTemplates()) names.push_back(t.name);
  return names;
}

void CheckBedFitsTheBox(const Scene& scene) {
  const BedSpec& spec = scene.bed;
  const dem::Vec3 extent = scene.box_max - scene.box_min;
  if (!(spec.settled_height > extent.z)) return;
  const bool clumps = !spec.clump.empty();
  const double mean_volume =
      clumps ? spec.clump_volume : MeanSphereVolume(spec.radius_min, spec.radius_max);
  const double max_count =
      std::floor(kSettledSolidFraction * extent.x * extent.y * extent.z / mean_volume);
  const std::string what = clumps ? " clumps of bed.clump " + spec.clump
                                  : " spheres of bed.radius " + Num(spec.radius_max) + " m";
  Fail(scene.path, SceneLine(scene, "bed.count"), "bed.count",
       "a bed that fits the box: at most " + Int(max_count) + what + " settle below its " +
           Num(extent.z) + " m height at a solid fraction of ~0.59",
       std::to_string(spec.count),
       "the settled bed would be " + Num(spec.settled_height) +
           " m high; raise box.max z or lower bed.count");
}

Scene WithClumpBed(const Scene& scene, const dem::ClumpTemplate& t) {
  Scene out = scene;
  const BedSpec& bed = scene.bed;
  const double volume =
      bed.clump.empty() ? MeanSphereVolume(bed.radius_min, bed.radius_max) : bed.clump_volume;
  SetBedClump(&out.bed, t);
  out.bed.count = std::max<int64_t>(
      1, std::llround(static_cast<double>(bed.count) * volume / out.bed.clump_volume));
  out.bed.file.clear();
  DeriveFromBed(&out);
  return out;
}

void LoadMaterials(const std::string& path, dem::MaterialTable* table) {
  std::string text;
  if (!ReadFile(path, &text)) throw InputError(path + ": cannot open materials file");
  ParseMaterials(path, Parse(path, text), table);
}

Scene LoadScene(const std::string& path, const std::vector<std::string>& sets) {
  std::string text;
  if (!ReadFile(path, &text)) throw InputError(path + ": cannot open scene file");
  return LoadSceneText(path, yaml_input::TextWithSets(text, sets));
}

InputError NamingSet(const InputError& error, const std::vector<std::string>& sets) {
  const std::string set = yaml_input::SetAt(error.line(), sets);
  if (set.empty()) return error;
  return InputError("--set " + set, 0, error.key(), error.expected(), error.got(), error.note());
}

Scene LoadSceneText(const std::string& path, const std::string& yaml_text) {
  yaml_input::TakeWarnings();  // none left from a load that failed
  const std::vector<std::string> sets = yaml_input::SetsOf(yaml_text);
  try {
    Scene scene = ReadScene(path, yaml_text);
    for (std::string& w : scene.warnings) w = yaml_input::WarningNamingSet(w, path, sets);
    return scene;
  } catch (const InputError& e) {
    throw NamingSet(e, sets);
  }
}

namespace {

Scene ReadScene(const std::string& path, const std::string& yaml_text) {
  Scene scene;
  scene.path = path;
  scene.yaml_text = yaml_text;
  const YAML::Node root = ParseScene(path, scene.yaml_text);
  if (root.IsNull()) Fail(path, 1, "(top level)", "a map of scene keys", "an empty file");
  const MapReader top(path, root, "",
                      {"materials", "gravity", "time_step", "neighbor", "box", "bed", "duration",
                       "output", "threads", "dig", "sleep", "render", "clump_templates", "health",
                       "notes", "obstacles", "arm"});

  // Materials file, relative to the scene's folder.
  const std::string materials_expected = "the path of a readable materials file";
  const std::string materials_name = top.String("materials", materials_expected);
  scene.materials_path = ResolveAgainst(path, materials_name);
  {
    std::string text;
    if (!ReadFile(scene.materials_path, &text)) {
      Fail(path, LineOf(root["materials"]), "materials", materials_expected, materials_name,
           "cannot open " + scene.materials_path);
    }
    ParseMaterials(scene.materials_path, Parse(scene.materials_path, text), &scene.materials);
  }

  scene.gravity = top.Vector("gravity", "a list of 3 numbers [gx, gy, gz] (m/s^2)");

  // Time step as a fraction of the Rayleigh time (paper eq. 4).
  if (top.Has("time_step")) {
    const MapReader ts(path, root["time_step"], "time_step", {"rayleigh_fraction"});
    const YAML::Node f = ts.Need("rayleigh_fraction", "a number in (0, 0.3]");
    double v = 0;
    if (!f.IsScalar() || !YAML::convert<double>::decode(f, v) || !std::isfinite(v) || v <= 0) {
      Fail(path, LineOf(f), ts.Key("rayleigh_fraction"), "a number in (0, 0.3]", Describe(f),
           "dt = rayleigh_fraction * t_R");
    }
    if (v > kMaxRayleighFraction) {
      Fail(path, LineOf(f), ts.Key("rayleigh_fraction"), "a number in (0, 0.3]", Describe(f),
           "time step too large: explicit DEM needs dt <= 0.3 t_R, the Rayleigh time of eq. 4");
    }
    scene.rayleigh_fraction = v;
  }

  // Clump templates of the scene (besides the built-in ones).
  if (top.Has("clump_templates"))
    scene.clump_templates = ParseClumpTemplates(path, root["clump_templates"]);

  // Bed: what to fill the box with: spheres (bed.radius) or clumps of a template (bed.clump).
  const YAML::Node bed_node = top.Need("bed", "a map with keys material, radius, count");
  const MapReader bed(
      path, bed_node, "bed",
      {"material", "radius", "count", "clump", "seed", "fill_fraction", "settle", "file", "bonds"});
  BedSpec& spec = scene.bed;
  spec.material = bed.String("material", "a material name");
  if (bed.Has("clump")) {
    std::vector<std::string> names = BuiltinClumpNames();
    for (const dem::ClumpTemplate& t : scene.clump_templates) names.push_back(t.name);
    const std::string expected = "a clump template (" + Join(names) + ")";
    const std::string name = bed.String("clump", expected);
    const dem::ClumpTemplate* t = dem::FindBuiltinTemplate(name);
    for (const dem::ClumpTemplate& own : scene.clump_templates)
      if (own.name == name) t = &own;
    if (t == nullptr) Fail(path, LineOf(bed_node["clump"]), "bed.clump", expected, name);
    if (bed.Has("radius")) {
      Fail(path, LineOf(bed_node["radius"]), "bed.radius",
           "no bed.radius with bed.clump (the template sets the spheres)",
           Describe(bed_node["radius"]));
    }
    SetBedClump(&spec, *t);
  } else {
    // At least 1 um: below it a cohesionless DEM sphere means nothing, and the time step (paper
    // eq. 4, proportional to the radius) and the box's insertion cells run away.
    const std::string expected =
        "a number >= 1e-6 or a range [rmin, rmax] with 1e-6 <= rmin <= rmax (m)";
    const auto at_least_1um = [](double v) { return v >= 1e-6; };
    const YAML::Node r = bed.Need("radius", expected);
    if (r.IsSequence()) {
      if (r.size() != 2) Fail(path, LineOf(r), "bed.radius", expected, Describe(r));
      spec.radius_min = bed.CheckNumber(r[0], "bed.radius", expected, at_least_1um, &r);
      spec.radius_max = bed.CheckNumber(r[1], "bed.radius", expected, at_least_1um, &r);
      if (spec.radius_min > spec.radius_max) {
        Fail(path, LineOf(r), "bed.radius", expected, Describe(r), "range reversed");
      }
    } else {
      spec.radius_min = spec.radius_max = bed.CheckNumber(r, "bed.radius", expected, at_least_1um);
    }
  }
  spec.count = bed.Integer("count", "an integer > 0", [](int64_t v) { return v > 0; });
  spec.seed = static_cast<uint64_t>(
      bed.Integer("seed", 1, "an integer >= 0", [](int64_t v) { return v >= 0; }));
  spec.fill_fraction = bed.Number("fill_fraction", spec.fill_fraction,
                                  "a number in (0, 0.5] (solid fraction of the loose fill)",
                                  [](double v) { return v > 0 && v <= 0.5; });
  if (bed.Has("settle")) {
    const MapReader settle(path, bed_node["settle"], "bed.settle", {"kinetic_energy", "max_time"});
    spec.settle_ke =
        settle.Number("kinetic_energy", spec.settle_ke, "a number > 0 (J per particle)", Positive);
    spec.settle_max_time =
        settle.Number("max_time", spec.settle_max_time, "a number > 0 (s)", Positive);
  }
  if (bed.Has("file")) {
    spec.file = ResolveAgainst(path, bed.String("file", "the path of a saved bed (.h5)"));
  }
  if (bed.Has("bonds")) ParseBonds(path, bed_node["bonds"], &spec);

  // Container: floor and four side walls.
  const YAML::Node box_node = top.Need("box", "a map with keys min, max, wall_material");
  const MapReader box(path, box_node, "box", {"min", "max", "wall_material"});
  scene.box_min = box.Vector("min", "a list of 3 numbers [x, y, z] (m)");
  scene.box_max = box.Vector("max", "a list of 3 numbers [x, y, z] (m)");
  for (int i = 0; i < 3; ++i) {
    if (!(scene.box_max[i] > scene.box_min[i])) {
      const char* axis = i == 0 ? "x" : (i == 1 ? "y" : "z");
      Fail(path, LineOf(box_node["max"]), "box.max", "every component greater than box.min's",
           Describe(box_node["max"]),
           std::string(axis) + ": max " + Num(scene.box_max[i]) + " <= min " +
               Num(scene.box_min[i]));
    }
  }
  scene.wall_material = box.String("wall_material", "a material name");

  // Materials named by the scene exist, and every pair that can meet has an interaction.
  const int bed_material = scene.materials.Find(spec.material);
  const auto names = [&] {
    std::vector<std::string> all;
    for (int i = 0; i < scene.materials.size(); ++i) all.push_back(scene.materials[i].name);
    return Join(all);
  };
  if (bed_material < 0) {
    Fail(path, LineOf(bed_node["material"]), "bed.material",
         "a material defined in " + scene.materials_path + " (" + names() + ")", spec.material);
  }
  const int wall_material = scene.materials.Find(scene.wall_material);
  if (wall_material < 0) {
    Fail(path, LineOf(box_node["wall_material"]), "box.wall_material",
         "a material defined in " + scene.materials_path + " (" + names() + ")",
         scene.wall_material);
  }
  if (!scene.materials.has_interaction(bed_material, bed_material)) {
    Fail(path, LineOf(bed_node["material"]), "bed.material",
         "an interaction for the pair [" + spec.material + ", " + spec.material + "] in " +
             scene.materials_path,
         "none");
  }
  if (!scene.materials.has_interaction(bed_material, wall_material)) {
    Fail(path, LineOf(box_node["wall_material"]), "box.wall_material",
         "an interaction for the pair [" + spec.material + ", " + scene.wall_material + "] in " +
             scene.materials_path,
         "none");
  }

  // The bed fits the box. The bed is poured in rounds (sim/loop/bed.h), each a loose lattice fill
  // of pitch a = max(cbrt(mean sphere volume / fill_fraction), 2 rmax) above the bed so far
  // (dem/insertion.h), so the box must hold one lattice cell in every direction and the settled
  // bed, at a solid fraction of about 0.59, must lie below the box's top.
  // Clumps are poured as their bounding spheres at a solid fraction of clumps of fill_fraction
  // (sim/loop/bed.cpp): the same pitch with the clump's volume and bounding radius.
  const dem::Vec3 extent = scene.box_max - scene.box_min;
  const bool clumps = !spec.clump.empty();
  const double mean_volume =
      clumps ? spec.clump_volume : MeanSphereVolume(spec.radius_min, spec.radius_max);
  const double pitch =
      std::max(std::cbrt(mean_volume / spec.fill_fraction), 2.0 * spec.radius_max * (1.0 + 1e-9));
  const std::string size =
      "a box of " + Num(extent.x) + " x " + Num(extent.y) + " x " + Num(extent.z) + " m";
  const std::string cell_of =
      std::string(clumps ? "bed.clump" : "bed.radius") + " at bed.fill_fraction";
  if (std::min({extent.x, extent.y, extent.z}) < pitch) {
    Fail(path, LineOf(box_node["max"]), "box.max",
         "a box at least " + Num(pitch) + " m along x, y and z (one insertion cell for " + cell_of +
             ")",
         size);
  }
  // The pour's lattice holds a layer of insertion cells (4 bytes each) and counts them along
  // each axis in int: a layer of at most max(1e8, 4 x bed.count) cells (the neighbour grid's
  // bound) and at most 1e9 cells along any axis. A 1e10 m box overflowed the casts (undefined
  // behaviour) and then the memory.
  const double cells_x = std::floor(extent.x / pitch), cells_y = std::floor(extent.y / pitch);
  const double max_layer = std::max(1e8, 4.0 * static_cast<double>(spec.count));
  if (!(cells_x * cells_y <= max_layer && std::max({cells_x, cells_y, extent.z / pitch}) <= 1e9)) {
    Fail(path, LineOf(box_node["max"]), "box.max",
         "a box of at most " + Num(max_layer) +
             " insertion cells a layer (max(1e8, 4 x bed.count)) and 1e9 along any axis (cells "
             "of " +
             Num(pitch) + " m: " + cell_of + ")",
         size,
         Num(cells_x * cells_y) + " cells a layer, " + Num(std::max(cells_x, cells_y)) +
             " along the floor, " + Num(extent.z / pitch) + " up");
  }
  const double floor_area = extent.x * extent.y;
  spec.settled_height =
      static_cast<double>(spec.count) * mean_volume / (kSettledSolidFraction * floor_area);

  // Neighbour search skin; default a quarter of the smallest diameter (DeriveFromBed).
  if (top.Has("neighbor")) {
    const MapReader neighbor(path, root["neighbor"], "neighbor", {"skin"});
    scene.skin_given = neighbor.Has("skin");
    scene.skin = neighbor.Number("skin", scene.skin, "a number > 0 (m)", Positive);
  }

  scene.duration = top.Number("duration", 0.0, "a number >= 0 (s)", NonNegative);
  if (top.Has("duration") && top.Has("dig")) {
    // A dig runs until its last pass ends; a duration beside it would be ignored.
    Fail(path, LineOf(root["duration"]), "duration",
         "no duration in a scene with a dig (its passes set how long it runs)",
         Describe(root["duration"]), "remove it, or remove dig for a plain run");
  }
  if (top.Has("output")) {
    const MapReader out(path, root["output"], "output",
                        {"interval", "snapshot_every", "flush_seconds"});
    scene.output.interval =
        out.Number("interval", scene.output.interval, "a number > 0 (s)", Positive);
    scene.output.snapshot_every =
        out.Integer("snapshot_every", scene.output.snapshot_every,
                    "an integer >= 0 (steps; 0 = no snapshots)", [](int64_t v) { return v >= 0; });
    scene.output.flush_seconds =
        out.Number("flush_seconds", scene.output.flush_seconds, "a number > 0 (s)", Positive);
  }
  scene.threads =
      static_cast<int>(top.Integer("threads", 0, "an integer in [0, 4096] (0 = all cores)",
                                   [](int64_t v) { return v >= 0 && v <= 4096; }));

  if (top.Has("dig")) ParseDig(path, root["dig"], bed_material, &scene);
  // A bed still to be poured must fit the box; with bed.file the run loads the file instead
  // (`scoopsim bed` checks it in Preflight), whose radii are then checked against bed.radius.
  if (spec.file.empty()) CheckBedFitsTheBox(scene);
  if (top.Has("sleep")) ParseSleep(path, root["sleep"], &scene.sleep);
  if (top.Has("health")) {
    // The overlap that stops a run as unstable. A clump's small spheres carry the whole clump's
    // mass into their contacts, so they overlap more than a free sphere of their size would.
    const MapReader health(path, root["health"], "health", {"max_overlap"});
    scene.max_overlap = health.Number("max_overlap", scene.max_overlap,
                                      "a number in (0, 0.5] (overlap / smaller diameter)",
                                      [](double v) { return v > 0 && v <= 0.5; });
  }
  // Frames (render/): camera, colouring, size, period.
  if (top.Has("render")) scene.render = ParseRender(path, root["render"]);

  if (top.Has("obstacles"))
    ParseObstacles(path, root["obstacles"], scene.wall_material, bed_material, &scene);
  if (top.Has("arm")) ParseArm(path, root["arm"], &scene);
  if (scene.arm.table_driven && !(scene.dig.enabled && scene.dig.surface_given)) {
    Fail(path, LineOf(root["dig"] ? root["dig"] : root["arm"]["wrench"]), "dig.surface",
         "the bed's surface height as a number (m) with arm.wrench: table (no bed is made)",
         scene.dig.enabled ? "auto" : "no dig: block");
  }

  // Derived time step and default skin.
  DeriveFromBed(&scene);

  // Legal but almost surely wrong: warnings, not refusals.
  if (dem::Dot(scene.gravity, scene.gravity) == 0) {
    yaml_input::Warn(path, LineOf(root["gravity"]),
                     "gravity: [0, 0, 0] m/s^2: nothing will settle and the bed will "
                     "not resist the scoop (the paper's is [0, 0, -1.3])");
  }
  if (scene.dig.surface_given && scene.dig.surface > scene.box_max.z) {
    yaml_input::Warn(path, LineOf(root["dig"]["surface"]),
                     "dig.surface: " + Num(scene.dig.surface) +
                         " m is above the box's open top (box.max z = " + Num(scene.box_max.z) +
                         " m): no bed stands there, the scoop will dig air");
  }
  // The arm's step: below the explicit D term's bound; on a table, at most the lander's control
  // step; coupled, below the wrench lag's bound.
  if (scene.arm.enabled) {
    const bool table_step = scene.arm.table_driven && scene.arm.implicit_d;
    const double limit = table_step ? kMaxArmStepImplicitD : kMaxArmStepExplicitD;
    const char* why = table_step ? "the arm steps at most at the lander's control step, 400 Hz"
                      : scene.arm.implicit_d
                          ? "a coupled arm's wrench lags one Bullet step behind the stiff "
                            "scoop-bed contact: transients above ~4e-5 s"
                          : "the PID's explicit D term is unstable above ~1.2e-4 s on "
                            "j_scoop_yaw (arm.d_term: implicit is not)";
    if (scene.arm.step > limit) {
      Fail(path, LineOf(root["arm"]["step"]), "arm.step",
           "a step <= " + Num(limit) +
               " s (arm.d_term: " + (scene.arm.implicit_d ? "implicit" : "explicit") + ")",
           Num(scene.arm.step), why);
    }
    if (scene.arm.step == 0 && scene.arm.substeps * scene.time_step > limit) {
      Fail(path, LineOf(root["arm"]["substeps"] ? root["arm"]["substeps"] : root["arm"]),
           "arm.substeps",
           "an integer <= " + Int(std::floor(limit / scene.time_step)) +
               " (substeps x time step <= " + Num(limit) + " s)",
           std::to_string(scene.arm.substeps), why);
    }
  }
  // The warnings, in the order found (a bare angle that looks like radians, then the checks'); the
  // CLI prints them (PrintWarnings in tools/main.cpp), once per command, not per load.
  scene.warnings = yaml_input::TakeWarnings();
  return scene;
}

}  // namespace

StoredScene ParseStoredScene(const std::string& yaml_text, const std::string& name) {
  StoredScene stored;
  const YAML::Node root = ParseScene(name, yaml_text);
  if (!root.IsMap()) return stored;
  // Only the keys read here are checked (as LoadScene checks them); the others describe the run,
  // not the world a reader of its file rebuilds, and may come from another version.
  const auto only = [&root, &name](const char* key) {
    YAML::Node map(YAML::NodeType::Map);
    map[key] = root[key];
    return MapReader(name, map, "", {key});
  };
  if (root["box"]) {
    const MapReader box(name, root["box"], "box", {"min", "max", "wall_material"});
    stored.box_min = box.Vector("min", "a list of 3 numbers [x, y, z] (m)");
    stored.box_max = box.Vector("max", "a list of 3 numbers [x, y, z] (m)");
    stored.has_box = true;
  }
  if (root["gravity"]) {
    stored.gravity = only("gravity").Vector("gravity", "a list of 3 numbers [gx, gy, gz] (m/s^2)");
    stored.has_gravity = true;
  }
  if (root["render"]) stored.render = ParseRender(name, root["render"]);
  return stored;
}

StoredDig ParseStoredDig(const std::string& yaml_text, const std::string& name) {
  const YAML::Node root = ParseScene(name, yaml_text);
  if (!root.IsMap() || !root["bed"] || !root["dig"])
    Fail(name, 1, "(top level)", "a scene with a bed and a dig", Describe(root));
  // Only the keys read here are checked; the others may come from another version.
  const auto only = [&](const char* map, std::initializer_list<const char*> keys) {
    YAML::Node subset(YAML::NodeType::Map);
    for (const char* key : keys)
      if (root[map].IsMap() && root[map][key]) subset[key] = root[map][key];
    return MapReader(name, root[map].IsMap() ? subset : root[map], map, keys);
  };
  StoredDig stored;
  const MapReader bed = only("bed", {"material", "radius", "clump"});
  stored.material = bed.String("material", "a material name");
  if (bed.Has("clump")) {
    stored.clump = bed.String("clump", "a clump template name");
  } else {
    const std::string expected = "a number > 0 or a range [rmin, rmax] (m)";
    const YAML::Node r = bed.Need("radius", expected);
    if (r.IsSequence() && r.size() == 2) {
      stored.radius_min = bed.CheckNumber(r[0], "bed.radius", expected, Positive, &r);
      stored.radius_max = bed.CheckNumber(r[1], "bed.radius", expected, Positive, &r);
    } else {
      stored.radius_min = stored.radius_max = bed.CheckNumber(r, "bed.radius", expected, Positive);
    }
  }
  const MapReader dig = only("dig", {"bite_depth"});
  stored.bite_depth =
      dig.Number("bite_depth", DigSpec{}.bite_depth, "a number >= 0 (m)", NonNegative);
  return stored;
}

}  // namespace sim

// Sweeps (sim/studies/sweep.h): the sweep file, the cases' scenes, running and resuming one case,
// the status records, and the plain (one after another) runner. The MPI runner is sweep_mpi.cpp.
#include "sim/studies/sweep.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "sim/files/bed_io.h"
#include "sim/files/checkpoint.h"
#include "sim/files/h5_output.h"
#include "sim/files/internal_h5.h"
#include "sim/files/wrench_table.h"
#include "sim/input/exit_status.h"
#include "sim/input/trajectory.h"
#include "sim/input/yaml_input.h"
#include "sim/loop/preflight.h"
#include "sim/loop/progress.h"
#include "sim/loop/world.h"
#include "sim/studies/internal_sweep.h"

namespace sim {
namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// The sweep file

namespace {

using yaml_input::Describe;
using yaml_input::LineOf;
using yaml_input::ResolveAgainst;

std::string YamlText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  if (node.IsNull()) return "~";
  YAML::Emitter e;
  e << YAML::Flow << node;
  return e.c_str();
}

// The most cases a sweep file may make (the largest shipped, lookup.yaml, has 40).
constexpr int kMaxCases = 100000;

[[noreturn]] void Fail(const std::string& file, const YAML::Node& node, const std::string& key,
                       const std::string& expected, const std::string& got,
                       const std::string& note = "") {
  throw InputError(file, LineOf(node), key, expected, got, note);
}

bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > 100 || name[0] == '.') return false;
  for (char ch : name) {
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '_' || ch == '-'))
      return false;
  }
  return true;
}

// A value's label in a derived case name: its text, characters outside [A-Za-z0-9._-] as '-'.
std::string LabelOf(const std::string& text) {
  std::string label = text;
  for (char& ch : label) {
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '_' || ch == '-'))
      ch = '-';
  }
  return label;
}

// One step of a key path: a map key, optionally indexed into a list ("moves[2]").
struct KeyStep {
  std::string key;
  int index = -1;
};

bool ParseKeyPath(const std::string& path, std::vector<KeyStep>* steps) {
  steps->clear();
  std::stringstream in(path);
  std::string piece;
  while (std::getline(in, piece, '.')) {
    KeyStep s;
    const size_t bracket = piece.find('[');
    s.key = piece.substr(0, bracket);
    if (s.key.empty()) return false;
    for (char ch : s.key)
      if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_')) return false;
    if (bracket != std::string::npos) {
      if (piece.back() != ']' || piece.size() < bracket + 3) return false;
      const std::string digits = piece.substr(bracket + 1, piece.size() - bracket - 2);
      for (char ch : digits)
        if (!std::isdigit(static_cast<unsigned char>(ch))) return false;
      s.index = std::stoi(digits);
    }
    steps->push_back(s);
  }
  return !steps->empty() && path.back() != '.';
}

// One value of a variable.
struct Choice {
  std::string label;
  YAML::Node value;
};
struct Variable {
  std::string key;
  YAML::Node key_node;
  std::vector<Choice> choices;
};

// A case before its scene is made.
struct Draft {
  std::string name;
  int name_line = 0;  // where the name was given (or the first value, for a derived one)
  std::vector<std::pair<std::string, Choice>> settings;  // key path, value
  std::vector<int> key_lines;                            // of each setting's key
};

void CheckKeyPath(const std::string& file, const YAML::Node& key_node, const std::string& key) {
  std::vector<KeyStep> steps;
  if (key != "scene" && !ParseKeyPath(key, &steps)) {
    Fail(file, key_node, key,
         "a scene key path (dotted map keys, [i] for a list entry: dig.trajectory.moves[2].rate) "
         "or `scene`",
         "'" + key + "'");
  }
}

Variable ReadVariable(const std::string& file, const std::string& where, const YAML::Node& key_node,
                      const YAML::Node& values) {
  Variable v;
  v.key = key_node.Scalar();
  v.key_node = key_node;
  CheckKeyPath(file, key_node, v.key);
  const std::string key = where + "." + v.key;
  const std::string expected =
      "a non-empty list of values or a non-empty map of label: value (labels name the cases)";
  if (values.IsSequence()) {
    if (values.size() == 0) Fail(file, values, key, expected, "an empty list");
    for (const YAML::Node& value : values) {
      if (!value.IsScalar()) {
        Fail(file, value, key, "scalar list entries (give other values a label: label: value)",
             Describe(value));
      }
      v.choices.push_back({LabelOf(value.Scalar()), value});
    }
  } else if (values.IsMap()) {
    if (values.size() == 0) Fail(file, values, key, expected, "an empty map");
    for (auto it = values.begin(); it != values.end(); ++it) {
      const std::string label = it->first.as<std::string>();
      if (!ValidName(label)) {
        Fail(file, it->first, key, "labels of letters, digits, '.', '_' and '-'",
             "'" + label + "'");
      }
      v.choices.push_back({label, it->second});
    }
  } else {
    Fail(file, values, key, expected, Describe(values));
  }
  return v;
}

// The cost a case is ordered by: its particles times its planned simulated time (the passes'
// paths, without the descents, which depend on the bed), divided by its time step: particle-
// steps, so that a material of a smaller step counts as the longer run it is.
double Estimate(const Scene& scene) {
  const double spheres =
      static_cast<double>(scene.bed.count) *
      (scene.bed.clump.empty() ? 1.0 : static_cast<double>(scene.bed.clump_template.radii.size()));
  const Trajectory path(scene.dig.trajectory);
  return spheres * scene.dig.passes * std::max(path.end_time() - path.start_time(), 1e-3) /
         scene.time_step;
}

// A setting as the command line's override (`--set KEY=VALUE`, yaml_input.h): the key path with
// "[i]" as ".i", the value on one line (YAML's flow form; a scalar as written).
std::string AsSet(const std::string& key, const YAML::Node& value) {
  std::vector<KeyStep> steps;
  ParseKeyPath(key, &steps);
  std::string path;
  for (const KeyStep& s : steps) {
    path += (path.empty() ? "" : ".") + s.key;
    if (s.index >= 0) path += "." + std::to_string(s.index);
  }
  if (value.IsNull()) return path + "=~";  // removes the key
  YAML::Emitter e;                         // quotes a scalar that would not read back as itself
  e << YAML::Flow << value;
  return path + "=" + e.c_str();
}

// Loads `draft`'s scene: the base scene's text with its settings as `--set` overrides (the
// mechanism of the command line's --set: written into the document before anything is checked),
// loaded whole. A loader error about a varied key is reported at that value's line in the sweep
// file.
SweepCase MakeCase(const std::string& file, const std::string& default_base, const Draft& draft,
                   std::map<std::string, std::string>* base_texts) {
  SweepCase c;
  c.name = draft.name;
  std::string base = default_base;
  for (const auto& [key, choice] : draft.settings) {
    c.settings.push_back({key, YamlText(choice.value), LineOf(choice.value)});
    if (key == "scene") {
      if (!choice.value.IsScalar() || choice.value.Scalar().empty())
        Fail(file, choice.value, "scene", "the path of a scene file", Describe(choice.value));
      base = ResolveAgainst(file, choice.value.Scalar());
    }
  }
  // The base scene, validated on its own first so that its errors point at its own lines.
  if (base_texts->count(base) == 0) {
    try {
      const Scene scene = LoadScene(base);
      RefuseArmScene(scene, "a sweep");
      (*base_texts)[base] = scene.yaml_text;
    } catch (const InputError& e) {
      throw InputError(std::string(e.what()) + " (base scene of the sweep " + file + ")");
    }
  }
  // The case's text: the base's, a comment naming the case, its settings as --set lines. Its
  // lines are the base file's; the overrides' nodes carry lines from yaml_input::kSetLine on.
  // The sweep file is not named: two sweep files that make the same case (lookup_snow.yaml's
  // cases are lookup.yaml's) make the same text, so either finds the other's case done.
  std::string text = base_texts->at(base);
  if (!text.empty() && text.back() != '\n') text += '\n';
  text += "# sweep case " + c.name + " of the base scene " + base + "\n";
  const size_t first_set = yaml_input::SetsOf(text).size();  // the base's own, if any
  std::vector<std::string> sets;  // sets[k]: draft.settings[k]'s ("" for the key `scene`)
  std::vector<std::string> given;
  for (const auto& [key, choice] : draft.settings) {
    sets.push_back(key == "scene" ? "" : AsSet(key, choice.value));
    if (key != "scene") given.push_back(sets.back());
  }
  text = yaml_input::TextWithSets(text, given);
  try {
    c.scene = LoadSceneText(base, text);
    Preflight(&c.scene, Work::kRun);
    RefuseArmScene(c.scene, "a sweep");
  } catch (const InputError& e) {
    // The setting it is about: the override at its line (an error found after the load), the
    // override it names (LoadSceneText's NamingSet), else one whose key is the error's, under
    // it or above it (an unknown key is reported at it).
    const auto under = [](const std::string& a, const std::string& b) {
      return a.size() > b.size() && a.compare(0, b.size(), b) == 0 &&
             (a[b.size()] == '.' || a[b.size()] == '[');
    };
    std::vector<std::string> all(first_set, "");
    all.insert(all.end(), given.begin(), given.end());
    const std::string at_line = yaml_input::SetAt(e.line(), all);
    for (size_t k = 0; k < draft.settings.size(); ++k) {
      const std::string& key = draft.settings[k].first;
      const std::string& got = e.key();
      const bool named =
          !sets[k].empty() && (at_line == sets[k] || e.file() == "--set " + sets[k] ||
                               (e.file() == "--set" && e.got() == "'" + sets[k] + "'"));
      if (named || (!got.empty() && (got == key || under(got, key) || under(key, got)))) {
        throw InputError(
            file, LineOf(draft.settings[k].second.value), got.empty() ? key : got, e.expected(),
            e.got(), "case " + c.name + " of " + base + (e.note().empty() ? "" : "; " + e.note()));
      }
    }
    throw InputError(file, draft.name_line, "case " + c.name,
                     "settings that make a valid scene of " + base, e.what());
  }
  c.scene.path = base;
  if (!c.scene.dig.enabled) {
    throw InputError(file, draft.name_line, "case " + c.name,
                     "a scene with a dig (a sweep's table is made of the scoop's wrench)",
                     "a scene without one");
  }
  c.estimate = Estimate(c.scene);
  return c;
}

}  // namespace

Sweep LoadSweep(const std::string& path) {
  Sweep sweep;
  sweep.path = path;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path + ": expected a sweep file (YAML), got a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open sweep file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const YAML::Node root = yaml_input::ParseDocument(path, buffer.str());
  if (!root.IsMap())
    Fail(path, root, "(top level)", "a map with keys scene, grid, cases", Describe(root));
  yaml_input::RefuseDuplicateKeys(path, root, "");
  for (auto it = root.begin(); it != root.end(); ++it) {
    const std::string key = it->first.as<std::string>();
    if (key != "scene" && key != "grid" && key != "cases" && key != "notes") {
      Fail(path, it->first, key, "one of the keys scene, grid, cases, notes",
           "an unknown key '" + key + "'");
    }
  }
  if (!root["scene"] || !root["scene"].IsScalar())
    Fail(path, root, "scene", "the base scene's path (relative to the sweep file)",
         Describe(root["scene"]));
  const std::string base = ResolveAgainst(path, root["scene"].Scalar());

  std::vector<Draft> drafts;
  // The grid: every combination, the first variable varying slowest.
  if (root["grid"]) {
    const YAML::Node grid = root["grid"];
    if (!grid.IsMap() || grid.size() == 0) {
      Fail(path, grid, "grid", "a non-empty map of key path: values", Describe(grid));
    }
    yaml_input::RefuseDuplicateKeys(path, grid, "grid");
    std::vector<Variable> variables;
    for (auto it = grid.begin(); it != grid.end(); ++it)
      variables.push_back(ReadVariable(path, "grid", it->first, it->second));
    // Counted before they are made: a grid of 1e12 cases died of std::bad_alloc after 23 s.
    double count = 1;
    std::string product;
    for (const Variable& v : variables) {
      count *= static_cast<double>(v.choices.size());
      product += (product.empty() ? "" : " x ") + std::to_string(v.choices.size());
    }
    if (count > kMaxCases) {
      std::ostringstream got;
      got << count << " cases (" << product << " values)";
      Fail(path, grid, "grid", "at most " + std::to_string(kMaxCases) + " cases", got.str());
    }
    std::vector<size_t> at(variables.size(), 0);
    for (;;) {
      Draft d;
      for (size_t k = 0; k < variables.size(); ++k) {
        const Choice& choice = variables[k].choices[at[k]];
        d.name += (k == 0 ? "" : "_") + choice.label;
        d.settings.push_back({variables[k].key, choice});
        d.key_lines.push_back(LineOf(variables[k].key_node));
      }
      d.name_line = LineOf(d.settings.front().second.value);
      drafts.push_back(d);
      size_t k = variables.size();
      while (k > 0 && ++at[k - 1] == variables[k - 1].choices.size()) at[--k] = 0;
      if (k == 0) break;
    }
  }
  // Single cases.
  if (root["cases"]) {
    const YAML::Node cases = root["cases"];
    if (!cases.IsSequence() || cases.size() == 0)
      Fail(path, cases, "cases", "a non-empty list of {name, set}", Describe(cases));
    for (size_t i = 0; i < cases.size(); ++i) {
      const YAML::Node entry = cases[i];
      const std::string where = "cases[" + std::to_string(i) + "]";
      if (!entry.IsMap()) Fail(path, entry, where, "a map with keys name, set", Describe(entry));
      yaml_input::RefuseDuplicateKeys(path, entry, where);
      for (auto it = entry.begin(); it != entry.end(); ++it) {
        const std::string key = it->first.as<std::string>();
        if (key != "name" && key != "set")
          Fail(path, it->first, where + "." + key, "one of the keys name, set",
               "an unknown key '" + key + "'");
      }
      const YAML::Node set = entry["set"];
      if (!set || !set.IsMap() || set.size() == 0) {
        Fail(path, set ? set : entry, where + ".set", "a non-empty map of key path: value",
             Describe(set));
      }
      yaml_input::RefuseDuplicateKeys(path, set, where + ".set");
      Draft d;
      for (auto it = set.begin(); it != set.end(); ++it) {
        const std::string key = it->first.as<std::string>();
        CheckKeyPath(path, it->first, key);
        d.settings.push_back({key, {LabelOf(YamlText(it->second)), it->second}});
        d.key_lines.push_back(LineOf(it->first));
        d.name += (d.name.empty() ? "" : "_") + LabelOf(YamlText(it->second));
      }
      d.name_line = LineOf(set.begin()->second);
      if (entry["name"]) {
        d.name_line = LineOf(entry["name"]);
        if (!entry["name"].IsScalar() || !ValidName(entry["name"].Scalar())) {
          Fail(path, entry["name"], where + ".name",
               "a name of letters, digits, '.', '_' and '-' (a file name)",
               Describe(entry["name"]));
        }
        d.name = entry["name"].Scalar();
      }
      drafts.push_back(d);
    }
  }
  if (drafts.empty()) Fail(path, root, "grid", "a non-empty grid or list of cases", "neither");

  // Names: file names, unique.
  std::map<std::string, int> seen;  // name -> line
  for (const Draft& d : drafts) {
    if (!ValidName(d.name)) {
      throw InputError(
          path, d.name_line, "case name",
          "a name of letters, digits, '.', '_' and '-' (give the case a name, or labels to its "
          "values)",
          "'" + d.name + "'");
    }
    const auto [where, fresh] = seen.emplace(d.name, d.name_line);
    if (!fresh) {
      throw InputError(path, d.name_line, "case name", "unique case names",
                       "a second '" + d.name + "'",
                       "first at line " + std::to_string(where->second));
    }
  }
  std::map<std::string, std::string> base_texts;
  for (const Draft& d : drafts) {
    sweep.cases.push_back(MakeCase(path, base, d, &base_texts));
    sweep.cases.back().index = static_cast<int>(sweep.cases.size()) - 1;
  }
  return sweep;
}

std::string SweepCaseList(const Sweep& sweep, const std::string& dir) {
  std::string text;
  for (const SweepCase& c : sweep.cases) {
    std::string settings;
    for (const SweepSetting& s : c.settings)
      settings += (settings.empty() ? "" : ", ") + s.key + " = " + s.value;
    char cost[32];
    std::snprintf(cost, sizeof cost, "%.3g", c.estimate);
    text += std::to_string(c.index) + "\t" + c.name + "\t" + settings + "\t" + cost;
    if (!dir.empty()) text += "\t" + CaseState(c, dir);
    text += "\n";
  }
  return text;
}

// ---------------------------------------------------------------------------------------------
// Status records

std::string TextHash(const std::string& text) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char ch : text) {
    h ^= ch;
    h *= 1099511628211ull;
  }
  return h5::HexHash(h);
}

CaseStatus ReadCaseStatus(const std::string& path) {
  CaseStatus s;
  std::ifstream in(path);
  if (!in) return s;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    const size_t colon = line.find(": ");
    if (colon == std::string::npos) {
      throw InputError(path, number, "", "'key: value' lines of a case status record",
                       "'" + line + "'");
    }
    const std::string key = line.substr(0, colon);
    const std::string value = line.substr(colon + 2);
    try {
      if (key == "state")
        s.state = value;
      else if (key == "index")
        s.index = std::stoi(value);
      else if (key == "passes")
        s.passes = std::stoi(value);
      else if (key == "passes_done")
        s.passes_done = std::stoi(value);
      else if (key == "surface")
        s.surface = std::stod(value);
      else if (key == "clear_z")
        s.clear_z = std::stod(value);
      else if (key == "scene_hash")
        s.scene_hash = value;
      else if (key == "exit_status")
        s.exit_status = std::stoi(value);
      else if (key == "wall_s")
        s.wall_s = std::stod(value);
      else if (key == "bed_cpu_s")
        s.bed_cpu_s = std::stod(value);
      else if (key == "pass_wall_s")
        s.pass_wall_s = std::stod(value);
      else if (key == "pass_cpu_s")
        s.pass_cpu_s = std::stod(value);
      else if (key == "message")
        s.message = value;
    } catch (const std::exception&) {
      throw InputError(path, number, key, "a number", "'" + value + "'");
    }
  }
  return s;
}

void WriteCaseStatus(const std::string& path, const CaseStatus& s) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    char surface[40], clear_z[40];
    // %.17g: the doubles read back bit for bit (a resumed dig cuts where the first pass did).
    std::snprintf(surface, sizeof surface, "%.17g", s.surface);
    std::snprintf(clear_z, sizeof clear_z, "%.17g", s.clear_z);
    std::string message = s.message;
    std::replace(message.begin(), message.end(), '\n', ' ');
    out << "# scoopsim sweep case status (sim/studies/sweep.h)\n"
        << "state: " << s.state << "\n"
        << "index: " << s.index << "\n"
        << "passes: " << s.passes << "\n"
        << "passes_done: " << s.passes_done << "\n"
        << "surface: " << surface << "\n"
        << "clear_z: " << clear_z << "\n"
        << "scene_hash: " << s.scene_hash << "\n"
        << "exit_status: " << s.exit_status << "\n"
        << "wall_s: " << s.wall_s << "\n"
        << "bed_cpu_s: " << s.bed_cpu_s << "\n"
        << "pass_wall_s: " << s.pass_wall_s << "\n"
        << "pass_cpu_s: " << s.pass_cpu_s << "\n"
        << "message: " << message << "\n";
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  fs::rename(tmp, path);
}

// ---------------------------------------------------------------------------------------------
// One case

namespace sweep {
namespace {

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct CasePaths {
  fs::path h5, status, lock, parts;
  fs::path Bed(int pass) const { return parts / ("bed_" + std::to_string(pass) + ".h5"); }
  fs::path Pass(int pass) const { return parts / ("pass_" + std::to_string(pass) + ".h5"); }
  fs::path Restart(int pass) const {
    return parts / ("pass_" + std::to_string(pass) + ".restart.h5");
  }
  fs::path Pour() const { return parts / "pour.h5"; }
};

CasePaths PathsOf(const SweepCase& c, const std::string& dir) {
  const fs::path cases = fs::path(dir) / "cases";
  return {cases / (c.name + ".h5"), cases / (c.name + ".status"), cases / (c.name + ".lock"),
          cases / (c.name + ".parts")};
}

// Test hook: SCOOPSIM_SWEEP_KILL=<case>:<pass>:<seconds>[:TERM] SIGKILLs the process that many
// simulated seconds into that pass of that case (the uncontrolled stop a resume must survive);
// pass 0 is the pour, killed just after its first keep that many simulated seconds in. With
// :TERM it raises SIGTERM instead (the controlled stop), just after a keep in a pass too.
struct KillHook {
  double after = 0;  // simulated seconds into the pass; 0: no hook for this case and pass
  int signal = SIGKILL;
};
KillHook KillAfter(const SweepCase& c, int pass) {
  KillHook hook;
  const char* text = std::getenv("SCOOPSIM_SWEEP_KILL");
  if (text == nullptr) return hook;
  std::vector<std::string> fields;
  std::stringstream in(text);
  for (std::string field; std::getline(in, field, ':');) fields.push_back(field);
  if (fields.size() < 3 || fields.size() > 4 || fields[0] != c.name ||
      std::atoi(fields[1].c_str()) != pass)
    return hook;
  hook.after = std::atof(fields[2].c_str());
  if (fields.size() == 4 && fields[3] == "TERM") hook.signal = SIGTERM;
  return hook;
}

// The datasets under `group` of a file, recursively, in name order (snapshots left out).
void ListDatasets(const h5::Reader& r, const std::string& group, std::vector<std::string>* out) {
  for (const std::string& name : r.List(group)) {
    const std::string full = (group == "/" ? "/" : group + "/") + name;
    if (full == "/snapshots") continue;
    const hid_t object = H5Oopen(r.file(), full.c_str(), H5P_DEFAULT);
    if (object < 0) r.Fail(full, "cannot be opened");
    const H5I_type_t type = H5Iget_type(object);
    H5Oclose(object);
    if (type == H5I_GROUP)
      ListDatasets(r, full, out);
    else if (type == H5I_DATASET)
      out->push_back(full);
  }
}

herr_t CollectAttributeName(hid_t, const char* name, const H5A_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->push_back(name);
  return 0;
}

// The case's output from its pass files: every series concatenated in pass order, the root
// attributes of the first pass (the dig's: surface, scoop_mesh, ...), the state hash and time of
// the last, the wall and CPU time of each pass and the CPU time of the pour (`bed_cpu_s`).
// Written beside and renamed into place.
void MergeParts(const SweepCase& c, const CasePaths& paths, double bed_cpu_s) {
  const int passes = c.scene.dig.passes;
  const fs::path tmp = paths.parts / "merged.h5";
  {
    H5Output out(tmp.string(), c.scene.yaml_text, SCOOPSIM_VERSION, 1e9);
    double cpu_s = 0;
    for (int pass = 1; pass <= passes; ++pass) {
      const std::string part = paths.Pass(pass).string();
      const h5::Handle file = h5::OpenForReading(part, true);
      const h5::Reader r(part, file.get());
      std::vector<std::string> datasets;
      ListDatasets(r, "/", &datasets);
      for (const std::string& name : datasets) {
        const h5::Handle d(h5::CheckId(H5Dopen2(file.get(), name.c_str(), H5P_DEFAULT), name),
                           H5Dclose);
        const h5::Handle space(H5Dget_space(d.get()), H5Sclose);
        hsize_t dims[2] = {0, 1};
        const int rank = H5Sget_simple_extent_dims(space.get(), dims, nullptr);
        if (rank < 1 || rank > 2) r.Fail(name, "expected a series of rank 1 or 2");
        const hsize_t width = rank == 2 ? dims[1] : 1;
        const h5::Handle type(H5Dget_type(d.get()), H5Tclose);
        if (H5Tget_class(type.get()) == H5T_INTEGER) {  // bit masks (uint64)
          std::vector<uint64_t> values(dims[0] * width);
          if (!values.empty()) {
            h5::CheckOk(
                H5Dread(d.get(), H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
                "H5Dread " + name + " in " + part);
          }
          for (hsize_t row = 0; row < dims[0]; ++row)
            out.AppendRow(name, values.data() + row * width, static_cast<int>(width));
          continue;
        }
        std::vector<double> values(dims[0] * width);
        if (!values.empty()) {
          h5::CheckOk(
              H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
              "H5Dread " + name + " in " + part);
        }
        if (name == "/scoop/pose") {
          out.SetSeriesAttribute(name, "quaternion_order", kQuaternionOrder);
          out.SetSeriesAttribute(name, "columns", kPoseColumns);
        }
        for (hsize_t row = 0; row < dims[0]; ++row)
          out.AppendRow(name, values.data() + row * width, static_cast<int>(width));
      }
      const hid_t root = file.get();
      if (pass == 1) {
        std::vector<std::string> names;
        hsize_t at = 0;
        H5Aiterate2(root, H5_INDEX_NAME, H5_ITER_INC, &at, CollectAttributeName, &names);
        for (const std::string& name : names) {
          if (name == "scene_yaml" || name == "version" || name == "state_hash" ||
              name == "state_hash_u64" || name == "time" || name == "wall_s" || name == "cpu_s")
            continue;
          const h5::Handle a(H5Aopen(root, name.c_str(), H5P_DEFAULT), H5Aclose);
          const h5::Handle type(H5Aget_type(a.get()), H5Tclose);
          const H5T_class_t cls = H5Tget_class(type.get());
          if (cls == H5T_STRING) {
            out.SetAttribute(name, h5::ReadStringAttribute(root, name));
          } else if (cls == H5T_FLOAT) {
            double v = 0;
            H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v);
            out.SetAttribute(name, v);
          } else if (cls == H5T_INTEGER) {  // counts and bit sets (SetCountAttribute)
            uint64_t v = 0;
            H5Aread(a.get(), H5T_NATIVE_UINT64, &v);
            out.SetCountAttribute(name, v);
          }
        }
      }
      const double wall = r.ReadDoubleAttribute("/", "wall_s");
      const double cpu = r.ReadDoubleAttribute("/", "cpu_s");
      out.AppendRow("/sweep/pass_wall_s", &wall, 1);
      out.AppendRow("/sweep/pass_cpu_s", &cpu, 1);
      cpu_s += cpu;
      if (pass == passes) {
        uint64_t hash = 0;
        const h5::Handle a(H5Aopen(root, "state_hash_u64", H5P_DEFAULT), H5Aclose);
        h5::CheckOk(H5Aread(a.get(), H5T_NATIVE_UINT64, &hash), "state_hash_u64 of " + part);
        out.SetStateHash(hash);
        out.SetAttribute("time", r.ReadDoubleAttribute("/", "time"));
      }
    }
    out.SetAttribute("sweep_case", c.name);
    out.SetAttribute("sweep_index", static_cast<double>(c.index));
    out.SetAttribute("sweep_cpu_s", cpu_s);
    out.SetAttribute("sweep_bed_cpu_s", bed_cpu_s);
    WriteTableCell(c.scene, &out);  // the table's cell, from the validated scene
    out.Close();
  }
  PlaceOutput(tmp.string(), paths.h5.string());  // under the output lock (sim/files/h5_output.h)
}

// The status record's message while a case pours its bed, and when the pour ended it (stopped or
// failed); StateOf reads them back.
constexpr const char* kPouring = "making the bed";
constexpr const char* kPourEnded = "the bed";

// Holds an exclusive lock on the case (flock on DIR/cases/<name>.lock) while it runs, so that
// two processes never run one case at once (a job array resubmitted while it still runs).
// With `wait`, waits for the lock (the table's build: two processes that end at once build it
// one after the other).
class CaseLock {
 public:
  explicit CaseLock(const fs::path& path, bool wait = false) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT, 0644);
    if (fd_ < 0) return;
    int rc;
    while ((rc = ::flock(fd_, wait ? LOCK_EX : LOCK_EX | LOCK_NB)) != 0 && errno == EINTR) {
    }
    locked_ = rc == 0;
  }
  ~CaseLock() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock
  }
  bool locked() const { return locked_; }

 private:
  int fd_ = -1;
  bool locked_ = false;
};

}  // namespace

bool CaseDone(const SweepCase& c, const std::string& dir) {
  const CasePaths paths = PathsOf(c, dir);
  try {
    const CaseStatus s = ReadCaseStatus(paths.status.string());
    return s.state == "done" && s.scene_hash == TextHash(c.scene.yaml_text) && fs::exists(paths.h5);
  } catch (const InputError&) {
    return false;
  }
}

std::string StateOf(const SweepCase& c, const std::string& dir) {
  const CasePaths paths = PathsOf(c, dir);
  const CaseStatus s = ReadCaseStatus(paths.status.string());
  if (s.state.empty()) return "not started";
  if (s.scene_hash != TextHash(c.scene.yaml_text)) return "made from another scene text";
  if (s.state == "done") return fs::exists(paths.h5) ? "done" : "done, but its file is missing";
  if (s.state == "failed")
    return "failed (exit " + std::to_string(s.exit_status) + "): " + s.message;
  // Where it stands: the pour (RunCase's records name it so), else the pass after those done.
  char where[160];
  if (s.message == kPouring || s.message == kPourEnded)
    std::snprintf(where, sizeof where, "the pour, %.1f CPU s to its last keep", s.bed_cpu_s);
  else
    std::snprintf(where, sizeof where, "pass %d of %d, %.1f CPU s in it to its last keep",
                  s.passes_done + 1, s.passes, s.pass_cpu_s);
  if (s.state == "running") {
    // Held by a live process, or left by one that was killed (flock dies with its holder).
    if (!CaseLock(paths.lock).locked())
      return std::string("running (another process holds its lock): ") + where;
    return std::string("killed: ") + where + " (the same command goes on from its last keep)";
  }
  if (s.state == "stopped")
    return std::string("stopped: ") + where + " (kept: the same command goes on)";
  return s.state + ": " + where;
}

CaseOutcome RunCase(const Sweep& sweep, const SweepCase& c, const SweepOptions& options,
                    int threads) {
  CaseOutcome outcome;
  const bool quiet = options.quiet;
  const double every = options.checkpoint_every;
  const auto wall0 = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  };
  const CasePaths paths = PathsOf(c, options.dir);
  CaseStatus status;
  const auto record = [&](const std::string& state, int exit_status, const std::string& message) {
    status.state = state;
    status.exit_status = exit_status;
    status.message = message;
    WriteCaseStatus(paths.status.string(), status);
  };
  try {
    fs::create_directories(paths.parts.parent_path());
    CaseLock lock(paths.lock);
    if (!lock.locked()) {
      // Another process runs it (two plain sweeps on one folder, a job array beside a plain
      // sweep): left to that one, whose own end builds the table if its case is the last. Asked
      // for this case alone (--case), this run did not do what it was asked: a failure.
      if (options.only_case < 0) {
        outcome.held = true;
        return outcome;
      }
      Status("scoopsim: sweep: case %s is being run by another process (%s is locked)\n",
             c.name.c_str(), paths.lock.c_str());
      outcome.exit_status = kExitFailure;
      return outcome;
    }
    Scene scene = c.scene;
    scene.output.snapshot_every = 0;  // a case's file holds its series, not the particles
    const int passes = scene.dig.passes;
    const std::string hash = TextHash(scene.yaml_text);

    // Where the case stands: done, some passes done (their beds and rows kept), or not begun.
    status = ReadCaseStatus(paths.status.string());
    if (!status.state.empty() && status.scene_hash != hash) {
      throw InputError(paths.status.string() + ": made from another scene text than case " +
                       c.name + " of " + sweep.path + " now has; remove DIR/cases/" + c.name +
                       ".* or use another output folder");
    }
    if (status.state == "done" && fs::exists(paths.h5)) {
      outcome.skipped = true;
      return outcome;
    }
    int done = status.passes_done;
    if (done > 0 && !(fs::exists(paths.Bed(done)) || done == passes)) done = 0;
    for (int k = 1; k <= done; ++k)
      if (!fs::exists(paths.Pass(k))) done = 0;
    // The next pass goes on from its checkpoint when one of this scene text is there (with the
    // rows it kept); any other is of no use.
    std::unique_ptr<Checkpoint> checkpoint;
    const fs::path restart = paths.Restart(done + 1);
    if (done < passes && fs::exists(restart) && fs::exists(paths.Pass(done + 1))) {
      try {
        auto read = std::make_unique<Checkpoint>(ReadCheckpoint(restart.string()));
        if (read->scene_yaml == scene.yaml_text) checkpoint = std::move(read);
      } catch (const InputError& e) {
        Status("scoopsim: sweep: case %s: %s; pass %d starts again\n", c.name.c_str(), e.what(),
               done + 1);
      }
    }
    if (done == 0) {
      // A fresh start. Kept: a settled bed made from this very scene text (saving is atomic), the
      // pour kept so far (World::Pour checks its scene text) and pass 1's checkpoint and rows.
      const bool keep_bed =
          fs::exists(paths.Bed(0)) && BedSceneYaml(paths.Bed(0).string()) == scene.yaml_text;
      const auto kept = [&](const fs::path& path) {
        if (keep_bed && path == paths.Bed(0)) return true;
        if (!keep_bed && path == paths.Pour()) return true;
        return checkpoint != nullptr && (path == paths.Pass(1) || path == paths.Restart(1));
      };
      if (fs::exists(paths.parts)) {
        for (const auto& entry : fs::directory_iterator(paths.parts))
          if (!kept(entry.path())) fs::remove_all(entry.path());
      }
      fs::remove(paths.h5);
    }
    fs::create_directories(paths.parts);
    status.index = c.index;
    status.passes = passes;
    status.passes_done = done;
    status.scene_hash = hash;
    outcome.first_pass = done + 1;

    // The bed the first pass starts from: the scene's saved bed, or one made now and saved.
    std::string first_bed = scene.bed.file;
    if (first_bed.empty()) {
      first_bed = paths.Bed(0).string();
      if (done == 0 && !fs::exists(first_bed)) {
        // A pour kept by an earlier attempt goes on; its CPU time up to that keep counts.
        PourPoint kept;
        const bool goes_on =
            every > 0 && ReadPourPoint(paths.Pour().string(), scene.yaml_text, &kept);
        const double cpu_before = goes_on ? status.bed_cpu_s : 0.0;
        status.bed_cpu_s = cpu_before;
        record("running", 0, kPouring);
        const double cpu0 = CpuSeconds();
        World world(scene, threads);
        if (every > 0) {
          const KillHook kill = KillAfter(c, 0);
          world.KeepPour(paths.Pour().string(), every, [&] {
            status.bed_cpu_s = cpu_before + (CpuSeconds() - cpu0);
            record("running", 0, kPouring);
            // (Once: the keep written when stopped calls this again, and a second SIGTERM
            // is the user's "now".)
            if (kill.after > 0 && world.system().time() >= kill.after && !StopRequested())
              std::raise(kill.signal);
          });
        }
        SettleReport report;
        const int settled = world.Pour(quiet, &report);
        if (settled != kExitOk) {
          record(settled == kExitStopped ? "stopped" : "failed", settled, kPourEnded);
          outcome.exit_status = settled;
          outcome.wall = elapsed();
          return outcome;
        }
        SaveBed(first_bed, world.system(), scene.yaml_text);
        status.bed_cpu_s = cpu_before + (CpuSeconds() - cpu0);
      }
    }

    // The passes, each in a World of its own from the bed the previous one left (or from its
    // checkpoint).
    for (int pass = done + 1; pass <= passes; ++pass) {
      const bool resumed = pass == done + 1 && checkpoint != nullptr;
      if (!resumed) status.pass_wall_s = status.pass_cpu_s = 0;
      const double wall_before = status.pass_wall_s, cpu_before = status.pass_cpu_s;
      record("running", 0, "pass " + std::to_string(pass));
      const double cpu0 = CpuSeconds();
      const auto pass0 = std::chrono::steady_clock::now();
      const auto pass_wall = [&] {
        return wall_before +
               std::chrono::duration<double>(std::chrono::steady_clock::now() - pass0).count();
      };
      World world(scene, threads);
      std::unique_ptr<H5Output> out;
      if (resumed) {
        const OutputCursor cursor = DecodeCursor(checkpoint->output_state, restart.string());
        out = std::make_unique<H5Output>(paths.Pass(pass).string(), scene.yaml_text,
                                         SCOOPSIM_VERSION, scene.output.flush_seconds, &cursor);
        world.UseOutput(out.get());
        world.ResumeFrom(*checkpoint, MakeScoopDriver(scene), restart.string());
        checkpoint.reset();
        Status("scoopsim: sweep: case %s goes on from %s at t = %.6g s\n", c.name.c_str(),
               restart.c_str(), world.system().time());
      } else {
        world.LoadBed(pass == 1 ? first_bed : paths.Bed(pass - 1).string());
        out = std::make_unique<H5Output>(paths.Pass(pass).string(), scene.yaml_text,
                                         SCOOPSIM_VERSION, scene.output.flush_seconds);
        world.UseOutput(out.get());
        const DigResume resume{pass, status.surface, status.clear_z};
        world.StartDig(MakeScoopDriver(scene), pass > 1 ? &resume : nullptr);
      }
      RunControl control;
      control.quiet = quiet;
      const KillHook kill = KillAfter(c, pass);
      if (kill.signal == SIGKILL) control.stop_after = kill.after;
      const double kill_at = world.system().time() + kill.after;
      control.on_pass_end = [&](int ended) {
        if (ended < passes) SaveBed(paths.Bed(ended).string(), world.system(), scene.yaml_text);
        return false;  // one pass per World
      };
      if (every > 0) {
        control.checkpoint_every = every;
        control.checkpoint_path = paths.Restart(pass).string();
        control.on_checkpoint = [&] {
          status.pass_wall_s = pass_wall();
          status.pass_cpu_s = cpu_before + (CpuSeconds() - cpu0);
          record("running", 0, "pass " + std::to_string(pass));
          if (kill.signal == SIGTERM && kill.after > 0 && world.system().time() >= kill_at &&
              !StopRequested())
            std::raise(SIGTERM);
        };
      }
      const RunResult result = world.Run(control);
      if (result.stopped_after) std::raise(SIGKILL);  // the test hook
      if (result.exit_status != kExitOk || result.stopped_at_pass != pass) {
        out->Close();
        const int exit_status = result.exit_status != kExitOk ? result.exit_status : kExitFailure;
        record(exit_status == kExitStopped ? "stopped" : "failed", exit_status,
               "pass " + std::to_string(pass) + " did not finish");
        outcome.exit_status = exit_status;
        outcome.wall = elapsed();
        return outcome;
      }
      if (pass == 1) {
        const DigResume point = world.ResumePoint();
        status.surface = point.surface;
        status.clear_z = point.clear_z;
      }
      out->SetStateHash(world.system().StateHash());
      out->SetAttribute("time", world.system().time());
      out->SetAttribute("wall_s", pass_wall());
      out->SetAttribute("cpu_s", cpu_before + (CpuSeconds() - cpu0));
      out->Close();
      status.passes_done = pass;
      status.wall_s += pass_wall();
      status.pass_wall_s = status.pass_cpu_s = 0;
      record("running", 0, "");
      fs::remove(paths.Restart(pass));
      // The bed before this pass is no longer needed (the scene's own bed is not ours to remove).
      if (pass > 1 || scene.bed.file.empty()) {
        const fs::path used = pass == 1 ? fs::path(first_bed) : paths.Bed(pass - 1);
        fs::remove(used);
        fs::remove(fs::path(used).replace_extension(".xdmf"));  // its ParaView sidecar
      }
    }

    MergeParts(c, paths, status.bed_cpu_s);
    record("done", 0, "");
    fs::remove_all(paths.parts);
    outcome.wall = elapsed();
    return outcome;
  } catch (const InputError& e) {
    outcome.exit_status = kExitInput;
    Status("scoopsim: sweep: case %s: %s\n", c.name.c_str(), e.what());
    try {
      record("failed", kExitInput, e.what());
    } catch (const std::exception&) {
    }
  } catch (const std::exception& e) {
    outcome.exit_status = kExitFailure;
    Status("scoopsim: sweep: case %s: error: %s\n", c.name.c_str(), e.what());
    try {
      record("failed", kExitFailure, e.what());
    } catch (const std::exception&) {
    }
  }
  outcome.wall = elapsed();
  return outcome;
}

// ---------------------------------------------------------------------------------------------
// Progress

Log::Log(const Sweep& sweep) : sweep_(sweep), t0_(std::chrono::steady_clock::now()) {
  for (const SweepCase& c : sweep.cases) total_ += c.estimate;
}

void Log::Started(const SweepCase& c, int rank, int threads) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string how = threads == 0
                              ? "all cores"
                              : std::to_string(threads) + (threads == 1 ? " thread" : " threads");
  Status("scoopsim: sweep: [%d/%zu] %s started (rank %d, %s)\n", c.index, sweep_.cases.size(),
         c.name.c_str(), rank, how.c_str());
}

void Log::Skipped(const SweepCase& c) {
  std::lock_guard<std::mutex> lock(mutex_);
  skipped_cost_ += c.estimate;
  ++finished_;
  Status("scoopsim: sweep: [%d/%zu] %s skipped (done)\n", c.index, sweep_.cases.size(),
         c.name.c_str());
}

void Log::Held(const SweepCase& c) {
  std::lock_guard<std::mutex> lock(mutex_);
  skipped_cost_ += c.estimate;  // not this run's work: out of its ETA
  Status(
      "scoopsim: sweep: [%d/%zu] %s left to another process (it holds cases/%s.lock); the "
      "process that finishes the last case builds the table\n",
      c.index, sweep_.cases.size(), c.name.c_str(), c.name.c_str());
}

void Log::Finished(const SweepCase& c, int rank, const CaseOutcome& outcome) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (outcome.exit_status == kExitStopped) {
    // Stopped by SIGINT/SIGTERM: not a failure and not finished; its kept state (the bed's
    // pour file, the running pass's restart file) is where the same command goes on.
    Status(
        "scoopsim: sweep: [%d/%zu] %s stopped after %.1f s (rank %d): kept; the same command "
        "goes on from its last keep\n",
        c.index, sweep_.cases.size(), c.name.c_str(), outcome.wall, rank);
    return;
  }
  done_cost_ += c.estimate;
  ++finished_;
  if (outcome.exit_status != kExitOk) ++failed_;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  const double left = total_ - done_cost_ - skipped_cost_;
  char eta[64] = "-";
  if (left > 0 && done_cost_ > 0)
    std::snprintf(eta, sizeof eta, "%.0f s", left * elapsed / done_cost_);
  if (left <= 0) std::snprintf(eta, sizeof eta, "0 s");
  const std::string resumed =
      outcome.first_pass > 1 ? " (resumed at pass " + std::to_string(outcome.first_pass) + ")" : "";
  const std::string failed = failed_ > 0 ? " (" + std::to_string(failed_) + " FAILED)" : "";
  Status("scoopsim: sweep: [%d/%zu] %s %s in %.1f s%s (rank %d); %d of %zu finished%s, ETA %s\n",
         c.index, sweep_.cases.size(), c.name.c_str(),
         outcome.exit_status == kExitOk ? "done" : "FAILED", outcome.wall, resumed.c_str(), rank,
         finished_, sweep_.cases.size(), failed.c_str(), eta);
}

int FinishTable(const Sweep& sweep, const SweepOptions& options) {
  if (!options.build_table && !options.on_complete) return kExitOk;
  for (const SweepCase& c : sweep.cases)
    if (!CaseDone(c, options.dir)) return kExitOk;  // another process's cases are still running
  // Two processes on one folder may both find every case done: one builds at a time.
  const CaseLock lock(fs::path(options.dir) / "table.lock", /*wait=*/true);
  if (options.build_table) {
    const std::string table = (fs::path(options.dir) / "table.h5").string();
    const std::string summary = BuildWrenchTable(options.dir, table);
    Status("scoopsim: sweep: wrote %s (%s)\n", table.c_str(), summary.c_str());
  }
  if (options.on_complete) options.on_complete();
  return kExitOk;
}

}  // namespace sweep

std::string CaseState(const SweepCase& c, const std::string& dir) { return sweep::StateOf(c, dir); }

// ---------------------------------------------------------------------------------------------
// The plain runner

int RunSweep(const Sweep& sweep, const SweepOptions& options) {
  InstallStopHandlers();
  if (options.only_case >= static_cast<int>(sweep.cases.size())) {
    throw InputError("--case: expected a case index in 0.." +
                     std::to_string(sweep.cases.size() - 1) + " (" + sweep.path + " has " +
                     std::to_string(sweep.cases.size()) + " cases), got " +
                     std::to_string(options.only_case));
  }
  // The output folder is writable: else every case would fail alike, one after the other.
  {
    const fs::path cases = fs::path(options.dir) / "cases";
    std::error_code ec;
    fs::create_directories(cases, ec);
    const fs::path probe = cases / (".write_probe_" + std::to_string(::getpid()));
    if (!ec) {
      const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
      if (fd < 0) ec = std::error_code(errno, std::generic_category());
      if (fd >= 0) {
        ::close(fd);
        fs::remove(probe, ec);
      }
    }
    if (ec) {
      throw InputError("-o " + options.dir +
                       ": expected an output folder scoopsim can write, got " + ec.message() +
                       " (" + cases.string() + ")");
    }
  }
  if (options.only_case < 0 && sweep::LaunchedByMpi()) return sweep::RunMpi(sweep, options);
  sweep::Log log(sweep);
  int exit_status = kExitOk;
  for (const SweepCase& c : sweep.cases) {
    if (options.only_case >= 0 && c.index != options.only_case) continue;
    if (StopRequested()) return kExitStopped;
    if (sweep::CaseDone(c, options.dir)) {
      log.Skipped(c);
      continue;
    }
    const int threads = options.threads >= 0 ? options.threads : c.scene.threads;
    log.Started(c, 0, threads);
    const sweep::CaseOutcome outcome = sweep::RunCase(sweep, c, options, threads);
    if (outcome.held) {
      log.Held(c);
    } else if (outcome.skipped) {
      log.Skipped(c);
    } else {
      log.Finished(c, 0, outcome);
    }
    if (outcome.exit_status != kExitOk && exit_status == kExitOk) exit_status = outcome.exit_status;
    if (outcome.exit_status == kExitStopped) return kExitStopped;
  }
  if (exit_status != kExitOk || options.only_case >= 0) return exit_status;
  return sweep::FinishTable(sweep, options);
}

}  // namespace sim

// Internal to sim/ (not a public header: it includes yaml-cpp): how sim reads a YAML input file
// (scene, materials, sweep file). One document per file, each map key once, and every fault an
// InputError at the line it is on.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace sim::yaml_input {

// 1-based line of a node, or 1 for a node without a mark (an empty document).
int LineOf(const YAML::Node& node);

// One-line description of what a node holds, as written, for "got ..." in messages: "-1",
// "[2e-3, 1e-3]", "a map", "nothing".
std::string Describe(const YAML::Node& node);

// Path of a file named in `owner_file`, relative to its folder unless absolute. Not normalised,
// so messages show the user's own spelling.
std::string ResolveAgainst(const std::string& owner_file, const std::string& name);

// The one document of `text` (a null node for an empty text). A syntax error, or a second document
// that holds anything ("---" then more keys, which a plain YAML::Load would drop silently), is an
// InputError naming `file` and the line.
YAML::Node ParseDocument(const std::string& file, const std::string& text);

// Refuses a key written twice in `map` (yaml-cpp keeps both, and a lookup finds only the first):
// an InputError at the second, naming the first's line. `where` is the map's dotted path ("" at the
// top level). Not a map: nothing to check.
void RefuseDuplicateKeys(const std::string& file, const YAML::Node& map, const std::string& where);

// Angles in input files (issue 40): a bare number keeps its key's unit (degrees, or deg/s for a
// rate); a number may carry its unit instead: "90 deg", "1.5708 rad" ("5 deg/s", "0.1 rad/s" for
// a rate). ParseAngleWithUnit reads such a text into degrees (deg/s); false when it is not one.
bool ParseAngleWithUnit(const std::string& text, bool rate, double* degrees);
// The warning rule for a bare number taken as degrees: it looks like radians when it is not an
// integer and |v| <= 2 pi (a radian value from ROS is rarely whole, a degree value in a scene
// nearly always is; writing the unit silences it).
bool LooksLikeRadians(double v);
// Warnings of the input being read on this thread, one line each ("FILE:LINE: KEY: ..."): the one
// route of a scene's warnings (sim::Scene::warnings takes them at the end of its load). Warn adds
// one about `line` of `file`, TakeWarnings returns them and starts over.
void Warn(const std::string& file, int line, const std::string& text);
std::vector<std::string> TakeWarnings();

// Scene keys set from the command line (`--set KEY=VALUE`, repeatable). They travel with the
// scene's text as trailing comment lines `# scoopsim --set KEY=VALUE` (so the text stored in an
// output, a checkpoint or a kept bed holds them, and whatever parses that text again sees the same
// scene); ApplySets writes them into the parsed document before anything is checked. The nodes an
// override makes carry the line kSetLine + i (i: its 0-based index), far past any scene's end, so
// an error about them can be told apart and reworded by NameSet; the other keys keep their lines.
constexpr int kSetLine = 100000;
inline constexpr const char* kSetComment = "# scoopsim --set ";

// `text` with the overrides appended as comment lines (a KEY=VALUE holding a line break is an
// InputError naming --set).
std::string TextWithSets(const std::string& text, const std::vector<std::string>& sets);
// The overrides a text holds, in order.
std::vector<std::string> SetsOf(const std::string& text);
// Writes each override into `root` (a map, or null for an empty document): KEY is a dotted path of
// map keys (or list indices), created when missing; VALUE is parsed as YAML. A malformed KEY=VALUE
// is an InputError naming --set. A null VALUE (~) removes a map's key (a list entry cannot be
// removed).
void ApplySets(YAML::Node* root, const std::vector<std::string>& sets);
// The override a line from ApplySets belongs to ("" for a line of the file itself).
std::string SetAt(int line, const std::vector<std::string>& sets);
// A warning of Warn about `file` reworded to name the override it is about ("--set KEY=VALUE:
// KEY: ...") when its line is one of `sets`'; else `warning`.
std::string WarningNamingSet(const std::string& warning, const std::string& file,
                             const std::vector<std::string>& sets);

}  // namespace sim::yaml_input

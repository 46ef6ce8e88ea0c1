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
// Warnings of the input being read on this thread, one line each ("FILE:LINE: KEY: ..."):
// Warn adds one, TakeWarnings returns them and starts over.
void Warn(const std::string& line);
std::vector<std::string> TakeWarnings();

}  // namespace sim::yaml_input
